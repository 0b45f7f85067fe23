//! RL's Denavit–Hartenberg kinematics format (`rlkin`): RL's example files load with RL's joint,
//! link and tool counts, units and limits, and — the independent check — their forward
//! kinematics agree with RL's `rlmdl` models of the same robots (written with fixed transforms
//! and joint axes, no DH) at many random configurations. Bad files give typed errors naming
//! the element.

use std::path::PathBuf;

use glam::{DQuat, DVec3};
use rl_core::algo;
use rl_core::joint::JointKind;
use rl_core::loader::{self, Format, LoadError, LoadErrorKind, LoadedModel};
use rl_core::model::ROOT;
use rl_core::spatial::PlueckerTransform;
use rl_core::{Data, Model};

const N: usize = 16;
const DEG: f64 = std::f64::consts::PI / 180.0;

fn data(dir: &str, name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data")
        .join(dir)
        .join(name)
}

fn load(dir: &str, name: &str) -> LoadedModel<N> {
    loader::load_file::<N>(data(dir, name)).unwrap_or_else(|e| panic!("{e}"))
}

fn kin_text(name: &str) -> String {
    std::fs::read_to_string(data("rlkin", name)).unwrap()
}

fn kin_err(text: &str) -> LoadError {
    match loader::load_rlkin_str::<N>(text) {
        Ok(_) => panic!("loaded a bad rlkin file:\n{text}"),
        Err(e) => e,
    }
}

/// World pose of frame `name` at `q`.
fn frame_pose(m: &LoadedModel<N>, q: &[f64], name: &str) -> PlueckerTransform {
    let mut d = Box::new(Data::<N>::new());
    algo::forward_position(&m.model, &mut d, q).unwrap();
    let (b, x) = m.frame_placement(name).unwrap();
    if b == ROOT { x } else { *d.world_pose(b) * x }
}

/// World pose of tool `tool` at `q`.
fn tool_pose(model: &Model<N>, q: &[f64], tool: usize) -> PlueckerTransform {
    let mut d = Box::new(Data::<N>::new());
    algo::forward_position(model, &mut d, q).unwrap();
    algo::tool_pose(model, &d, tool).unwrap()
}

/// Largest difference of position (m) and rotation matrix entries.
fn gap(a: &PlueckerTransform, b: &PlueckerTransform) -> f64 {
    let dp = (a.translation - b.translation).abs().max_element();
    let dr = (a.rotation - b.rotation)
        .to_cols_array()
        .iter()
        .fold(0.0f64, |m, x| m.max(x.abs()));
    dp.max(dr)
}

/// A small deterministic generator (xorshift64*), uniform in [0, 1).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
    /// A configuration uniform within the model's limits (±π where unlimited).
    fn q(&mut self, m: &Model<N>) -> Vec<f64> {
        (0..m.nq())
            .map(|k| {
                let l = m.limits(k);
                let (lo, hi) = if l.lower.is_finite() && l.upper.is_finite() {
                    (l.lower, l.upper)
                } else {
                    (-std::f64::consts::PI, std::f64::consts::PI)
                };
                lo + self.next() * (hi - lo)
            })
            .collect()
    }
}

/// (file, root element, DOF, links, tools) as RL's `Kinematics::update` counts them.
const FILES: &[(&str, usize, usize, &[&str])] = &[
    ("box-6d-300505.xml", 6, 7, &["tcp"]),
    ("mitsubishi-rv6sl.xml", 6, 7, &["tcp"]),
    ("staeubli-tx60l.xml", 6, 7, &["tcp"]),
    ("unimation-puma560.xml", 6, 7, &["tcp"]),
];

#[test]
fn every_example_file_loads_with_rls_counts() {
    let mut files: Vec<String> = std::fs::read_dir(data("rlkin", ""))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".xml"))
        .collect();
    files.sort();
    let listed: Vec<&str> = FILES.iter().map(|f| f.0).collect();
    assert_eq!(files, listed, "tests/data/rlkin and this list differ");
    for &(name, dof, links, tools) in FILES {
        let m = load("rlkin", name);
        assert_eq!(m.format, Format::Rlkin, "{name}");
        assert_eq!(m.model.nq(), dof, "{name}");
        assert_eq!(m.model.dof(), dof, "{name}");
        let names: Vec<&str> = m.model.tools().iter().map(|t| t.name.as_str()).collect();
        assert_eq!(names, tools, "{name}");
        let nlinks = m
            .frames
            .iter()
            .filter(|f| f.name.starts_with("link"))
            .count();
        assert_eq!(nlinks, links, "{name}");
        // One note that the format has no masses, nothing else.
        assert_eq!(m.warnings.len(), 1, "{name}: {:?}", m.warnings);
        assert!(
            m.warnings[0].contains("kinematics only"),
            "{:?}",
            m.warnings
        );
    }
}

