//! RL's planning scenarios (tests/data/rlplan, from RL's examples/rlplan) load and solve, and
//! their paths pass the exact check at a resolution ten times finer than the scenario's.

use std::path::PathBuf;
use std::time::Duration;

use rl_plan::problem::rlplan::Scenario;
use rl_plan::solve::path_valid;
use rl_plan::verifier::Verifier;
use rl_plan::{PlanError, plan};

fn scenario(name: &str) -> Scenario {
    let p = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data/rlplan")).join(name);
    Scenario::load(&p).unwrap()
}

fn solve(name: &str, budget: Duration) {
    let sc = scenario(name);
    let (space, mut checker) = sc.build().unwrap();
    let mut opts = sc.options(1);
    opts.time = budget;
    let r = plan(&space, &mut checker, &sc.start, &sc.goal, &opts).unwrap();
    assert!(r.solved, "{name}: not solved in {budget:?}");
    let path = r.optimized.unwrap();
    assert_eq!(path.point(0), &sc.start[..]);
    let fine = Verifier::sequential(sc.verifier.delta / 10.0);
    let (_, mut exact) = sc.build().unwrap();
    assert!(
        path_valid(&space, &mut exact, &path, &fine),
        "{name}: path collides"
    );
}

#[test]
fn scenarios_read_as_rl_reads_them() {
    let sc = scenario("unimation-puma560_boxes_rrtConCon.mdl.xml");
    assert_eq!(sc.planner_element, "rrtConCon");
    assert!(
        (sc.start[1] + std::f64::consts::PI).abs() < 1e-12,
        "degrees → rad"
    );
    assert!((sc.verifier.delta - 1f64.to_radians()).abs() < 1e-15);
    assert_eq!(sc.duration, Duration::from_secs(120));
    assert!(sc.world.is_some());
    let prm = scenario("unimation-puma560_boxes_prm.mdl.xml");
    assert!(matches!(prm.planner, rl_plan::planner::PlannerKind::Prm(_)));
    assert_eq!(prm.verifier.order, rl_plan::verifier::Order::Recursive);
    let maze = scenario("box-6d-300505_maze_rrtConCon.mdl.sixDof.xml");
    assert_eq!(maze.start.len(), 7);
    // The case-insensitive fallback found box-6d-300505.sixDof.xml.
    assert!(maze.kinematics.exists(), "{}", maze.kinematics.display());
    assert_eq!(
        maze.planner.clone().rrt_settings_mut().unwrap().epsilon,
        1e-9
    );
}

#[test]
fn puma_among_boxes_rrt_connect() {
    solve(
        "unimation-puma560_boxes_rrtConCon.mdl.xml",
        Duration::from_secs(20),
    );
}

#[test]
fn puma_among_boxes_prm() {
    solve(
        "unimation-puma560_boxes_prm.mdl.xml",
        Duration::from_secs(20),
    );
}

#[test]
fn box_in_maze_prm() {
    solve(
        "box-6d-300505_maze_prm.mdl.sixDof.xml",
        Duration::from_secs(60),
    );
}

#[test]
fn box_in_maze_rrt_connect() {
    solve(
        "box-6d-300505_maze_rrtConCon.mdl.sixDof.xml",
        Duration::from_secs(60),
    );
}

#[test]
fn bad_scenarios_say_what_and_where() {
    let dir = std::env::temp_dir().join(format!("rlplan-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("bad.xml");
    std::fs::write(&f, "<rlplan>\n  <eet>\n  </eet>\n</rlplan>\n").unwrap();
    match Scenario::load(&f) {
        Err(PlanError::File { element, line, .. }) => {
            assert_eq!(element, "<eet>");
            assert_eq!(line, 2);
        }
        other => panic!("{other:?}"),
    }
    std::fs::write(&f, "<rlplan><rrt><start><q>x</q></start></rrt></rlplan>").unwrap();
    let e = Scenario::load(&f).unwrap_err().to_string();
    assert!(e.contains("not a number") && e.contains("<q>"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}
