//! Bidirectional RRT with *extend* on both sides (RL's `RrtExtExt`): the growing tree extends
//! towards a sample, the other tree extends one step towards the new vertex; the search ends
//! when that step reaches it. The trees swap roles every iteration. Both steps are plain
//! extensions (the settings' dynamic domain is not used). The search is the one in
//! [`super::bidirectional`].

use super::bidirectional::two_tree_planner;

two_tree_planner! {
    /// RL's `RrtExtExt`.
    RrtExtExt, "RRT Extend Extend",
    towards_sample: Extend, towards_tree: Extend,
}