#[test]
fn units_limits_and_joint_types_are_rls() {
    let rv = load("rlkin", "mitsubishi-rv6sl.xml");
    assert_eq!(rv.model.name(), "RV-6SL");
    // joint1: <max>135</max> <min>-92</min> <speed>267</speed>, degrees.
    let l = *rv.model.limits(1);
    assert!((l.upper - 135.0 * DEG).abs() < 1e-15);
    assert!((l.lower + 92.0 * DEG).abs() < 1e-15);
    assert!((l.velocity - 267.0 * DEG).abs() < 1e-15);
    assert!(!l.wraparound);
    for b in 0..6 {
        assert_eq!(rv.model.joint(b).kind(), JointKind::Revolute);
    }
    // The Puma has no <speed>: unknown, infinite.
    let puma = load("rlkin", "unimation-puma560.xml");
    assert_eq!(puma.model.limits(0).velocity, f64::INFINITY);
    // The box: three prismatic joints in metres, three revolute, two of them wrapping.
    let bx = load("rlkin", "box-6d-300505.xml");
    let kinds: Vec<JointKind> = (0..6).map(|b| bx.model.joint(b).kind()).collect();
    assert_eq!(
        kinds,
        [
            JointKind::Prismatic,
            JointKind::Prismatic,
            JointKind::Prismatic,
            JointKind::Revolute,
            JointKind::Revolute,
            JointKind::Revolute
        ]
    );
    assert_eq!(bx.model.limits(0).upper, 30.0);
    assert_eq!(bx.model.limits(2).upper, 2.0);
    assert!(bx.model.limits(3).wraparound);
    assert!(!bx.model.limits(4).wraparound);
    assert!(bx.model.limits(5).wraparound);
}

#[test]
fn the_dh_product_is_pauls_with_theta_added_to_q() {
    // Puma joint1 (link1 → link2): d = 0.1291, θ = 0, a = 0.4318, α = 0. At q1 = 30° the
    // pose of link2 in link1 is Tz(d)·Rz(30°)·Tx(a): origin (a cos 30°, a sin 30°, d).
    let puma = load("rlkin", "unimation-puma560.xml");
    let q = [0.0, 30.0 * DEG, 0.0, 0.0, 0.0, 0.0];
    let l1 = frame_pose(&puma, &q, "link1");
    let l2 = frame_pose(&puma, &q, "link2");
    let rel = l1.inverse() * l2;
    let (s, c) = (30.0 * DEG).sin_cos();
    let want = DVec3::new(0.4318 * c, 0.4318 * s, 0.1291);
    assert!((rel.translation - want).length() < 1e-15, "{rel:?}");
    // RV-6SL joint1 has θ = -90°: at q = 0 its link2 is turned -90° about link1's z, and
    // q = +90° cancels it (θ is an offset added to q).
    let rv = load("rlkin", "mitsubishi-rv6sl.xml");
    let at = |q1: f64| {
        let q = [0.0, q1, 0.0, 0.0, 0.0, 0.0];
        frame_pose(&rv, &q, "link1").inverse() * frame_pose(&rv, &q, "link2")
    };
    let zero = at(0.0);
    assert!((zero.rotation * DVec3::X - DVec3::NEG_Y).length() < 1e-15);
    assert!((zero.translation - DVec3::new(0.0, -0.38, 0.0)).length() < 1e-15);
    let back = at(90.0 * DEG);
    assert!((back.rotation * DVec3::X - DVec3::X).length() < 1e-15);
    assert!((back.translation - DVec3::new(0.38, 0.0, 0.0)).length() < 1e-15);
}

/// The tool poses of an rlkin and an rlmdl model of one robot agree at 200 random
/// configurations.
fn same_fk(kin: &str, mdl: &str, mdl_tool: &str) {
    let k = load("rlkin", kin);
    let m = load("rlmdl", mdl);
    assert_eq!(k.model.nq(), m.model.nq());
    let mt = m
        .model
        .tools()
        .iter()
        .position(|t| t.name.as_str() == mdl_tool)
        .unwrap();
    let mut rng = Rng(0x5eed_0001);
    let mut worst = 0.0f64;
    for _ in 0..200 {
        let q = rng.q(&k.model);
        let a = tool_pose(&k.model, &q, 0);
        let b = tool_pose(&m.model, &q, mt);
        worst = worst.max(gap(&a, &b));
    }
    assert!(worst < 1e-9, "{kin} vs {mdl}: tool poses differ by {worst}");
    // Every link frame is the rlmdl body frame of the same index (RL's scenes pair both with
    // the same link geometry).
    let mut worst = 0.0f64;
    for _ in 0..50 {
        let q = rng.q(&k.model);
        for i in 0..7 {
            let a = frame_pose(&k, &q, &format!("link{i}"));
            let b = frame_pose(&m, &q, &format!("body{i}"));
            worst = worst.max(gap(&a, &b));
        }
    }
    assert!(
        worst < 1e-9,
        "{kin} vs {mdl}: link frames differ by {worst}"
    );
}

