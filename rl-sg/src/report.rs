//! A robot's collision state in words: which named bodies collide, the closest pairs with their
//! points — what `rl scene check` prints, for tools and logs.

use crate::query::{CollisionFilter, Distance};
use crate::scene::{BodyId, ModelId, Scene};

/// Two named bodies at a signed distance, with the witness points (world frame).
#[derive(Clone, Debug, PartialEq)]
pub struct NamedDistance {
    /// The robot's body (link name).
    pub a: String,
    /// The other body (link name, or obstacle id).
    pub b: String,
    /// Signed distance, m (negative: penetration depth).
    pub distance: f64,
    /// Closest point on `a`.
    pub point_a: [f64; 3],
    /// Closest point on `b`.
    pub point_b: [f64; 3],
}

/// The collision state of one robot model in a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckReport {
    /// Whether any pair checked collides.
    pub colliding: bool,
    /// Colliding body pairs: self-collisions, then the robot against the other models.
    pub collisions: Vec<(String, String)>,
    /// Self-collisions alone.
    pub self_collisions: Vec<(String, String)>,
    /// Environment collisions alone.
    pub environment_collisions: Vec<(String, String)>,
    /// The closest pair over every pair checked.
    pub min_distance: Option<NamedDistance>,
    /// The closest self-collision pair.
    pub self_min_distance: Option<NamedDistance>,
    /// The closest pair between the robot and the other models (`None` without any).
    pub environment_min_distance: Option<NamedDistance>,
    /// Self-collision pairs checked.
    pub self_pairs_checked: usize,
    /// Other models' bodies the robot was checked against.
    pub environment_bodies: usize,
}

/// A body's name for reports: its own (a link name, an obstacle id), or its model's when it has
/// none (RL's `""` bodies).
pub fn body_label(scene: &Scene, id: BodyId) -> String {
    match (scene.models().get(id.model), scene.body(id)) {
        (_, Some(b)) if !b.name().is_empty() => b.name().to_string(),
        (Some(m), _) => m.name().to_string(),
        _ => format!("{}/{}", id.model, id.body),
    }
}

fn named(scene: &Scene, d: &Distance, robot: ModelId) -> NamedDistance {
    // The robot's body first.
    let d = if d.a.model != robot.0 && d.b.model == robot.0 {
        d.swapped()
    } else {
        *d
    };
    NamedDistance {
        a: body_label(scene, d.a.body_id()),
        b: body_label(scene, d.b.body_id()),
        distance: d.distance,
        point_a: d.point_a.to_array(),
        point_b: d.point_b.to_array(),
    }
}

/// Checks `robot` against itself (its self-collision pairs) and against every other model.
pub fn check(scene: &Scene, robot: ModelId) -> CheckReport {
    let names = |pairs: Vec<(BodyId, BodyId)>| -> Vec<(String, String)> {
        pairs
            .into_iter()
            .map(|(a, b)| {
                let (a, b) = if a.model != robot.0 && b.model == robot.0 {
                    (b, a)
                } else {
                    (a, b)
                };
                (body_label(scene, a), body_label(scene, b))
            })
            .collect()
    };
    let own = CollisionFilter::SelfCollision(robot);
    let env = CollisionFilter::Against(robot);
    let self_collisions = names(scene.colliding_bodies(&own));
    let environment_collisions = names(scene.colliding_bodies(&env));
    let self_d = scene.min_distance(&own);
    let env_d = scene.min_distance(&env);
    let min = match (self_d, env_d) {
        (Some(a), Some(b)) => Some(if b.distance < a.distance { b } else { a }),
        (a, b) => a.or(b),
    };
    let environment_bodies = scene
        .models()
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != robot.0)
        .map(|(_, m)| m.bodies().iter().filter(|b| !b.shapes().is_empty()).count())
        .sum();
    CheckReport {
        colliding: !self_collisions.is_empty() || !environment_collisions.is_empty(),
        collisions: self_collisions
            .iter()
            .chain(&environment_collisions)
            .cloned()
            .collect(),
        self_pairs_checked: scene
            .model(robot)
            .map_or(0, |m| m.self_collision_pairs().len()),
        self_collisions,
        environment_collisions,
        min_distance: min.map(|d| named(scene, &d, robot)),
        self_min_distance: self_d.map(|d| named(scene, &d, robot)),
        environment_min_distance: env_d.map(|d| named(scene, &d, robot)),
        environment_bodies,
    }
}
