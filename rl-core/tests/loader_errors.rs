//! Bad model files: one test per error class. Each checks the error's kind and that the message
//! names the element at fault (tag, id or name, line:column) — and nothing panics.

use rl_core::loader::{self, LoadError, LoadErrorKind, LoadedModel, UrdfOptions};
use rl_core::model::ModelError;

const N: usize = 8;

fn urdf_err(text: &str) -> LoadError {
    urdf_err_n::<N>(text)
}

fn urdf_err_n<const C: usize>(text: &str) -> LoadError {
    match loader::load_urdf_str::<C>(text, &UrdfOptions::default()) {
        Ok(_) => panic!("loaded a bad URDF:\n{text}"),
        Err(e) => e,
    }
}

fn rl_err(text: &str) -> LoadError {
    rl_err_n::<N>(text)
}

fn rl_err_n<const C: usize>(text: &str) -> LoadError {
    let r: Result<LoadedModel<C>, _> = loader::load_rlmdl_str(text);
    match r {
        Ok(_) => panic!("loaded a bad RL model:\n{text}"),
        Err(e) => e,
    }
}

/// The message names `<tag "id">` at `line:col`.
fn names(e: &LoadError, at: &str) {
    let msg = e.to_string();
    assert!(msg.contains(at), "message {msg:?} should name {at:?}");
}

const INERTIAL: &str = r#"<inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>"#;

fn revolute(name: &str, parent: &str, child: &str) -> String {
    format!(
        r#"<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>"#
    )
}

/// An RL model around `body` (frames, transforms), world `w`.
fn rl(body: &str) -> String {
    format!("<rlmdl><model><name>t</name>\n<world id=\"w\"/>\n{body}\n</model></rlmdl>")
}

#[test]
fn xml_syntax() {
    let e = urdf_err("<robot name=\"r\">\n  <link name=\"a\">\n</robot>");
    assert!(matches!(e.kind, LoadErrorKind::Xml(_)), "{e:?}");
    let msg = e.to_string();
    assert!(
        msg.contains("XML syntax error") && msg.contains("3:"),
        "{msg}"
    );
    let e = rl_err("<rlmdl><model></rlmdl>");
    assert!(matches!(e.kind, LoadErrorKind::Xml(_)));
    // Not even text.
    let e = urdf_err("");
    assert!(matches!(e.kind, LoadErrorKind::Xml(_)));
}

#[test]
fn unknown_format() {
    let e = loader::load_str::<N>("<robotmodel/>", &UrdfOptions::default()).unwrap_err();
    assert!(matches!(&e.kind, LoadErrorKind::UnknownFormat { root } if root == "robotmodel"));
    names(&e, "1:1: <robotmodel>");
}

#[test]
fn unknown_joint_type() {
    let text = String::from(
        "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/>\n<joint name=\"ball\" type=\"spherical\"><parent link=\"a\"/><child link=\"b\"/></joint></robot>",
    );
    let e = urdf_err(&text);
    assert!(
        matches!(&e.kind, LoadErrorKind::UnknownJointType { joint_type } if joint_type == "spherical")
    );
    names(&e, "2:1: <joint \"ball\">");
    let e = rl_err(&rl(
        "<frame id=\"f\"/>\n<universal id=\"u\"><frame><a idref=\"w\"/><b idref=\"f\"/></frame></universal>",
    ));
    assert!(
        matches!(&e.kind, LoadErrorKind::UnknownJointType { joint_type } if joint_type == "universal")
    );
    names(&e, "4:1: <universal \"u\">");
}

#[test]
fn missing_attribute() {
    let e = urdf_err(
        "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/>\n<joint name=\"j\"><parent link=\"a\"/><child link=\"b\"/></joint></robot>",
    );
    assert!(matches!(
        e.kind,
        LoadErrorKind::MissingAttribute { attribute: "type" }
    ));
    names(&e, "2:1: <joint \"j\">");
    assert!(e.to_string().contains("missing attribute \"type\""));
    let e = rl_err(&rl("<body/>"));
    assert!(matches!(
        e.kind,
        LoadErrorKind::MissingAttribute { attribute: "id" }
    ));
    names(&e, "3:1: <body>");
}