#[test]
fn puma_560_forward_kinematics_agree_with_rls_rlmdl_model() {
    // The rlmdl Puma's only tool is body6 (its frame7 is unconnected); the rlkin tool `tcp`
    // sits on link6 through an identity transform, so both are the frame of the last link.
    same_fk("unimation-puma560.xml", "unimation-puma560.xml", "body6");
}

#[test]
fn rv_6sl_forward_kinematics_agree_with_rls_rlmdl_model() {
    same_fk("mitsubishi-rv6sl.xml", "mitsubishi-rv6sl.xml", "frame8");
}

#[test]
fn box_6d_forward_kinematics_agree_with_rls_six_dof_model() {
    // The rlkin box is three prismatic joints (x, y, z of the world, through the base's 90°
    // about y and the DH twists) and three revolute joints; RL's rlmdl box is one sixDof
    // joint, q = [x y z qx qy qz qw]. The prismatic joints must move link6's origin along the
    // world axes exactly; with the sixDof joint set to link6's pose, both tools (1.5 m along
    // link6's x) must agree.
    let k = load("rlkin", "box-6d-300505.xml");
    let m = load("rlmdl", "box-6d-300505.sixDof.xml");
    assert_eq!(m.model.nq(), 7);
    let mut rng = Rng(0x5eed_0002);
    let mut worst = 0.0f64;
    for _ in 0..200 {
        let q = rng.q(&k.model);
        let link6 = frame_pose(&k, &q, "link6");
        worst = worst.max((link6.translation - DVec3::new(q[0], q[1], q[2])).length());
        let r: DQuat = link6.quaternion();
        let q6 = [q[0], q[1], q[2], r.x, r.y, r.z, r.w];
        let a = tool_pose(&k.model, &q, 0);
        let b = tool_pose(&m.model, &q6, 0);
        worst = worst.max(gap(&a, &b));
    }
    assert!(worst < 1e-9, "box: {worst}");
    // At q = 0 the box is in the world's axes, as the sixDof box at the identity.
    let zero = frame_pose(&k, &[0.0; 6], "link6");
    assert!(gap(&zero, &PlueckerTransform::IDENTITY) < 1e-15, "{zero:?}");
}

#[test]
fn rl_kin_root_is_read_too() {
    let text = kin_text("unimation-puma560.xml")
        .replace("<rlkin ", "<rl><kin ")
        .replace("</rlkin>", "</kin></rl>");
    let m = loader::load_str::<N>(&text, &Default::default()).unwrap();
    assert_eq!(m.format, Format::Rlkin);
    assert_eq!(m.model.nq(), 6);
}

#[test]
fn world_and_offset_are_applied() {
    let text = kin_text("unimation-puma560.xml");
    let a: LoadedModel<N> = loader::load_rlkin_str(&text).unwrap();
    // The world moved 2 m along x and turned 90° about z.
    let moved = text.replacen("<z>0</z>", "<z>90</z>", 1).replacen(
        "<x>0</x>\n\t\t\t\t<y>0</y>\n\t\t\t\t<z>0</z>\n\t\t\t</translation>",
        "<x>2</x>\n\t\t\t\t<y>0</y>\n\t\t\t\t<z>0</z>\n\t\t\t</translation>",
        1,
    );
    assert_ne!(moved, text);
    let b: LoadedModel<N> = loader::load_rlkin_str(&moved).unwrap();
    let q = [0.1, -0.2, 0.3, 0.4, -0.5, 0.6];
    let w = PlueckerTransform::new(
        glam::DMat3::from_rotation_z(90.0 * DEG),
        DVec3::new(2.0, 0.0, 0.0),
    );
    let ta = tool_pose(&a.model, &q, 0);
    let tb = tool_pose(&b.model, &q, 0);
    assert!(gap(&(w * ta), &tb) < 1e-12);
    // An <offset> (deg) on joint2 is added to q like θ.
    let off = text.replacen(
        "<max>225</max>",
        "<offset>20</offset>\n\t\t\t<max>225</max>",
        1,
    );
    let c: LoadedModel<N> = loader::load_rlkin_str(&off).unwrap();
    let mut q2 = q;
    q2[2] += 20.0 * DEG;
    assert!(gap(&tool_pose(&c.model, &q, 0), &tool_pose(&a.model, &q2, 0)) < 1e-12);
    assert!(gap(&tool_pose(&c.model, &q, 0), &ta) > 1e-3);
}

