//! Loaders in linear time and bounded: generated large files (a 10 000-link chain, a
//! 10 000-child fan, a 2 000-body chain that loads), inputs above the size, depth, node and
//! attribute limits refused with a clear error, errors that print a few names rather than all,
//! and the bounded file reader (devices, FIFOs, large files refused unread). (`scripts/
//! loader-scaling` times the same files at growing sizes.)

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
            ..InputLimits::DEFAULT
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
            LoadErrorKind::File(loader::ReadErrorKind::TooLarge { limit: 1000 })
        ),
        "{e}"
    );
    assert!(e.to_string().contains("big.urdf"), "{e}");
}

#[test]
fn an_element_with_100k_attributes_is_refused_before_it_is_parsed() {
    // The parser compares each new attribute with the element's earlier ones: these 1.1 MB
    // took 22.4 s. The check before parsing refuses them in one pass, naming the element.
    let attributes: String = (0..100_000).map(|k| format!(" a{k}=\"x\"")).collect();
    let text = format!("<robot name=\"r\">\n  <link name=\"a\"{attributes}/>\n</robot>\n");
    assert!(text.len() > 1_000_000);
    let e = loader::load_str_options::<64>(&text, &LoadOptions::default()).unwrap_err();
    assert!(
        matches!(
            e.kind,
            LoadErrorKind::TooLarge {
                what: "number of attributes of one element",
                limit: 256
            }
        ),
        "{e}"
    );
    assert!(e.to_string().starts_with("2:3: <link>"), "{e}");
    // 256 attributes are read (and the limit is the caller's).
    let attributes: String = (0..255).map(|k| format!(" a{k}='x'")).collect();
    let ok = format!("<robot name=\"r\"><link name=\"a\"{attributes}/></robot>");
    loader::load_str_options::<64>(&ok, &LoadOptions::default()).unwrap();
    let strict = LoadOptions {
        input: InputLimits {
            max_attributes: 100,
            ..InputLimits::DEFAULT
        },
        ..LoadOptions::default()
    };
    let e = loader::load_str_options::<64>(&ok, &strict).unwrap_err();
    assert!(
        matches!(e.kind, LoadErrorKind::TooLarge { limit: 100, .. }),
        "{e}"
    );
}

#[test]
fn several_roots_print_the_first_few_and_a_count() {
    // 100 000 links and no joint: each is a root. The message printed all their names
    // (23.9 MB for longer names); now the first five and how many more.
    let links: String = (0..100_000)
        .map(|k| format!("<link name=\"link_with_a_long_name_{k}\"/>"))
        .collect();
    let text = format!("<robot name=\"r\">{links}</robot>");
    let e = loader::load_str_options::<64>(&text, &LoadOptions::default()).unwrap_err();
    let LoadErrorKind::NoSingleRoot { roots, count } = &e.kind else {
        panic!("{e}")
    };
    assert_eq!((roots.len(), *count), (5, 100_000));
    let msg = e.to_string();
    assert!(msg.len() < 400, "{} bytes: {msg}", msg.len());
    assert!(
        msg.contains("several roots (link_with_a_long_name_0, link_with_a_long_name_1, ")
            && msg.contains("link_with_a_long_name_4 and 99995 more)"),
        "{msg}"
    );
    // A name of a megabyte is cut in messages too.
    let long = "x".repeat(1 << 20);
    let text = format!("<robot name=\"r\"><link name=\"{long}\"/><link name=\"{long}\"/></robot>");
    let msg = loader::load_str_options::<64>(&text, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        msg.len() < 400 && msg.contains("(1048576 bytes in all)"),
        "{msg}"
    );
}