#[test]
fn missing_element() {
    // urdfdom requires <limit> on revolute and prismatic joints.
    let text = "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/>\n<joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/></joint></robot>";
    let e = urdf_err(text);
    assert!(matches!(
        e.kind,
        LoadErrorKind::MissingElement { child: "limit" }
    ));
    names(&e, "2:1: <joint \"j\">");
    let e = urdf_err(
        "<robot name=\"r\"><link name=\"a\"/>\n<joint name=\"j\" type=\"fixed\"><parent link=\"a\"/></joint></robot>",
    );
    assert!(matches!(
        e.kind,
        LoadErrorKind::MissingElement { child: "child" }
    ));
    let e = rl_err(&rl("<frame id=\"f\"/>\n<fixed id=\"x\"/>"));
    assert!(matches!(
        e.kind,
        LoadErrorKind::MissingElement { child: "frame" }
    ));
    names(&e, "4:1: <fixed \"x\">");
    let e = rl_err("<rlmdl><model><body id=\"b\"/></model></rlmdl>");
    assert!(matches!(
        e.kind,
        LoadErrorKind::MissingElement { child: "world" }
    ));
}

#[test]
fn invalid_value() {
    let text = format!(
        "<robot name=\"r\"><link name=\"a\"/><link name=\"b\">{INERTIAL}</link>\n<joint name=\"j\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/>\n<origin xyz=\"1 2\"/></joint></robot>"
    );
    let e = urdf_err(&text);
    assert!(
        matches!(&e.kind, LoadErrorKind::InvalidValue { what, value, .. } if what == "xyz" && value == "1 2")
    );
    names(&e, "3:1: <origin>");
    let e = urdf_err(&text.replace("1 2", "1 2 nan"));
    assert!(e.to_string().contains("not finite"), "{e}");
    let e = urdf_err(&text.replace("1 2", "1 2 x"));
    assert!(e.to_string().contains("not a number"), "{e}");
    // A zero axis on a moving joint.
    let text = String::from(
        "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/>\n<joint name=\"j\" type=\"continuous\"><parent link=\"a\"/><child link=\"b\"/>\n<axis xyz=\"0 0 0\"/></joint></robot>",
    );
    let e = urdf_err(&text);
    assert!(e.to_string().contains("zero axis"), "{e}");
    names(&e, "3:1: <axis>");
    // RL: a mass that is not a number, a negative mass, min above max.
    let e = rl_err(&rl("<body id=\"b\">\n<m>heavy</m></body>"));
    assert!(matches!(&e.kind, LoadErrorKind::InvalidValue { what, .. } if what == "m"));
    names(&e, "4:1: <m>");
    let e = rl_err(&rl("<body id=\"b\"><m>-1</m></body>"));
    assert!(e.to_string().contains("negative mass"), "{e}");
    let e = rl_err(&rl(
        "<body id=\"b\"/><revolute id=\"j\"><frame><a idref=\"w\"/><b idref=\"b\"/></frame><max>10</max>\n<min>20</min></revolute>",
    ));
    assert!(e.to_string().contains("greater than max"), "{e}");
}

#[test]
fn missing_inertia() {
    let text = "<robot name=\"r\"><link name=\"a\"/>\n<link name=\"b\"><inertial><mass value=\"2\"/></inertial></link>\n".to_string()
        + &revolute("j", "a", "b")
        + "</robot>";
    let e = urdf_err(&text);
    assert!(matches!(
        e.kind,
        LoadErrorKind::MissingInertia { part: "inertia" }
    ));
    names(&e, "2:1: <link \"b\">");
    assert!(e.to_string().contains("missing inertia"));
    let e = urdf_err(&text.replace(
        "<mass value=\"2\"/>",
        "<inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/>",
    ));
    assert!(matches!(
        e.kind,
        LoadErrorKind::MissingInertia { part: "mass" }
    ));
    // An inertia that is not physical (negative moment) is refused by the model builder.
    let e = urdf_err(&text.replace(
        "<mass value=\"2\"/>",
        "<mass value=\"2\"/><inertia ixx=\"-1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/>",
    ));
    assert!(
        matches!(
            e.kind,
            LoadErrorKind::Model(ModelError::InvalidInertia { .. })
        ),
        "{e:?}"
    );
    names(&e, "<joint \"j\">");
}

