//! rl-rs's side of scripts/bench-task-space: times one whole cycle of the task-space law —
//! forward kinematics, the capsules to the world, their proximities to the obstacle spheres
//! (rl-sg `CapsuleModel::proximities`), `TaskData::set_proximities` and rl-core's
//! `operational_impedance` with `Priority::OrientationFirst` and a `Repulsion` — over the states
//! of problem.json (gen_problem.py), as task_bench.cpp times the same law on Pinocchio: per
//! round enough repetitions over all states for ~2 ms, the median of `--rounds` rounds, in ns
//! per cycle. Prints one JSON line; writes every state's torques to `--torques`. Counts the
//! heap allocations made inside the timed cycles (a counting global allocator).
//!
//! Usage: rl-task-bench PROBLEM_JSON [--rounds N] [--torques OUT.json]

use std::alloc::{GlobalAlloc, Layout, System};
use std::hint::black_box;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use glam::{DMat3, DVec3};
use rl_core::loader::{LoadOptions, UrdfOptions, load_file_options};
use rl_core::spatial::PlueckerTransform;
use rl_core::task::{
    ImpedanceGains, MAX_PROXIMITIES, Orientation, Priority, Proximity, Repulsion, Singularity,
    TaskData, TaskTarget, operational_impedance,
};
use rl_core::{Data, Model};
use rl_sg::capsule::{Capsule, CapsuleModel, LinkCapsule};
use serde_json::Value;

/// The capacities the controller uses (src/controller: `LoadedModel<16>`, `MAX_ARM_CAPSULES`).
const N: usize = 16;
const CAPSULES: usize = 64;

struct Counting;
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: the caller's contract is System's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as above.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: as above.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn die(msg: impl std::fmt::Display) -> ! {
    eprintln!("rl-task-bench: {msg}");
    std::process::exit(1)
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| die(format!("not a number: {v}")))
}

fn vec_of(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| die(format!("not an array: {v}")))
        .iter()
        .map(f)
        .collect()
}

fn v3(v: &Value) -> DVec3 {
    let x = vec_of(v);
    DVec3::new(x[0], x[1], x[2])
}

/// Everything one cycle touches, preallocated.
struct Cycle<'a> {
    model: &'a Model<N>,
    data: Data<N>,
    task: Box<TaskData<N>>,
    caps: CapsuleModel<CAPSULES>,
    obstacles: &'a [Capsule],
    out: [Proximity; MAX_PROXIMITIES],
    contacts: usize,
    within: f64,
    tool: usize,
    gains: ImpedanceGains,
    target: TaskTarget,
    posture: [f64; N],
    seen: usize,
    /// States whose operational inertia was bounded (a clamp acted).
    bounded: usize,
}

