//! The controller's own pins in the loop: an [`rl_drivers::safety`] chain (e-stop, enable,
//! brake or contactor, watchdog) that a run arms before the device starts and checks every
//! cycle.
//!
//! A [`SafetyHandle`] in [`RunOptions::safety`](super::RunOptions::safety) hands the chain to
//! the run, which:
//!
//! - arms it before the device is switched on ([`SafetyIo::arm`]): the chain must read closed
//!   (and the enable held) for its debounce time, or the run is refused
//!   ([`RunError::Safety`](super::RunError::Safety)) and nothing moves;
//! - checks it every cycle on the real-time thread, before the law runs (one virtual call, no
//!   allocation, no lock): the watchdog output toggles, and a stop it finds becomes the run's
//!   fault [`Fault::Safety`](super::Fault::Safety) — in stop category 0 the run ends at once and
//!   the device is stopped, in category 1 the law brings the arm to rest first (its braking
//!   bound applies) and the device is stopped then;
//! - after the device is stopped, tells the chain the drives are off (a category-1 brake output
//!   drops), holds the watchdog steady, gives the chain back to the handle and reports what it
//!   counted ([`SafetyReport`]).
//!
//! On Linux the pins are GPIO lines ([`gpio`], feature `gpio`, on with the `rl` tool: `rl run
//! --estop gpiochip0:17 --watchdog gpiochip0:27 …`).
//!
//! A stop latches in the chain: releasing the e-stop never restarts motion, and a new run
//! starts only after the chain has read closed again (its reset, inside the next run's arming).

#[cfg(feature = "gpio")]
pub mod gpio;

use std::sync::{Arc, Mutex, PoisonError};

use rl_drivers::safety::{ChainState, SafetyCounters, SafetyIo, StopCategory};

/// A safety chain a run checks every cycle, whatever its pins.
pub type SafetyBox = Box<dyn SafetyIo + Send>;

/// Hands a safety chain to a run and takes it back after it: clone it freely; the chain goes
/// to one run at a time.
#[derive(Clone)]
pub struct SafetyHandle {
    slot: Arc<Mutex<Option<SafetyBox>>>,
}

impl core::fmt::Debug for SafetyHandle {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let chain = self.slot.lock().unwrap_or_else(PoisonError::into_inner);
        f.debug_struct("SafetyHandle")
            .field("state", &chain.as_ref().map(|c| c.state()))
            .finish()
    }
}

impl SafetyHandle {
    /// A handle holding `chain` (e.g. an [`rl_drivers::safety::SafetyChain`] over GPIO lines).
    pub fn new(chain: impl SafetyIo + Send + 'static) -> Self {
        Self {
            slot: Arc::new(Mutex::new(Some(Box::new(chain)))),
        }
    }

    /// Takes the chain for a run (`None` while another run has it).
    pub fn take(&self) -> Option<SafetyBox> {
        self.slot
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take()
    }

    /// Gives the chain back after a run.
    pub fn put_back(&self, chain: SafetyBox) {
        *self.slot.lock().unwrap_or_else(PoisonError::into_inner) = Some(chain);
    }

    /// Calls `f` with the chain while no run has it (e.g. to read its pins' state).
    pub fn with<T>(&self, f: impl FnOnce(&mut dyn SafetyIo) -> T) -> Option<T> {
        let mut slot = self.slot.lock().unwrap_or_else(PoisonError::into_inner);
        slot.as_mut().map(|c| f(c.as_mut()))
    }
}

/// What the safety chain saw over a run, for the report.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SafetyReport {
    /// Its state after the run (latched after a stop).
    pub state: ChainState,
    /// How it stops.
    pub category: StopCategory,
    /// Cycles checked, stops, pin errors.
    pub counters: SafetyCounters,
    /// Whether the brake or contactor output was still energised after the run (it must not
    /// be).
    pub brake_energised: bool,
}

impl SafetyReport {
    /// The chain's state and counts after a run.
    pub fn of(chain: &dyn SafetyIo) -> Self {
        Self {
            state: chain.state(),
            category: chain.category(),
            counters: chain.counters(),
            brake_energised: chain.brake_energised(),
        }
    }

    /// One line for the report.
    pub fn line(&self) -> String {
        let c = &self.counters;
        format!(
            "safety chain: {} cycles checked, {} stop{}, {} read and {} write errors; after the \
             run {:?}, brake output {}, stop category {}",
            c.cycles,
            c.stops,
            if c.stops == 1 { "" } else { "s" },
            c.read_errors,
            c.write_errors,
            self.state,
            if self.brake_energised {
                "ENERGISED"
            } else {
                "dropped"
            },
            match self.category {
                StopCategory::Zero => 0,
                StopCategory::One => 1,
            }
        )
    }

    /// The JSON object of the report's `safety` key.
    pub fn to_json(&self) -> serde_json::Value {
        let c = &self.counters;
        serde_json::json!({
            "state": format!("{:?}", self.state),
            "stop_category": match self.category {
                StopCategory::Zero => 0,
                StopCategory::One => 1,
            },
            "cycles": c.cycles,
            "stops": c.stops,
            "read_errors": c.read_errors,
            "write_errors": c.write_errors,
            "brake_energised": self.brake_energised,
        })
    }
}
