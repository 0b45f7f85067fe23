//! Bare-metal canary for rl-core: a `#![no_std]`, `#![no_main]` program with its own panic
//! handler and **no global allocator** that runs forward kinematics, RNEA, ABA and a trajectory
//! evaluation on a 6-axis arm whose parameters are compile-time constants.
//!
//! It exists to break the build: if `alloc` or `std` creeps into rl-core's default (no-feature)
//! build, linking this binary for `thumbv7em-none-eabihf` fails (no `std` for that target, and
//! no `#[global_allocator]` here for `alloc` to use). Build with `scripts/cross --canary` or
//!
//! ```sh
//! cargo build --release --target thumbv7em-none-eabihf \
//!     --manifest-path targets/nostd-canary/Cargo.toml
//! ```
//!
//! It is linked, not run: there is no vector table or memory map for a particular chip. The
//! entry point `_start` runs [`control_step`] forever and reads every result through
//! `black_box`, so nothing is optimised away and the code size reported by
//! `scripts/cross` is the size of the real algorithms.
#![no_std]
#![no_main]

use core::hint::black_box;
use core::panic::PanicInfo;

use rl_core::Data;
use rl_core::traj::{Polynomial, Trajectory};
use rl_nostd_canary::{DOF, Outputs, Q_GOAL, Q_START, TRAJ_LIMITS, build_arm, control_step};

/// The entry point a bare-metal start-up would jump to: builds the arm and the trajectory, then
/// runs control steps forever.
#[unsafe(no_mangle)]
pub extern "C" fn _start() -> ! {
    let mut out = Outputs {
        flange: [0.0; 3],
        tau: [0.0; DOF],
        qdd: [0.0; DOF],
        error: 0,
    };
    // black_box: the inputs are "unknown" to the optimiser, so nothing is folded at compile
    // time and every algorithm is really linked.
    let model = match build_arm() {
        Some(m) => m,
        None => {
            out.error = 1;
            loop {
                black_box(&out);
            }
        }
    };
    let model = black_box(model);
    let traj =
        match Polynomial::quintic_at_rest(black_box(Q_START), black_box(Q_GOAL), &TRAJ_LIMITS) {
            Ok(p) => p,
            Err(_) => {
                out.error = 2;
                loop {
                    black_box(&out);
                }
            }
        };
    let mut data = Data::<DOF>::new();
    let dt = 1e-3;
    let mut t = 0.0;
    loop {
        out = match control_step(&model, &mut data, &traj, black_box(t)) {
            Ok(o) => o,
            Err(_) => Outputs { error: 3, ..out },
        };
        // Read every result, so none of the computation is dead.
        black_box((out.flange, out.tau, out.qdd, out.error));
        t = if t < traj.duration() { t + dt } else { 0.0 };
    }
}

/// Bare metal has nowhere to report a panic: stop here (a debugger shows this frame).
#[panic_handler]
fn panic(_info: &PanicInfo) -> ! {
    loop {
        core::hint::spin_loop();
    }
}