#[test]
fn unresolved_reference() {
    let text = "<robot name=\"r\"><link name=\"a\"/>\n".to_string()
        + &revolute("j", "a", "nope")
        + "</robot>";
    let e = urdf_err(&text);
    assert!(matches!(&e.kind, LoadErrorKind::UnresolvedReference { target } if target == "nope"));
    names(&e, "2:1: <joint \"j\">");
    let e = rl_err(&rl(
        "<body id=\"b\"/>\n<fixed id=\"x\"><frame><a idref=\"w\"/><b idref=\"missing\"/></frame></fixed>",
    ));
    assert!(
        matches!(&e.kind, LoadErrorKind::UnresolvedReference { target } if target == "missing")
    );
    names(&e, "4:1: <fixed \"x\">");
}

#[test]
fn duplicate_name() {
    let e = urdf_err("<robot name=\"r\"><link name=\"a\"/>\n<link name=\"a\"/></robot>");
    assert!(matches!(&e.kind, LoadErrorKind::DuplicateName { name } if name == "a"));
    names(&e, "2:1: <link \"a\">");
    let e = rl_err(&rl("<frame id=\"f\"/>\n<body id=\"f\"/>"));
    assert!(matches!(e.kind, LoadErrorKind::DuplicateName { .. }));
    names(&e, "4:1: <body \"f\">");
}

#[test]
fn cycle_in_the_tree() {
    // a is the root; c and d hang from each other.
    let text = format!(
        "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><link name=\"c\"/><link name=\"d\"/>\n{}\n{}\n{}</robot>",
        revolute("j1", "a", "b"),
        revolute("j2", "c", "d"),
        revolute("j3", "d", "c")
    );
    let e = urdf_err(&text);
    assert!(matches!(e.kind, LoadErrorKind::Cycle), "{e:?}");
    assert!(e.to_string().contains("<joint \"j2\">") || e.to_string().contains("<joint \"j3\">"));
    assert!(e.to_string().contains("cycle"));
    // RL: a transform back into the world.
    let e = rl_err(&rl(
        "<body id=\"b\"/>\n<revolute id=\"j\"><frame><a idref=\"w\"/><b idref=\"b\"/></frame></revolute>\n<fixed id=\"back\"><frame><a idref=\"b\"/><b idref=\"w\"/></frame></fixed>",
    ));
    assert!(matches!(e.kind, LoadErrorKind::Cycle));
    names(&e, "5:1: <fixed \"back\">");
}

#[test]
fn a_body_with_two_parents() {
    let text = format!(
        "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><link name=\"c\"/>\n{}\n{}\n{}</robot>",
        revolute("j1", "a", "b"),
        revolute("j2", "a", "c"),
        revolute("j3", "b", "c")
    );
    let e = urdf_err(&text);
    assert!(
        matches!(&e.kind, LoadErrorKind::TwoParents { frame, other } if frame == "c" && other == "j2")
    );
    names(&e, "<joint \"j3\">");
    let e = rl_err(&rl(
        "<body id=\"b\"/><frame id=\"f\"/>\n<fixed id=\"x\"><frame><a idref=\"w\"/><b idref=\"b\"/></frame></fixed>\n<fixed id=\"y\"><frame><a idref=\"f\"/><b idref=\"b\"/></frame></fixed>",
    ));
    assert!(matches!(e.kind, LoadErrorKind::TwoParents { .. }));
    names(&e, "5:1: <fixed \"y\">");
}