#[test]
fn a_truncated_file_is_an_xml_error() {
    let text = kin_text("mitsubishi-rv6sl.xml");
    let cut = &text[..text.len() / 2];
    let e = kin_err(cut);
    assert!(matches!(e.kind, LoadErrorKind::Xml(_)), "{e:?}");
    // By file, too: the error names the file.
    let dir = std::env::temp_dir().join(format!("rlkin-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("cut.xml");
    std::fs::write(&f, cut).unwrap();
    let e = loader::load_file::<N>(&f).unwrap_err();
    assert!(e.to_string().contains("cut.xml"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn an_unknown_joint_type_names_its_element() {
    let text = kin_text("unimation-puma560.xml")
        .replacen("<revolute id=\"joint3\">", "<helical id=\"joint3\">", 1)
        .replacen(
            "</revolute>\n\t\t<link id=\"link4\">",
            "</helical>\n\t\t<link id=\"link4\">",
            1,
        );
    let e = kin_err(&text);
    assert!(
        matches!(&e.kind, LoadErrorKind::UnknownJointType { joint_type } if joint_type == "helical"),
        "{e:?}"
    );
    assert!(e.to_string().contains("<helical \"joint3\">"), "{e}");
}

#[test]
fn a_missing_dh_element_names_its_joint() {
    let text = kin_text("unimation-puma560.xml");
    let no_dh = text.replacen(
        "<dh>\n\t\t\t\t<d>0</d>\n\t\t\t\t<theta>0</theta>\n\t\t\t\t<a>-0.0203</a>\n\t\t\t\t<alpha>90</alpha>\n\t\t\t</dh>",
        "",
        1,
    );
    assert_ne!(no_dh, text);
    let e = kin_err(&no_dh);
    assert_eq!(e.kind, LoadErrorKind::MissingElement { child: "dh" });
    assert!(e.to_string().contains("<revolute \"joint2\">"), "{e}");
    // And a missing parameter inside <dh>.
    let no_alpha = text.replacen("<alpha>-90</alpha>", "", 1);
    let e = kin_err(&no_alpha);
    assert_eq!(e.kind, LoadErrorKind::MissingElement { child: "alpha" });
    assert!(e.to_string().contains("<dh>"), "{e}");
}

#[test]
fn other_bad_input_is_typed() {
    let text = kin_text("unimation-puma560.xml");
    // Not a number.
    let e = kin_err(&text.replacen("<d>0.6604</d>", "<d>high</d>", 1));
    assert!(
        matches!(&e.kind, LoadErrorKind::InvalidValue { what, .. } if what == "d"),
        "{e:?}"
    );
    // min above max.
    let e = kin_err(&text.replacen("<min>-160</min>", "<min>170</min>", 1));
    assert!(
        matches!(e.kind, LoadErrorKind::InvalidValue { .. }),
        "{e:?}"
    );
    // A frame reference that does not exist.
    let e = kin_err(&text.replacen("<b idref=\"link3\"/>", "<b idref=\"link9\"/>", 1));
    assert!(
        matches!(&e.kind, LoadErrorKind::UnresolvedReference { target } if target == "link9"),
        "{e:?}"
    );
    // An <ignore idref> that names no link (RL throws).
    let e = kin_err(&text.replacen("<ignore idref=\"link1\"/>", "<ignore idref=\"nope\"/>", 1));
    assert!(
        matches!(&e.kind, LoadErrorKind::UnresolvedReference { target } if target == "nope"),
        "{e:?}"
    );
    // Two frames with one id.
    let e = kin_err(&text.replacen("<frame id=\"tcp\"/>", "<frame id=\"link3\"/>", 1));
    assert!(
        matches!(e.kind, LoadErrorKind::DuplicateName { .. }),
        "{e:?}"
    );
    // No world; no model element.
    let e = kin_err(
        &text
            .replacen("<world id=\"world\">", "<frame id=\"world\">", 1)
            .replacen("</world>", "</frame>", 1),
    );
    assert_eq!(e.kind, LoadErrorKind::MissingElement { child: "world" });
    let e = kin_err("<rlkin><robot/></rlkin>");
    assert_eq!(
        e.kind,
        LoadErrorKind::MissingElement {
            child: "kinematics"
        }
    );
}