#[test]
fn a_file_on_one_line_loads_in_linear_time() {
    // Elements' columns were counted from the start of their line: a URDF written on one line
    // (as generators do) was quadratic in its size (9 s for 100 000 links). A scaling check,
    // not a timed one: 4× the links may take at most 10× the time (linear is 4×, the old count
    // 19×). Sizes alternate and the best of five counts for each.
    let texts = [
        urdf(5_000, false).replace('\n', ""),
        urdf(20_000, false).replace('\n', ""),
    ];
    let mut best = [std::time::Duration::MAX; 2];
    for _ in 0..5 {
        for (k, text) in texts.iter().enumerate() {
            let t = std::time::Instant::now();
            let e = loader::load_urdf_str::<64>(text, &UrdfOptions::default()).unwrap_err();
            best[k] = best[k].min(t.elapsed());
            assert!(matches!(e.kind, LoadErrorKind::Model(_)), "{e}");
        }
    }
    let ratio = best[1].as_secs_f64() / best[0].as_secs_f64();
    println!(
        "5 000 links {:?}, 20 000 links {:?}: ratio {ratio:.1}",
        best[0], best[1]
    );
    assert!(ratio < 10.0, "4× the links took {ratio:.1}× the time");
}

/// Runs `f` on a thread and fails if it has not returned within 20 s (a reader that blocks on
/// a FIFO must fail the test, not hang it).
fn within<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(std::time::Duration::from_secs(20))
        .expect("the reader returned (it did not block)")
}

#[test]
fn the_reader_refuses_devices_fifos_and_large_files_unread() {
    use loader::ReadErrorKind;
    use std::path::PathBuf;
    let dir = std::env::temp_dir().join(format!("rl-core-reader-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let max = InputLimits::DEFAULT.max_bytes;

    // /dev/zero never ends: reading it first grew `rl model info` to 8.8 GB. It is refused
    // without being opened, and so is a link to it.
    let not_regular = |file_type| LoadErrorKind::File(ReadErrorKind::NotRegular { file_type });
    let e = loader::load_file::<64>("/dev/zero").unwrap_err();
    assert_eq!(e.kind, not_regular("a character device"), "{e}");
    assert!(
        e.to_string().starts_with("/dev/zero: a character device"),
        "{e}"
    );
    let link = dir.join("zero.urdf");
    std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
    let e = loader::read_bytes(&link, max).unwrap_err();
    assert!(matches!(e.kind, ReadErrorKind::NotRegular { .. }), "{e}");
    assert_eq!(e.path, link);

    // A FIFO: opening it for reading waits for a writer (forever).
    let fifo = dir.join("model.urdf");
    if std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success())
    {
        let f = fifo.clone();
        let e = within(move || loader::load_file::<64>(&f).unwrap_err());
        assert_eq!(e.kind, not_regular("a FIFO (named pipe)"), "{e}");
    } else {
        println!("SKIPPED (FIFO case only): mkfifo is not available");
    }

    // A directory, a missing file, a file over the limit, not UTF-8.
    let e = loader::read_text(&dir, max).unwrap_err();
    assert_eq!(
        e.kind,
        ReadErrorKind::NotRegular {
            file_type: "a directory"
        }
    );
    let e = loader::read_text(&dir.join("missing.urdf"), max).unwrap_err();
    assert_eq!(e.kind, ReadErrorKind::NotFound);
    let big: PathBuf = dir.join("big.urdf");
    std::fs::write(&big, vec![b' '; 1001]).unwrap();
    let e = loader::read_bytes(&big, 1000).unwrap_err();
    assert_eq!(e.kind, ReadErrorKind::TooLarge { limit: 1000 });
    assert_eq!(loader::read_bytes(&big, 1001).unwrap().len(), 1001);
    std::fs::write(&big, [b'a', 0xff, b'b']).unwrap();
    assert_eq!(
        loader::read_text(&big, max).unwrap_err().kind,
        ReadErrorKind::NotUtf8 { byte: 1 }
    );

    // A regular file that reports no size (/proc) is read, and cut off at the limit.
    let status = loader::read_text(std::path::Path::new("/proc/self/status"), max).unwrap();
    assert!(status.contains("VmRSS"), "{status}");
    let e = loader::read_text(std::path::Path::new("/proc/self/status"), 10).unwrap_err();
    assert_eq!(e.kind, ReadErrorKind::TooLarge { limit: 10 });
    let _ = std::fs::remove_dir_all(&dir);
}