#[test]
fn not_exactly_one_root() {
    let e = urdf_err("<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/></robot>");
    assert!(matches!(&e.kind, LoadErrorKind::NoSingleRoot { roots, count: 2 } if roots.len() == 2));
    names(&e, "1:1: <robot \"r\">");
    assert!(e.to_string().contains("several roots (a, b)"), "{e}");
    let e = rl_err("<rlmdl><model><world id=\"w1\"/>\n<world id=\"w2\"/></model></rlmdl>");
    assert!(matches!(e.kind, LoadErrorKind::NoSingleRoot { .. }));
    names(&e, "2:1: <world \"w2\">");
}

#[test]
fn more_than_the_capacity() {
    // Three bodies into a model of two.
    let mut text = "<robot name=\"r\"><link name=\"l0\"/>".to_string();
    for k in 1..=3 {
        text += &format!("<link name=\"l{k}\">{INERTIAL}</link>\n");
        text += &revolute(&format!("j{k}"), &format!("l{}", k - 1), &format!("l{k}"));
    }
    text += "</robot>";
    let e = urdf_err_n::<2>(&text);
    assert!(matches!(
        e.kind,
        LoadErrorKind::Model(ModelError::TooManyBodies { capacity: 2 })
    ));
    names(&e, "<joint \"j3\">");
    assert!(e.to_string().contains("capacity of 2"), "{e}");
    // Seven DOF (six-DOF + revolute) into six.
    let e = rl_err_n::<6>(&rl(
        "<body id=\"a\"/><body id=\"b\"/>\n<sixDof id=\"free\"><frame><a idref=\"w\"/><b idref=\"a\"/></frame></sixDof>\n<revolute id=\"r\"><frame><a idref=\"a\"/><b idref=\"b\"/></frame></revolute>",
    ));
    assert!(matches!(
        e.kind,
        LoadErrorKind::Model(ModelError::TooManyDofs {
            capacity: 6,
            needed: 7
        })
    ));
    names(&e, "5:1: <revolute \"r\">");
    // Two leaves (tools) into one.
    let text = format!(
        "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><link name=\"c\"/>\n{}\n{}</robot>",
        revolute("j1", "a", "b"),
        revolute("j2", "a", "c")
    );
    let e = urdf_err_n::<1>(&text);
    assert!(matches!(
        e.kind,
        LoadErrorKind::Model(ModelError::TooManyBodies { .. } | ModelError::TooManyTools { .. })
    ));
    let e = urdf_err_n::<2>(&text.replace("<link name=\"c\"/>", "<link name=\"c\"/><link name=\"d\"/>").replace("</robot>", "<joint name=\"f\" type=\"fixed\"><parent link=\"c\"/><child link=\"d\"/></joint><link name=\"e\"/><joint name=\"g\" type=\"fixed\"><parent link=\"c\"/><child link=\"e\"/></joint></robot>"));
    assert!(
        matches!(
            e.kind,
            LoadErrorKind::Model(ModelError::TooManyTools { capacity: 2 })
        ),
        "{e:?}"
    );
    assert!(e.to_string().contains("tools"), "{e}");
}

