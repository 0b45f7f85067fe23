//! The Scene JSON of the protocol (`/api/scene`, and inside `hello`): models with their joints,
//! tool, placement and drawn geometry, the obstacles, the path to play back (with where its
//! times came from) and a plan's start and goal ghosts and tool trail.

use rl_core::spatial::PlueckerTransform;
use rl_sg::{Geometry, Shape};
use serde_json::{Value, json};

use crate::files::FileTable;
use crate::load::World;
use crate::path::{Timing, UNKNOWN_SPEED};

/// Protocol version in the Scene JSON.
pub const VERSION: u32 = 1;

/// `[x, y, z, qx, qy, qz, qw]` of a pose.
pub fn pose7(x: &PlueckerTransform) -> [f64; 7] {
    let q = x.quaternion();
    [
        x.translation.x,
        x.translation.y,
        x.translation.z,
        q.x,
        q.y,
        q.z,
        q.w,
    ]
}

fn finite_or_null(x: f64) -> Value {
    if x.is_finite() { json!(x) } else { Value::Null }
}

fn shape_json(s: &Shape, files: &FileTable, model: Option<usize>) -> Value {
    let mut v = match s.geometry() {
        Geometry::Box { size } => json!({"kind": "box", "size": size.to_array()}),
        Geometry::Sphere { radius } => json!({"kind": "sphere", "radius": radius}),
        Geometry::Cylinder { radius, length } => {
            json!({"kind": "cylinder", "radius": radius, "length": length})
        }
        Geometry::Capsule { radius, length } => {
            json!({"kind": "capsule", "radius": radius, "length": length})
        }
        Geometry::Cone { radius, length } => {
            json!({"kind": "cone", "radius": radius, "length": length})
        }
        Geometry::HalfSpace { normal, offset } => {
            json!({"kind": "plane", "normal": normal.to_array(), "offset": offset})
        }
        Geometry::Mesh(m) | Geometry::Convex(m) => {
            let url = match (model, s.source()) {
                (Some(i), Some(p)) => files.url_of(i, p),
                _ => None,
            };
            match (url, s.source()) {
                (Some(url), Some(p)) => {
                    let ext = p
                        .extension()
                        .and_then(|e| e.to_str())
                        .unwrap_or("")
                        .to_ascii_lowercase();
                    json!({"kind": "mesh", "url": url, "format": ext,
                           "scale": s.source_scale().to_array()})
                }
                // Meshes with no file (VRML faces, MoveIt meshes): the triangles inline.
                _ => json!({
                    "kind": "mesh",
                    "vertices": m.vertices().iter().map(|v| v.to_array()).collect::<Vec<_>>(),
                    "triangles": m.triangles(),
                    "scale": [1.0, 1.0, 1.0],
                }),
            }
        }
    };
    v["pose"] = json!(pose7(s.local_pose()));
    v
}

/// The Scene JSON of `world`.
pub fn scene_json(world: &World) -> Value {
    let models: Vec<Value> = world
        .robots
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let collision = &world.scene.models()[i];
            let bodies: Vec<Value> = collision
                .bodies()
                .iter()
                .map(|b| {
                    let shapes: Vec<Value> = r
                        .visual
                        .body_index(b.name())
                        .and_then(|k| r.visual.bodies().get(k))
                        .map(|vb| {
                            vb.shapes()
                                .iter()
                                .map(|s| shape_json(s, &world.files, Some(i)))
                                .collect()
                        })
                        .unwrap_or_default();
                    json!({"name": b.name(), "shapes": shapes})
                })
                .collect();
            let joints: Vec<Value> = r
                .joints
                .iter()
                .map(|j| {
                    json!({"name": j.name, "kind": j.kind, "min": finite_or_null(j.min),
                           "max": finite_or_null(j.max), "unit": j.unit,
                           "max_speed": finite_or_null(j.max_speed)})
                })
                .collect();
            let tool = r
                .kinematics
                .model
                .tools()
                .get(r.tool)
                .map(|t| t.name.as_str().to_string());
            // The body the tool is attached to, as the page names bodies.
            let tool_body = r
                .kinematics
                .model
                .tools()
                .get(r.tool)
                .and_then(|t| collision.kinematics().map(|k| (t.body, k)))
                .and_then(|(kb, link)| {
                    (0..collision.bodies().len())
                        .find(|&i| link.frame(i).is_some_and(|(b, _)| b == kb))
                        .map(|i| collision.bodies()[i].name().to_string())
                });
            json!({
                "index": i,
                "name": r.name,
                "urdf": r.urdf,
                "joints": joints,
                "tool": tool,
                "tool_body": tool_body,
                "initial_q": r.initial_q,
                "initial_source": r.initial_source,
                "base": pose7(&r.base),
                "bodies": bodies,
                "warnings": r.warnings,
            })
        })
        .collect();
    let env: Vec<Value> = world
        .scene
        .models()
        .iter()
        .enumerate()
        .skip(world.robots.len())
        .flat_map(|(mi, m)| {
            m.bodies()
                .iter()
                .enumerate()
                .map(move |(bi, b)| (mi, bi, b))
        })
        .map(|(mi, bi, b)| {
            let name = rl_sg::report::body_label(
                &world.scene,
                rl_sg::BodyId {
                    model: mi,
                    body: bi,
                },
            );
            let shapes: Vec<Value> = b
                .shapes()
                .iter()
                .map(|s| shape_json(s, &world.files, None))
                .collect();
            json!({"name": name, "model": world.scene.models()[mi].name(),
                   "pose": pose7(b.pose()), "shapes": shapes})
        })
        .collect();
    let path = world.path.as_ref().map(|p| {
        let timing = match &p.timing {
            Timing::File => json!({"from": "file"}),
            Timing::SpeedLimits { assumed } => json!({
                "from": "speed_limits", "assumed_speed": UNKNOWN_SPEED, "assumed_for": assumed,
            }),
        };
        json!({"model": 0, "t": p.t, "q": p.q, "timing": timing})
    });
    let plan = world.plan.as_ref().map(|v| {
        let poses = |b: &[PlueckerTransform]| b.iter().map(pose7).collect::<Vec<_>>();
        json!({
            "model": v.model,
            "start": {"q": v.start, "bodies": poses(&v.start_bodies)},
            "goal": {"q": v.goal, "bodies": poses(&v.goal_bodies)},
            "trail": v.trail.iter().map(|p| p.to_array()).collect::<Vec<_>>(),
        })
    });
    json!({
        "version": VERSION,
        "models": models,
        "env": {"bodies": env},
        "path": path,
        "plan": plan,
    })
}
