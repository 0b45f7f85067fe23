//! Path optimisers (RL's `Optimizer`): shorter, smoother paths from a planner's, every new
//! edge checked by the context's verifier, stopping when the budget runs out.
//!
//! - [`SimpleOptimizer`]: shortcutting — drop waypoint `j` when its neighbours `i` and `k` see
//!   each other, until no waypoint can go (RL's `SimpleOptimizer`).
//! - [`AdvancedOptimizer`]: drop only waypoints that are real corners (their distance from the
//!   chord `i–k` is more than `ratio` of the chord), then cut segments longer than `length` in
//!   half and repeat, so corners are cut ever closer (RL's `AdvancedOptimizer`).
//! - [`ShortcutOptimizer`]: greedy shortcutting — from each waypoint, straight to the farthest
//!   one it sees (VAMP's `shortcut_path`).

mod advanced;
mod shortcut;
mod simple;

pub use advanced::AdvancedOptimizer;
pub use shortcut::ShortcutOptimizer;
pub use simple::SimpleOptimizer;

use crate::path::Path;
use crate::planner::Context;

/// Improves paths.
pub trait Optimizer {
    /// Its name.
    fn name(&self) -> &'static str;

    /// Improves `path` in place (end points kept); `true` if it changed.
    fn process(&mut self, ctx: &mut Context, path: &mut Path) -> bool;
}

/// Which optimiser, with its settings.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum OptimizerKind {
    /// None: the planner's path as it is.
    None,
    /// [`SimpleOptimizer`].
    #[default]
    Simple,
    /// [`ShortcutOptimizer`] (VAMP's, 5 passes).
    Shortcut,
    /// [`AdvancedOptimizer`] with `length` and `ratio`.
    Advanced {
        /// Longest segment after subdivision.
        length: f64,
        /// Smallest relative corner that is cut.
        ratio: f64,
    },
}

impl OptimizerKind {
    /// The optimiser (`None` for [`OptimizerKind::None`]).
    pub fn build(&self) -> Option<Box<dyn Optimizer>> {
        match *self {
            Self::None => None,
            Self::Simple => Some(Box::new(SimpleOptimizer)),
            Self::Shortcut => Some(Box::new(ShortcutOptimizer::default())),
            Self::Advanced { length, ratio } => Some(Box::new(AdvancedOptimizer { length, ratio })),
        }
    }

    /// `none`, `simple`, `shortcut`, `advanced` (RL's defaults: length 1, ratio 0.1).
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "none" => Some(Self::None),
            "simple" | "simpleOptimizer" => Some(Self::Simple),
            "shortcut" => Some(Self::Shortcut),
            "advanced" | "advancedOptimizer" => Some(Self::Advanced {
                length: 1.0,
                ratio: 0.1,
            }),
            _ => None,
        }
    }
}
