//! RL's scene files: `<rlsg>` (or `<rl><sg>`) XML naming models and bodies in a VRML97 scene.
//!
//! ```xml
//! <rlsg>
//!   <scene href="unimation-puma560_boxes.wrl">
//!     <model name="unimation-puma560"> <body name="link0"/> … </model>
//!     <model name="boxes"> <body name=""/> </model>
//!   </scene>
//! </rlsg>
//! ```
//!
//! As RL reads them: the first `<scene>` only; each model is the first VRML node `DEF`'d with
//! its name (searched depth first through `Inline`s; the empty name is the first unnamed node);
//! each body the first node with its name below the model's; the body's frame is the product
//! of the transforms from the scene root to the body's node (it must be rigid); its shapes are
//! every `Shape` below that node, posed relative to it. A model or body the VRML lacks is
//! skipped by RL silently; here it is an error that names it.
//!
//! [`link_rlmdl`] links such a robot model to RL's kinematic model (`rlmdl`), body by body in
//! order, and applies the model's `<ignore>` elements: `<ignore/>` takes a body out of checks
//! against other models (a base on the floor), `<ignore idref>` allows a pair. [`link_rlkin`]
//! does the same for RL's older Denavit–Hartenberg format (`rlkin`), whose `<link>` elements
//! carry the `<ignore>`s: as RL's `rl::plan::Model` pairs `rl::kin` links with scene bodies,
//! the scene's bodies go to the links in the order RL's depth-first walk from the world reaches
//! them (file order for a serial chain). [`link_kinematics`] picks one by the loaded format.

use std::path::Path;

use rl_core::loader::{Format, LoadedModel};
use roxmltree::Node;

use super::vrml::{VrmlScene, rigid};
use super::xml::{at, attr, child, children, parse};
use super::{SceneLimits, dir_of, read_text, read_text_within};
use crate::error::{SgError, SgErrorKind};
use crate::scene::{KinematicLink, Model, Scene, Shape};

/// Reads the rlsg XML in `text` (the file `path`, for the VRML's relative `href`).
pub fn scene_from_str(text: &str, path: &Path) -> Result<Scene, SgError> {
    scene_from_str_with(text, path, &SceneLimits::DEFAULT)
}

/// [`scene_from_str`] within `limits` (for the VRML and everything it inlines and expands
/// into).
pub fn scene_from_str_with(
    text: &str,
    path: &Path,
    limits: &SceneLimits,
) -> Result<Scene, SgError> {
    let doc = parse(text)?;
    let root = doc.root_element();
    let holder = match root.tag_name().name() {
        "rlsg" => root,
        "rl" => child(root, "sg").ok_or_else(|| at(root, SgError::missing("<sg>")))?,
        other => {
            return Err(at(
                root,
                SgError::new(SgErrorKind::UnsupportedFormat {
                    format: format!("<{other}>: not an RL scene (<rlsg> or <rl><sg>)"),
                }),
            ));
        }
    };
    let scene_node =
        child(holder, "scene").ok_or_else(|| at(holder, SgError::missing("<scene>")))?;
    let href = attr(scene_node, "href")?;
    let wrl = dir_of(path).join(href);
    let vrml =
        VrmlScene::load_with(&wrl, limits).map_err(|e| at(scene_node, SgError::nested(e)))?;
    let mut scene = Scene::new();
    for m in children(scene_node, "model") {
        let name = attr(m, "name")?;
        let found = vrml
            .find(name, None)
            .map_err(|e| at(m, SgError::nested(e)))?;
        let Some(model_path) = found else {
            return Err(at(
                m,
                SgError::new(SgErrorKind::UnknownName {
                    what: "VRML node (DEF) for the model",
                    name: name.to_string(),
                }),
            ));
        };
        let model_node = *model_path.last().expect("a found path is not empty");
        let mut model = Model::new(name);
        for b in children(m, "body") {
            let bname = attr(b, "name")?;
            let found = vrml
                .find(bname, Some(model_node))
                .map_err(|e| at(b, SgError::nested(e)))?;
            let Some(body_path) = found else {
                return Err(at(
                    b,
                    SgError::new(SgErrorKind::UnknownName {
                        what: "VRML node (DEF) for the body",
                        name: bname.to_string(),
                    }),
                ));
            };
            let body_node = *body_path.last().expect("a found path is not empty");
            let full: Vec<_> = model_path[..model_path.len() - 1]
                .iter()
                .chain(&body_path)
                .copied()
                .collect();
            let frame = vrml
                .path_transform(&full)
                .map_err(|e| at(b, SgError::nested(e)))?;
            let pose = rigid(&frame).ok_or_else(|| {
                at(
                    b,
                    SgError::unsupported("a scaled or sheared body frame (RL refuses it too)"),
                )
            })?;
            let shapes = vrml
                .shapes_under(body_node)
                .map_err(|e| at(b, SgError::nested(e)))?;
            let mut built = Vec::with_capacity(shapes.len());
            for s in shapes {
                for n in &s.notes {
                    model.warn(format!("body {bname}: {n}"));
                }
                built.push(Shape::new(s.name, s.geometry, s.pose).map_err(|e| at(b, e))?);
            }
            let body = model.add_body(bname);
            for s in built {
                body.push_shape(s);
            }
            body.place(&pose);
        }
        scene.add_model(model).map_err(|e| at(m, e))?;
    }
    Ok(scene)
}