impl Cycle<'_> {
    /// The distance part alone, for the breakdown: forward kinematics, the capsules to the
    /// world, their proximities.
    #[inline(never)]
    fn distances_only(&mut self, q: &[f64]) -> usize {
        rl_core::algo::forward_position(self.model, &mut self.data, q)
            .unwrap_or_else(|e| die(e));
        self.caps.update(&self.data);
        self.caps.proximities(
            self.obstacles,
            &[],
            self.within,
            &mut self.out[..self.contacts],
        )
    }

    #[inline(never)]
    fn run(&mut self, q: &[f64], qd: &[f64], tau: &mut [f64]) {
        let n = self.model.dof();
        rl_core::algo::forward_position(self.model, &mut self.data, q)
            .unwrap_or_else(|e| die(e));
        self.caps.update(&self.data);
        let k = self.caps.proximities(
            self.obstacles,
            &[],
            self.within,
            &mut self.out[..self.contacts],
        );
        self.seen += k;
        self.task
            .set_proximities(&self.out[..k])
            .unwrap_or_else(|e| die(e));
        let report = operational_impedance(
            self.model,
            &mut self.data,
            &mut self.task,
            self.tool,
            &self.gains,
            &self.target,
            q,
            qd,
            &self.posture[..n],
            tau,
        )
        .unwrap_or_else(|e| die(e));
        self.bounded += usize::from(report.bounded_directions > 0);
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 2 {
        die("usage: rl-task-bench PROBLEM_JSON [--rounds N] [--torques OUT.json]");
    }
    let mut rounds = 15usize;
    let mut torques_path = None;
    let mut i = 2;
    while i < args.len() {
        match (args[i].as_str(), args.get(i + 1)) {
            ("--rounds", Some(n)) => rounds = n.parse().unwrap_or_else(|_| die("bad --rounds")),
            ("--torques", Some(p)) => torques_path = Some(p.clone()),
            _ => die(format!("unknown argument {}", args[i])),
        }
        i += 2;
    }
    if cfg!(debug_assertions) {
        die("a debug build: refusing to time");
    }
    let text = std::fs::read_to_string(&args[1]).unwrap_or_else(|e| die(e));
    let p: Value = serde_json::from_str(&text).unwrap_or_else(|e| die(e));
    if p["format"] != "rl-rs task-space bench problem 1" {
        die("not a task-space bench problem");
    }

    // The model, with the tool as an extra tool (its fixed links merged into panda_link7).
    let tool_name = p["tool"].as_str().unwrap_or_else(|| die("no tool"));
    let options = LoadOptions::urdf(&UrdfOptions {
        extra_tools: vec![tool_name.to_string()],
        ..UrdfOptions::default()
    });
    let urdf = p["urdf"].as_str().unwrap_or_else(|| die("no urdf"));
    let loaded = load_file_options::<N>(urdf, &options).unwrap_or_else(|e| die(e));
    let mut model = loaded.model;
    model.set_gravity(v3(&p["gravity"]));
    let tool = model
        .tool_index(tool_name)
        .unwrap_or_else(|| die(format!("no tool {tool_name}")));
    let n = model.dof();
    let joints: Vec<&str> = p["joints"]
        .as_array()
        .unwrap_or_else(|| die("no joints"))
        .iter()
        .map(|j| j.as_str().unwrap_or(""))
        .collect();
    let ours: Vec<&str> = (0..model.body_count()).map(|b| model.joint_name(b)).collect();
    if ours != joints || n != joints.len() {
        die(format!("joint order differs: {ours:?} vs {joints:?}"));
    }

    // Gains.
    let g = &p["gains"];
    let r = &g["repulsion"];
    let stiffness: [f64; 6] = vec_of(&g["stiffness"])
        .try_into()
        .unwrap_or_else(|_| die("stiffness: 6 numbers"));
    let clamp = vec_of(&g["clamp"]);
    if g["priority"] != "orientation_first" {
        die("only the orientation-first priority is benchmarked");
    }
    let gains = ImpedanceGains {
        stiffness,
        damping_ratio: f(&g["damping_ratio"]),
        orientation: Orientation::Held,
        max_position_error: f(&g["max_position_error"]),
        max_orientation_error: f(&g["max_orientation_error"]),
        posture_stiffness: f(&g["posture_stiffness"]),
        posture_damping_ratio: f(&g["posture_damping_ratio"]),
        limit_band: f(&g["limit_band"]),
        limit_stiffness: f(&g["limit_stiffness"]),
        singularity: Singularity::Clamped([clamp[0], clamp[1]]),
        gravity_by_device: false,
        priority: Priority::OrientationFirst,
        repulsion: Repulsion {
            influence: f(&r["influence"]),
            margin: f(&r["margin"]),
            stiffness: f(&r["gain"]),
            damping: f(&r["damping"]),
            max_acceleration: f(&r["max_acceleration"]),
        },
        // The model has no joint friction: nothing to compensate (Pinocchio's side has none).
        friction_smoothing: 0.05,
    };
    gains.check().unwrap_or_else(|e| die(e));
    let contacts = r["max_contacts"].as_u64().unwrap_or_else(|| die("max_contacts")) as usize;
    if contacts > MAX_PROXIMITIES {
        die(format!("max_contacts > {MAX_PROXIMITIES}"));
    }

    // Target (rotation row-major in the file) and posture.
    let rot = vec_of(&p["target"]["rotation"]);
    let rotation = DMat3::from_cols_array(&rot.try_into().unwrap_or_else(|_| die("rotation")))
        .transpose();
    let target = TaskTarget::at(PlueckerTransform::new(
        rotation,
        v3(&p["target"]["translation"]),
    ));
    let mut posture = [0.0; N];
    posture[..n].copy_from_slice(&vec_of(&p["posture"]));

    // Capsules (in their joint's frame = the rl-core body's) and obstacles.
    let mut caps = CapsuleModel::<CAPSULES>::new();
    for (i, c) in p["capsules"].as_array().unwrap_or_else(|| die("capsules")).iter().enumerate() {
        let joint = c["joint"].as_str().unwrap_or("");
        let body = (0..model.body_count())
            .find(|&b| model.joint_name(b) == joint)
            .unwrap_or_else(|| die(format!("no joint {joint}")));
        caps.push(LinkCapsule::new(
            body,
            i as u16,
            Capsule::new(v3(&c["a"]), v3(&c["b"]), f(&c["radius"])),
        ))
        .unwrap_or_else(|e| die(e));
    }
    let obstacles: Vec<Capsule> = p["obstacles"]
        .as_array()
        .unwrap_or_else(|| die("obstacles"))
        .iter()
        .map(|o| Capsule::sphere(v3(&o["center"]), f(&o["radius"])))
        .collect();
    let states: Vec<(Vec<f64>, Vec<f64>)> = p["states"]
        .as_array()
        .unwrap_or_else(|| die("states"))
        .iter()
        .map(|s| (vec_of(&s["q"]), vec_of(&s["qd"])))
        .collect();

    let mut cycle = Cycle {
        model: &model,
        data: Data::new(),
        task: Box::new(TaskData::new()),
        caps,
        obstacles: &obstacles,
        out: [Proximity::at_rest(0, DVec3::ZERO, DVec3::X, f64::INFINITY); MAX_PROXIMITIES],
        contacts,
        within: gains.repulsion.influence,
        tool,
        gains,
        target,
        posture,
        seen: 0,
        bounded: 0,
    };

    // The torques, once per state.
    let mut taus = vec![vec![0.0; n]; states.len()];
    for ((q, qd), tau) in states.iter().zip(&mut taus) {
        cycle.run(q, qd, tau);
    }
    let contacts_mean = cycle.seen as f64 / states.len() as f64;
    let bounded_states = cycle.bounded;

    // Timing: as task_bench.cpp's time_per_cycle.
    let mut tau = [0.0; N];
    let mut pass = |cycle: &mut Cycle| {
        for (q, qd) in &states {
            cycle.run(black_box(q), black_box(qd), &mut tau[..n]);
            black_box(&tau);
        }
    };
    let start = Instant::now();
    pass(&mut cycle);
    let once = start.elapsed().as_secs_f64().max(1e-9);
    let reps = ((2e-3 / once).ceil() as usize).clamp(1, 10000);
    let mut samples = Vec::with_capacity(rounds);
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    for _ in 0..rounds {
        let t = Instant::now();
        for _ in 0..reps {
            pass(&mut cycle);
        }
        samples.push(t.elapsed().as_secs_f64() * 1e9 / (reps * states.len()) as f64);
    }
    let allocations = ALLOCATIONS.load(Ordering::Relaxed) - before;
    // (samples was preallocated: pushes inside the loop do not allocate.)
    samples.sort_by(f64::total_cmp);
    let ns = samples[samples.len() / 2];
    let cycles = rounds * reps * states.len();

    // The distance part alone (same method).
    let mut dist_samples = Vec::with_capacity(rounds);
    for _ in 0..rounds {
        let t = Instant::now();
        for _ in 0..reps {
            for (q, _) in &states {
                black_box(cycle.distances_only(black_box(q)));
            }
        }
        dist_samples.push(t.elapsed().as_secs_f64() * 1e9 / (reps * states.len()) as f64);
    }
    dist_samples.sort_by(f64::total_cmp);
    let ns_distances = dist_samples[dist_samples.len() / 2];

    if let Some(path) = torques_path {
        let json = serde_json::json!({ "tau": taus });
        std::fs::write(&path, json.to_string()).unwrap_or_else(|e| die(e));
    }
    println!(
        "{}",
        serde_json::json!({
            "library": "rl-rs",
            "states": states.len(),
            "rounds": rounds,
            "ns": ns,
            "ns_distances": ns_distances,
            "contacts_mean": contacts_mean,
            "bounded_states": bounded_states,
            "allocations": allocations,
            "timed_cycles": cycles,
        })
    );
}
