//! Cancelling a planning call from another thread (what `rl run --plan` does on Ctrl-C): a
//! search with no path and a long budget ends with `PlanError::Cancelled` soon after the
//! request, for every planner; a request raised before the call ends it at once.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use rl_plan::budget::Cancel;
use rl_plan::optimizer::OptimizerKind;
use rl_plan::planner::{PlannerKind, PrmSettings};
use rl_plan::sampler::SamplerKind;
use rl_plan::solve::plan_cancellable;
use rl_plan::validity::FnValidity;
use rl_plan::verifier::Verifier;
use rl_plan::{JointSpace, PlanError, PlanOptions, Topology, Validity};

/// [0, 10]² split by a wall at x ∈ [4, 6]: no path from x = 1 to x = 9.
fn closed_wall() -> (JointSpace, impl FnMut(&[f64]) -> bool + Clone) {
    let i = Topology::Interval {
        lower: 0.0,
        upper: 10.0,
    };
    let space = JointSpace::new(vec![("x".into(), i), ("y".into(), i)]).unwrap();
    (space, |q: &[f64]| !(4.0..=6.0).contains(&q[0]))
}

fn options(planner: PlannerKind) -> PlanOptions {
    PlanOptions {
        planner,
        sampler: SamplerKind::Uniform,
        verifier: Verifier::recursive(0.05),
        optimizer: OptimizerKind::Simple,
        optimizer_verifier: None,
        seed: 1,
        // Far longer than the test waits: only the cancel request can end the call in time.
        time: Duration::from_secs(120),
        optimize_time: Duration::from_secs(120),
        try_direct: true,
    }
}

#[test]
fn a_cancel_request_ends_planning_with_cancelled() {
    let (space, free) = closed_wall();
    for name in ["rrt-connect", "rrt", "rrt-dual", "prm"] {
        let planner = match name {
            "prm" => PlannerKind::Prm(PrmSettings {
                k: 10,
                ..Default::default()
            }),
            n => PlannerKind::parse(n).unwrap(),
        };
        let flag = Arc::new(AtomicBool::new(false));
        let raised = flag.clone();
        let cancel = Cancel::when(move || raised.load(Ordering::Relaxed));
        let raiser = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(100));
            flag.store(true, Ordering::Relaxed);
            Instant::now()
        });
        let mut check = FnValidity::new(free.clone());
        let r = plan_cancellable(
            &space,
            &mut check,
            &[1.0, 1.0],
            &[9.0, 1.0],
            &options(planner),
            Some(&cancel),
        );
        let ended = Instant::now();
        let raised_at = raiser.join().unwrap();
        assert_eq!(r, Err(PlanError::Cancelled), "{name}");
        assert!(ended >= raised_at, "{name} ended before the request");
        // Well within the 120 s budget (not a speed assertion: the budget is the alternative).
        assert!(
            ended - raised_at < Duration::from_secs(10),
            "{name} went on for {:?} after the request",
            ended - raised_at
        );
    }
}

#[test]
fn a_request_before_the_call_ends_it_at_once() {
    let (space, free) = closed_wall();
    let cancel = Cancel::when(|| true);
    let mut check = FnValidity::new(free);
    let r = plan_cancellable(
        &space,
        &mut check,
        &[1.0, 1.0],
        &[9.0, 1.0],
        &options(PlannerKind::parse("rrt-connect").unwrap()),
        Some(&cancel),
    );
    assert_eq!(r, Err(PlanError::Cancelled));
    assert_eq!(
        check.checks(),
        0,
        "it checked configurations after the request"
    );
}