/// Reads the rlsg file at `path` and the VRML it names.
pub fn load_scene(path: &Path) -> Result<Scene, SgError> {
    load_scene_with(path, &SceneLimits::DEFAULT)
}

/// [`load_scene`] within `limits`.
pub fn load_scene_with(path: &Path, limits: &SceneLimits) -> Result<Scene, SgError> {
    let text = read_text_within(path, limits.max_file_bytes)?;
    scene_from_str_with(&text, path, limits).map_err(|e| e.in_file(path))
}

/// Reads a bare `.wrl` as a scene of one model (named after the file) with one body `""`.
pub fn load_vrml(path: &Path) -> Result<Scene, SgError> {
    load_vrml_with(path, &SceneLimits::DEFAULT)
}

/// [`load_vrml`] within `limits`.
pub fn load_vrml_with(path: &Path, limits: &SceneLimits) -> Result<Scene, SgError> {
    let vrml = VrmlScene::load_with(path, limits)?;
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("vrml");
    let mut scene = Scene::new();
    scene.add_model(vrml.to_model(name).map_err(|e| e.in_file(path))?)?;
    Ok(scene)
}

/// Reads the rlsg scene at `scene` whose first model is the robot of RL's kinematic model file
/// `rlmdl` (`rlmdl` or `rlkin`, loaded by rl-core as `loaded`), and links that model to it
/// ([`link_kinematics`]).
pub fn load_robot_scene<const N: usize>(
    scene: &Path,
    rlmdl: &Path,
    loaded: &LoadedModel<N>,
) -> Result<Scene, SgError> {
    let mut s = load_scene(scene)?;
    let model = s
        .model_mut(crate::ModelId(0))
        .ok_or_else(|| SgError::missing("a model (the robot) in the scene").in_file(scene))?;
    link_kinematics(model, rlmdl, loaded)?;
    Ok(s)
}

/// Links `model` to RL's kinematics file `path` by the format rl-core loaded it as:
/// [`link_rlkin`] for `rlkin`, else [`link_rlmdl`].
pub fn link_kinematics<const N: usize>(
    model: &mut Model,
    path: &Path,
    loaded: &LoadedModel<N>,
) -> Result<(), SgError> {
    match loaded.format {
        Format::Rlkin => link_rlkin(model, path, loaded),
        _ => link_rlmdl(model, path, loaded),
    }
}

/// Links `model`'s bodies to the `<link>` elements of RL's Denavit–Hartenberg kinematics file
/// `rlkin` (loaded by rl-core as `loaded`), in the order RL's depth-first walk from the world
/// reaches them, and applies their `<ignore>` elements (see the module docs). Turns
/// self-collision on.
pub fn link_rlkin<const N: usize>(
    model: &mut Model,
    rlkin: &Path,
    loaded: &LoadedModel<N>,
) -> Result<(), SgError> {
    let text = read_text(rlkin)?;
    link_rlkin_str(model, &text, loaded).map_err(|e| e.in_file(rlkin))
}