#[test]
fn unsupported_features() {
    // A coupled (mimic) joint, when mimic joints are refused (by default they follow).
    let text = "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><link name=\"c\"/>\n"
        .to_string()
        + &revolute("j1", "a", "b")
        + "\n"
        + &revolute("j2", "b", "c").replace("</joint>", "<mimic joint=\"j1\"/></joint>")
        + "</robot>";
    let refuse = UrdfOptions {
        mimic: loader::MimicJoints::Reject,
        ..UrdfOptions::default()
    };
    let e = loader::load_urdf_str::<N>(&text, &refuse).unwrap_err();
    assert!(matches!(e.kind, LoadErrorKind::Unsupported { .. }));
    names(&e, "4:1: <joint \"j2\">");
    // RL's XSLT-parameterised models and XInclude.
    let xslt =
        r#"<xsl:stylesheet version="1.0" xmlns:xsl="http://www.w3.org/1999/XSL/Transform"/>"#;
    let e = rl_err(xslt);
    assert!(matches!(e.kind, LoadErrorKind::Unsupported { .. }));
    assert!(
        e.to_string().contains("XSLT") && e.to_string().contains("<stylesheet>"),
        "{e}"
    );
    let e = rl_err(
        r#"<rlmdl xmlns:xi="http://www.w3.org/2001/XInclude"><xi:include href="m.xml"/></rlmdl>"#,
    );
    assert!(
        e.to_string().contains("XInclude") && e.to_string().contains("<include>"),
        "{e}"
    );
    // A coupling matrix that is not the identity.
    let e = rl_err(&rl(
        "<body id=\"b\"/><revolute id=\"j\"><frame><a idref=\"w\"/><b idref=\"b\"/></frame></revolute>\n<gammaPosition><row><col>2</col></row></gammaPosition>",
    ));
    assert!(matches!(e.kind, LoadErrorKind::Unsupported { .. }));
    names(&e, "4:1: <gammaPosition>");
    // A helical joint with two different axes; an offset on a spherical joint.
    let e = rl_err(&rl(
        "<body id=\"b\"/>\n<helical id=\"h\"><frame><a idref=\"w\"/><b idref=\"b\"/></frame><axis><x>1</x></axis></helical>",
    ));
    assert!(matches!(e.kind, LoadErrorKind::Unsupported { .. }));
    names(&e, "4:1: <helical \"h\">");
    let e = rl_err(&rl(
        "<body id=\"b\"/><spherical id=\"s\"><frame><a idref=\"w\"/><b idref=\"b\"/></frame>\n<offset>5</offset></spherical>",
    ));
    names(&e, "4:1: <offset>");
}

#[test]
fn unreadable_file_names_the_path() {
    let path = std::env::temp_dir().join("rl-core-loader-test-no-such-file.urdf");
    let e = loader::load_file::<N>(&path).unwrap_err();
    assert!(matches!(
        e.kind,
        LoadErrorKind::File(loader::ReadErrorKind::NotFound)
    ));
    assert!(e.to_string().contains("no-such-file.urdf"), "{e}");
}

#[test]
fn errors_in_a_file_name_the_file_and_line() {
    let path = std::env::temp_dir().join(format!("rl-core-loader-{}.urdf", std::process::id()));
    std::fs::write(
        &path,
        "<robot name=\"r\">\n<link name=\"a\"/>\n<link/>\n</robot>",
    )
    .unwrap();
    let e = loader::load_file::<N>(&path).unwrap_err();
    std::fs::remove_file(&path).ok();
    assert!(matches!(
        e.kind,
        LoadErrorKind::MissingAttribute { attribute: "name" }
    ));
    assert_eq!(e.path.as_deref(), Some(path.as_path()));
    let msg = e.to_string();
    assert!(
        msg.starts_with(&format!("{}:3:1: <link>", path.display())),
        "{msg}"
    );
}

/// Truncated and corrupted versions of every RL example model and of a URDF load or fail with
/// an error: never a panic (a panic fails this test).
#[test]
fn damaged_files_give_errors_not_panics() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/rlmdl");
    let mut texts: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "xml"))
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    texts.push(format!(
        "<robot name=\"r\"><link name=\"a\"/><link name=\"b\">{INERTIAL}</link>\n{}</robot>",
        revolute("j", "a", "b")
    ));
    let replacements = [
        "",
        "1e308",
        "-",
        "\"",
        "<",
        "nan",
        "0 0 0",
        "9999999999999999999999",
    ];
    let (mut ok, mut errors) = (0, 0);
    for text in &texts {
        let cuts = text.char_indices().map(|(i, _)| i).step_by(53);
        for (k, at) in cuts.enumerate() {
            let mut damaged = text[..at].to_string();
            if k % 2 == 1 {
                // Corrupt instead of truncate: replace the next few characters.
                let rest: String = text[at..].chars().skip(3).collect();
                damaged += replacements[k % replacements.len()];
                damaged += &rest;
            }
            match loader::load_str::<64>(&damaged, &UrdfOptions::default()) {
                Ok(_) => ok += 1,
                Err(e) => {
                    assert!(!e.to_string().is_empty());
                    errors += 1;
                }
            }
        }
    }
    println!("{ok} damaged files still loaded, {errors} gave errors");
    assert!(errors > 100);
}
