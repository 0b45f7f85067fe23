//! Loaders in linear time and bounded: generated large files (a 10 000-link chain, a
//! 10 000-child fan, a 2 000-body chain that loads), and inputs above the size, depth and node
//! limits refused with a clear error. (`scripts/loader-scaling` times the same files at
//! growing sizes.)

use rl_core::loader::{self, InputLimits, LoadErrorKind, LoadOptions, UrdfOptions};
use rl_core::model::ModelError;

const INERTIAL: &str = r#"<inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>"#;

/// A chain of `n` links on revolute joints (`fan`: all hanging from the root instead).
fn urdf(n: usize, fan: bool) -> String {
    let mut s = String::with_capacity(n * 400);
    s.push_str("<robot name=\"big\">\n<link name=\"l0\"/>\n");
    for k in 1..=n {
        let parent = if fan { 0 } else { k - 1 };
        s.push_str(&format!(
            "<link name=\"l{k}\">{INERTIAL}</link>\n<joint name=\"j{k}\" type=\"revolute\">\
             <parent link=\"l{parent}\"/><child link=\"l{k}\"/><origin xyz=\"0 0 0.1\"/>\
             <axis xyz=\"0 1 0\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>\
             </joint>\n"
        ));
    }
    s.push_str("</robot>\n");
    s
}

#[test]
fn a_ten_thousand_link_chain_fails_with_the_capacity_error() {
    let text = urdf(10_000, false);
    let e = loader::load_urdf_str::<64>(&text, &UrdfOptions::default()).unwrap_err();
    assert!(
        matches!(
            e.kind,
            LoadErrorKind::Model(ModelError::TooManyBodies { capacity: 64 })
        ),
        "{e}"
    );
    assert!(e.to_string().contains("<joint \"j65\">"), "{e}");
    // A fan of 10 000 joints under one link (sorted by name for Pinocchio's order).
    let text = urdf(10_000, true);
    let options = UrdfOptions {
        joint_order: loader::JointOrder::Pinocchio,
        ..UrdfOptions::default()
    };
    let e = loader::load_urdf_str::<64>(&text, &options).unwrap_err();
    assert!(matches!(
        e.kind,
        LoadErrorKind::Model(ModelError::TooManyBodies { .. })
    ));
}

#[test]
fn a_two_thousand_body_chain_loads() {
    // Model<2048> is a large value: load it on a thread with room on its stack.
    std::thread::Builder::new()
        .stack_size(256 << 20)
        .spawn(|| {
            let text = urdf(2_000, false);
            let m = loader::load_urdf_str::<2048>(&text, &UrdfOptions::default())
                .unwrap_or_else(|e| panic!("{e}"));
            assert_eq!((m.model.dof(), m.model.body_count()), (2000, 2000));
            assert_eq!(m.model.tools().len(), 1);
            assert_eq!(m.model.joint_name(1999), "j2000");
        })
        .unwrap()
        .join()
        .unwrap();
}

fn limited(max_bytes: u64, max_depth: usize, max_nodes: u32) -> LoadOptions {
    LoadOptions {
        input: InputLimits {
            max_bytes,
            max_depth,
            max_nodes,
        },
        ..LoadOptions::default()
    }
}

#[test]
fn input_above_the_size_depth_and_node_limits_is_refused() {
    let text = urdf(20, false);
    let e = loader::load_str_options::<64>(&text, &limited(1000, 256, 1_000_000)).unwrap_err();
    assert!(
        matches!(e.kind, LoadErrorKind::TooLarge { limit: 1000, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("limit of 1000"), "{e}");
    let e = loader::load_str_options::<64>(&text, &limited(1 << 20, 256, 50)).unwrap_err();
    assert!(
        matches!(
            e.kind,
            LoadErrorKind::TooLarge {
                what: "number of XML nodes",
                ..
            }
        ),
        "{e}"
    );
    // 300 nested elements, refused at the 257th, named with its line and column.
    let mut deep = String::from("<robot name=\"deep\">\n");
    for _ in 0..300 {
        deep.push_str("<a>");
    }
    for _ in 0..300 {
        deep.push_str("</a>");
    }
    deep.push_str("</robot>");
    let e = loader::load_str_options::<64>(&deep, &LoadOptions::default()).unwrap_err();
    assert!(
        matches!(
            e.kind,
            LoadErrorKind::TooLarge {
                what: "nesting depth",
                limit: 256
            }
        ),
        "{e}"
    );
    let msg = e.to_string();
    assert!(msg.contains("2:766: <a>"), "{msg}"); // 255 × "<a>" before it on line 2
    // Comments, CDATA, quoted '>' and self-closing elements do not count as nesting.
    let tricky = "<robot name=\"t\"><!-- <a><a><a> --><![CDATA[<a><a>]]>\
                  <link name=\"x>y\"/><?pi <a> ?></robot>";
    let m = loader::load_str_options::<4>(tricky, &limited(1 << 20, 2, 1000)).unwrap();
    assert_eq!(m.model.dof(), 0);
    // A file above the size limit is refused before it is read.
    let dir = std::env::temp_dir().join(format!("rl-loader-limits-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("big.urdf");
    std::fs::write(&path, &text).unwrap();
    let e = loader::load_file_options::<64>(&path, &limited(1000, 256, 1_000_000)).unwrap_err();
    assert!(
        matches!(
            e.kind,
            LoadErrorKind::TooLarge {
                what: "file size",
                limit: 1000
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("big.urdf"), "{e}");
}