/// [`link_rlkin`] from the file's text.
pub fn link_rlkin_str<const N: usize>(
    model: &mut Model,
    rlkin: &str,
    loaded: &LoadedModel<N>,
) -> Result<(), SgError> {
    let doc = parse(rlkin)?;
    let root = doc.root_element();
    let kin = match root.tag_name().name() {
        "rlkin" => Some(root),
        "rl" => child(root, "kin"),
        _ => None,
    }
    .and_then(|c| {
        c.children().find(|n| {
            n.is_element() && matches!(n.tag_name().name(), "kinematics" | "puma" | "rhino")
        })
    })
    .ok_or_else(|| {
        at(
            root,
            SgError::missing("<rlkin><kinematics> (or <puma>, <rhino>)"),
        )
    })?;
    let mut links = Vec::new();
    for l in children(kin, "link") {
        links.push((attr(l, "id")?, l));
    }
    // RL's `Kinematics::links`: the links the walk from the world reaches, in its order.
    let ordered: Vec<Node> = loaded
        .frames
        .iter()
        .filter_map(|f| links.iter().find(|(id, _)| *id == f.name).map(|(_, l)| *l))
        .collect();
    link_bodies(model, loaded, &ordered, "link (idref)")
}

/// Links `model`'s bodies, in order, to the `<body>` elements of RL's kinematic model file
/// `rlmdl` (loaded by rl-core as `loaded`), and applies its `<ignore>` elements (see the module
/// docs). Turns self-collision on.
pub fn link_rlmdl<const N: usize>(
    model: &mut Model,
    rlmdl: &Path,
    loaded: &LoadedModel<N>,
) -> Result<(), SgError> {
    let text = read_text(rlmdl)?;
    link_rlmdl_str(model, &text, loaded).map_err(|e| e.in_file(rlmdl))
}

/// [`link_rlmdl`] from the file's text.
pub fn link_rlmdl_str<const N: usize>(
    model: &mut Model,
    rlmdl: &str,
    loaded: &LoadedModel<N>,
) -> Result<(), SgError> {
    let doc = parse(rlmdl)?;
    let root = doc.root_element();
    let mdl = match root.tag_name().name() {
        "rlmdl" => child(root, "model"),
        "rl" => child(root, "mdl").and_then(|m| child(m, "model")),
        _ => None,
    }
    .ok_or_else(|| at(root, SgError::missing("<rlmdl><model>")))?;
    let bodies: Vec<_> = children(mdl, "body").collect();
    link_bodies(model, loaded, &bodies, "body (idref)")
}

/// Links `model`'s bodies in order to the frames of the elements `bodies` (by their `id`) and
/// applies the elements' `<ignore>` children; `what` names an `idref` in errors.
fn link_bodies<const N: usize>(
    model: &mut Model,
    loaded: &LoadedModel<N>,
    bodies: &[Node],
    what: &'static str,
) -> Result<(), SgError> {
    let ids: Vec<String> = bodies
        .iter()
        .map(|b| attr(*b, "id").map(str::to_string))
        .collect::<Result<_, _>>()?;
    let link = KinematicLink::by_order(model, loaded, &ids)?;
    model.set_kinematics(link);
    let index_of = |id: &str| ids.iter().position(|x| x == id);
    let n = model.bodies().len();
    for (i, b) in bodies.iter().enumerate().take(n) {
        for ig in children(*b, "ignore") {
            match ig.attribute("idref") {
                None | Some("") => {
                    if let Some(body) = model.body_mut(i) {
                        body.set_collision_enabled(false);
                    }
                }
                Some(r) => match index_of(r) {
                    Some(j) if j < n => model.allowed_collisions_mut().allow(i, j),
                    Some(_) => {}
                    None => {
                        return Err(at(
                            ig,
                            SgError::new(SgErrorKind::UnknownName {
                                what,
                                name: r.to_string(),
                            }),
                        ));
                    }
                },
            }
        }
    }
    model.set_self_collision(true);
    Ok(())
}
