//! RL's XML model format: every example model loads with RL's DOF and tool counts, and the
//! loaded geometry is RL's (offsets, degrees, Rz·Ry·Rx, COM-frame inertia, gravity sign).
#![allow(clippy::needless_range_loop)]

use std::path::PathBuf;

use glam::{DMat3, DVec3};
use rl_core::algo;
use rl_core::joint::JointKind;
use rl_core::loader::{self, Format, LoadErrorKind, LoadedModel};
use rl_core::model::ROOT;
use rl_core::spatial::PlueckerTransform;
use rl_core::{Data, Model};

const N: usize = 64;

fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/data/rlmdl")
}

fn load(name: &str) -> LoadedModel<N> {
    let path = data_dir().join(name);
    loader::load_file::<N>(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// (file, DOF, nq, tools) as RL computes them: DOF per joint type, tools = leaves of the frame
/// tree reachable from the world.
const MODELS: &[(&str, usize, usize, &[&str])] = &[
    ("box-6d-300505.sixDof.xml", 6, 7, &["tcp"]),
    ("box-6d-300505.spherical.xml", 6, 7, &["tcp"]),
    ("comau-smart5-nj4-220-27.xml", 6, 6, &["frame7"]),
    // rl-models.md lists two tools, but RL's Model::update() finds one leaf: `frame1` is
    // declared and never connected, so it is not visited (like the Puma's `frame7`).
    ("kuka-kr16-2.xml", 6, 6, &["body6"]),
    ("kuka-lbr-iiwa-7-r800.xml", 7, 7, &["frame8"]),
    (
        "mekabot-torso-rightarm-leftarm.xml",
        17,
        17,
        &["RT8", "LT8"],
    ),
    ("mitsubishi-rv6sl.xml", 6, 6, &["frame8"]),
    ("planar2.xml", 2, 2, &["frame1"]),
    ("planar3.xml", 3, 3, &["frame2"]),
    ("staeubli-tx90.xml", 6, 6, &["frame8"]),
    ("unimation-puma560.xml", 6, 6, &["body6"]),
    ("universal-robots-ur5.xml", 6, 6, &["frame7"]),
];

/// RL's XSLT-parameterised model (an `xsl:stylesheet` whose parameters fill in the lengths) is
/// refused with a typed error that says what to do, not misread as a model.
#[test]
fn the_xslt_parameterised_model_is_refused_with_what_to_do() {
    let path = data_dir().join("planar2.param.xml");
    let e = loader::load_file::<8>(&path).unwrap_err();
    assert!(matches!(e.kind, LoadErrorKind::Unsupported { .. }), "{e:?}");
    assert!(e.to_string().contains("xsltproc"), "{e}");
}

#[test]
fn every_example_model_loads_with_rls_dof_and_tools() {
    let mut files: Vec<String> = std::fs::read_dir(data_dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".xml") && !n.ends_with(".param.xml"))
        .collect();
    files.sort();
    let listed: Vec<&str> = MODELS.iter().map(|m| m.0).collect();
    assert_eq!(
        files, listed,
        "every file in tests/data/rlmdl is checked here"
    );
    for &(file, dof, nq, tools) in MODELS {
        let m = load(file);
        assert_eq!(m.format, Format::Rlmdl);
        assert_eq!(m.model.dof(), dof, "{file}: DOF");
        assert_eq!(m.model.nq(), nq, "{file}: nq");
        let names: Vec<&str> = m.model.tools().iter().map(|t| t.name.as_str()).collect();
        assert_eq!(names, tools, "{file}: tools");
        for i in 0..m.model.body_count() {
            assert!(m.model.inertia(i).mass.is_finite());
        }
    }
}

#[test]
fn the_tree_keeps_rls_depth_first_joint_order() {
    let m = load("mekabot-torso-rightarm-leftarm.xml");
    let joints: Vec<&str> = (0..m.model.body_count())
        .map(|i| m.model.joint_name(i))
        .collect();
    // The torso first, then the right arm (first in the file), then the left arm.
    assert_eq!(&joints[..3], &["T2.J0", "T2.J1", "T2.J2"]);
    assert!(joints[3].starts_with("Right."), "{joints:?}");
    assert!(joints[10].starts_with("Left."), "{joints:?}");
    // Both arms hang from the torso's last body.
    let torso = m.model.body_index(m.model.body_name(2)).unwrap();
    assert_eq!(m.model.parent(3), torso);
    assert_eq!(m.model.parent(10), torso);
}

#[test]
fn gravity_is_the_negated_base_acceleration() {
    let m = load("unimation-puma560.xml");
    assert_eq!(m.model.gravity(), DVec3::new(0.0, 0.0, -9.86055));
    let p = load("planar2.xml");
    assert_eq!(p.model.gravity(), DVec3::new(0.0, 0.0, -9.80665));
}

#[test]
fn limits_and_home_are_converted_from_degrees() {
    let m = load("unimation-puma560.xml");
    let l = m.model.limits(1);
    let d = std::f64::consts::PI / 180.0;
    assert_eq!(
        (l.lower, l.upper, l.velocity),
        (-225.0 * d, 45.0 * d, 250.0 * d)
    );
    assert!(!l.wraparound);
    let ur5 = load("universal-robots-ur5.xml");
    let home = ur5.home.as_ref().unwrap();
    assert_eq!(home.len(), 6);
    assert!((home[1] + std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    let sixdof = load("box-6d-300505.sixDof.xml");
    assert_eq!(sixdof.model.joint(0).kind(), JointKind::SixDof);
    assert_eq!(
        (sixdof.model.limits(2).lower, sixdof.model.limits(2).upper),
        (0.0, 2.0)
    );
    assert_eq!(sixdof.model.limits(3).upper, f64::INFINITY);
}

#[test]
fn defaults_give_unit_mass_and_identity_inertia() {
    let m = load("box-6d-300505.sixDof.xml");
    let i = m.model.inertia(0);
    assert_eq!(i.mass, 1.0);
    assert_eq!(i.first_moment, DVec3::ZERO);
    assert_eq!(i.rotational, DMat3::IDENTITY);
    // The tool is the leaf frame 1.5 m along x.
    let t = &m.model.tools()[0];
    assert_eq!(t.body, 0);
    assert_eq!(t.placement.translation, DVec3::new(1.5, 0.0, 0.0));
}

/// Forward kinematics of an RL model by hand: world pose of `body` at `q`, walking the frames
/// as RL does (fixed: Rz·Ry·Rx then translation; revolute: rotation about the axis by q+offset).
fn fk_tool(model: &Model<N>, q: &[f64], tool: usize) -> PlueckerTransform {
    let mut d = Box::new(Data::<N>::new());
    algo::forward_position(model, &mut d, q).unwrap();
    let t = &model.tools()[tool];
    if t.body == ROOT {
        t.placement
    } else {
        *d.world_pose(t.body) * t.placement
    }
}

#[test]
fn a_revolute_offset_is_added_to_q_as_rl_does() {
    // comau-smart5's joint2 has <offset>90</offset>: its frame3 at q is the same as a model
    // without the offset at q + 90°.
    let text = std::fs::read_to_string(data_dir().join("comau-smart5-nj4-220-27.xml")).unwrap();
    assert!(text.contains("<offset>90</offset>"));
    let with: LoadedModel<N> = loader::load_rlmdl_str(&text).unwrap();
    let without: LoadedModel<N> =
        loader::load_rlmdl_str(&text.replace("<offset>90</offset>", "")).unwrap();
    let q = [0.1, -0.2, 0.3, 0.4, -0.5, 0.6];
    let mut q2 = q;
    q2[2] += std::f64::consts::FRAC_PI_2;
    let a = fk_tool(&with.model, &q, 0);
    let b = fk_tool(&without.model, &q2, 0);
    assert!(
        (a.translation - b.translation).length() < 1e-12,
        "{a:?} vs {b:?}"
    );
    assert!(
        (a.rotation - b.rotation)
            .to_cols_array()
            .iter()
            .all(|x| x.abs() < 1e-12)
    );
    // And the offset changes the pose at the same q (so the test can fail).
    let c = fk_tool(&without.model, &q, 0);
    assert!((a.translation - c.translation).length() > 1e-3);
}

#[test]
fn puma_tool_pose_matches_rls_reference() {
    // shared/reference/rl-models.md: RL's tool0 pose at q_i = 0.1 i + 0.2.
    let m = load("unimation-puma560.xml");
    let q: Vec<f64> = (0..6).map(|i| 0.1 * i as f64 + 0.2).collect();
    let x = fk_tool(&m.model, &q, 0);
    let p = [0.671474225622, 0.279233964449, 0.889996320686];
    for k in 0..3 {
        assert!(
            (x.translation[k] - p[k]).abs() < 1e-11,
            "{:?}",
            x.translation
        );
    }
    let quat = x.quaternion();
    let expected = [
        0.587069090875,
        0.157051554336,
        0.565084560121,
        0.558000118039,
    ];
    let s = if quat.w < 0.0 { -1.0 } else { 1.0 };
    let got = [s * quat.w, s * quat.x, s * quat.y, s * quat.z];
    for k in 0..4 {
        assert!((got[k] - expected[k]).abs() < 1e-11, "{got:?}");
    }
}

#[test]
fn fixed_frames_merge_their_inertia_into_the_moving_body() {
    // Puma: joint0 moves frame1; body1 (m = 0, I_yy = 0.35) hangs from it through fixed2, which
    // turns it by -90° about x. Its inertia in frame1 axes is I_zz = 0.35.
    let m = load("unimation-puma560.xml");
    let i = m.model.inertia(0);
    assert_eq!(i.mass, 0.0);
    assert!(
        (i.rotational.col(2).z - 0.35).abs() < 1e-12,
        "{:?}",
        i.rotational
    );
    assert!(i.rotational.col(1).y.abs() < 1e-12);
    // The base body0 (default m = 1) sits on the world.
    assert_eq!(m.model.base_mass(), 1.0);
    assert!(m.frame("body0").unwrap().body == ROOT);
    assert!(
        m.warnings.iter().any(|w| w.contains("frame7")),
        "{:?}",
        m.warnings
    );
}

#[test]
fn the_world_transform_places_the_base() {
    let text = std::fs::read_to_string(data_dir().join("planar2.xml")).unwrap();
    let moved = text.replacen(
        "<translation>\n\t\t\t\t<x>0</x>",
        "<translation>\n\t\t\t\t<x>2</x>",
        1,
    );
    assert_ne!(moved, text, "planar2.xml changed its layout");
    let a: LoadedModel<N> = loader::load_rlmdl_str(&text).unwrap();
    let b: LoadedModel<N> = loader::load_rlmdl_str(&moved).unwrap();
    let q = [0.3, -0.4];
    let d = fk_tool(&b.model, &q, 0).translation - fk_tool(&a.model, &q, 0).translation;
    assert!((d - DVec3::new(2.0, 0.0, 0.0)).length() < 1e-12, "{d}");
}

#[test]
fn prismatic_helical_and_cylindrical_offsets_follow_rl() {
    let text = r#"<rlmdl><model><name>joints</name><world id="w"><g><z>9.81</z></g></world>
    <body id="a"/><body id="b"/><body id="c"/><frame id="t"/>
    <prismatic id="p"><frame><a idref="w"/><b idref="a"/></frame>
      <axis><x>1</x><y>0</y><z>0</z></axis><max>2</max><min>-1</min><offset>0.5</offset><speed>0.3</speed></prismatic>
    <helical id="h"><frame><a idref="a"/><b idref="b"/></frame><offset>2</offset><pitch>0.1</pitch></helical>
    <cylindrical id="c"><frame><a idref="b"/><b idref="c"/></frame><offset>0.3</offset><offset>0.2</offset></cylindrical>
    <fixed id="f"><frame><a idref="c"/><b idref="t"/></frame><translation><x>1</x></translation></fixed>
    </model></rlmdl>"#;
    let m: LoadedModel<N> = loader::load_rlmdl_str(text).unwrap();
    assert_eq!((m.model.nq(), m.model.dof()), (4, 4));
    let l = m.model.limits(0);
    assert_eq!((l.lower, l.upper, l.velocity), (-1.0, 2.0, 0.3));
    // Prismatic: x = q + 0.5. Helical (RL's quirk): rotation by q, translation 0.1 (q + 2).
    // Cylindrical: rotation q0 + 0.3, translation q1 + 0.2.
    for q in [[0.0, 0.0, 0.0, 0.0], [0.1, 0.5, 0.2, 0.1]] {
        let x = fk_tool(&m.model, &q, 0).translation;
        let angle = q[1] + q[2] + 0.3;
        let expected = DVec3::new(
            q[0] + 0.5 + angle.cos(),
            angle.sin(),
            0.1 * (q[1] + 2.0) + q[3] + 0.2,
        );
        assert!((x - expected).length() < 1e-12, "{q:?}: {x} vs {expected}");
    }
}

#[test]
fn elements_rl_ignores_are_reported() {
    // comau-smart5 has a <gamma> element, which RL's XmlFactory does not read (it reads
    // gammaPosition/gammaVelocity).
    let m = load("comau-smart5-nj4-220-27.xml");
    assert!(
        m.warnings.iter().any(|w| w.contains("<gamma>")),
        "{:?}",
        m.warnings
    );
    let home = m.home.as_ref().unwrap();
    assert!((home[2] + std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    let kr16 = load("kuka-kr16-2.xml");
    assert!(
        kr16.warnings.iter().any(|w| w.contains("\"frame1\"")),
        "{:?}",
        kr16.warnings
    );
}

#[test]
fn a_turned_world_turns_gravity_with_it() {
    // RL's <g> is given in the world frame's axes; the world frame is turned by its rotation.
    let text = r#"<rlmdl><model><world id="w"><rotation><x>90</x></rotation>
        <g><z>9.81</z></g></world><body id="b"/>
        <revolute id="j"><frame><a idref="w"/><b idref="b"/></frame></revolute></model></rlmdl>"#;
    let m: LoadedModel<N> = loader::load_rlmdl_str(text).unwrap();
    assert!((m.model.gravity() - DVec3::new(0.0, 9.81, 0.0)).length() < 1e-12);
    // The joint axis (z of the world frame) is the absolute -y axis.
    let x = *m.model.placement(0);
    assert!((x.rotation * DVec3::Z - DVec3::new(0.0, -1.0, 0.0)).length() < 1e-12);
}
