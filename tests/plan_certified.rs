//! A planned motion is handed to the controller only if it is certified collision-free on the
//! exact geometry: here a checker that lets the planner through an obstacle (it checks only the
//! joint limits) while its exact geometry has the obstacle, so every path the planner returns
//! runs through it. `plan_motion` refuses after trying `CERTIFY_ATTEMPTS` seeds, and says why.

#![cfg(feature = "plan")]

use std::path::PathBuf;

use rl::controller::planned::{CERTIFY_ATTEMPTS, PlannedMotionError, plan_motion};
use rl_plan::problem::{Robot, mbm};
use rl_plan::scene::SceneValidity;
use rl_plan::{JointSpace, PlanOptions, Validity};

fn data() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mbm/panda"))
}

/// Valid wherever the joint limits allow; the exact geometry is a real scene's.
struct Blind {
    space: JointSpace,
    exact: SceneValidity,
    checks: u64,
}

impl Validity for Blind {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.checks += 1;
        self.space.contains(q)
    }
    fn checks(&self) -> u64 {
        self.checks
    }
    fn free_checks(&self) -> u64 {
        self.checks
    }
    fn exact_checker(&mut self) -> Option<&mut SceneValidity> {
        Some(&mut self.exact)
    }
}

#[test]
fn a_path_through_an_obstacle_is_refused_however_it_was_found() {
    let robot = Robot::load_urdf(&data().join("panda.urdf"), None, None).unwrap();
    let problems = mbm::find_problems(&data().join("problems")).unwrap();
    // A problem whose straight start–goal motion hits the scene (the blind planner's path).
    let mut found = None;
    for p in &problems {
        let (env, start, goal) = p.load(&robot).unwrap();
        let mut exact = robot.exact_checker(env).unwrap();
        let cert = exact
            .certify_edge(&start, &goal, &Default::default())
            .unwrap();
        if cert.is_err() {
            found = Some((p.name.clone(), exact, start, goal));
            break;
        }
    }
    let (name, exact, start, goal) = found.expect("a problem whose straight motion collides");
    let loaded = rl::core::loader::load_file::<16>(data().join("panda.urdf")).unwrap();
    let mut blind = Blind {
        space: robot.space.clone(),
        exact,
        checks: 0,
    };
    let e = plan_motion::<16, 16>(
        &loaded.model,
        &robot.space,
        &mut blind,
        &start,
        &goal,
        &PlanOptions::default(),
        0.5,
        None,
    )
    .map(|_| ())
    .unwrap_err();
    println!("{name}: {e}");
    match &e {
        PlannedMotionError::Uncertified { attempts } => {
            assert_eq!(attempts.len() as u64, CERTIFY_ATTEMPTS);
            let seeds: Vec<u64> = attempts.iter().map(|(s, _)| *s).collect();
            assert_eq!(seeds, (0..CERTIFY_ATTEMPTS).collect::<Vec<_>>());
            assert!(attempts.iter().all(|(_, why)| why.contains("come within")));
        }
        other => panic!("{other:?}"),
    }
    assert!(
        e.to_string().contains("could be certified collision-free"),
        "{e}"
    );
}
