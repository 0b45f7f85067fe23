//! A failed command never truncates or empties an existing output file (issue 25: a failed
//! `rl traj` emptied a 3 MB CSV): outputs are written beside their destination and moved over
//! it only once complete. Files that cannot be read are bad arguments (exit 2) in every
//! subcommand, and a device given as the output (`/dev/null`) is written in place, never
//! replaced.

use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::process::Command;

fn rl(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rl"))
        .args(args)
        .output()
        .expect("run rl")
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rl-output-files-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn data(p: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(p)
        .to_string_lossy()
        .into_owned()
}

/// The file still holds `content` and nothing was left beside it.
fn untouched(path: &Path, content: &str) {
    assert_eq!(
        std::fs::read_to_string(path).unwrap(),
        content,
        "{}",
        path.display()
    );
    let dir = path.parent().unwrap();
    let left: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".partial"))
        .collect();
    assert!(
        left.is_empty(),
        "partial files left in {}: {left:?}",
        dir.display()
    );
}

/// `rl traj WP --profile quintic --out OUT --plot SVG`.
fn traj(wp: &Path, out: &Path, svg: &Path) -> std::process::Output {
    let path = |p: &Path| p.to_string_lossy().into_owned();
    rl(&[
        "traj",
        &path(wp),
        "--profile",
        "quintic",
        "--out",
        &path(out),
        "--plot",
        &path(svg),
    ])
}

/// Refused with exit code 2 and `needle` in the message; `out` and `svg` as they were.
fn refused_and_untouched(o: &std::process::Output, needle: &str, out: &Path, svg: &Path) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(needle) && !err.contains("writing"), "{err}");
    untouched(out, "t,a\n0,1\n");
    untouched(svg, "<svg/>");
}

#[test]
fn a_failed_traj_leaves_existing_outputs_as_they_were() {
    let d = dir("traj");
    // 13 axes: refused by the sampler, after the output files were opened.
    let header: Vec<String> = (0..13).map(|k| format!("j{k}")).collect();
    let wp = d.join("wp.csv");
    std::fs::write(
        &wp,
        format!(
            "{}\n{}\n{}\n",
            header.join(","),
            ["0"; 13].join(","),
            ["1"; 13].join(",")
        ),
    )
    .unwrap();
    let out = d.join("out.csv");
    let svg = d.join("plot.svg");
    std::fs::write(&out, "t,a\n0,1\n").unwrap();
    std::fs::write(&svg, "<svg/>").unwrap();
    refused_and_untouched(&traj(&wp, &out, &svg), "13 axes", &out, &svg);

    // Waypoints without times for a profile that needs them: refused while sampling into the
    // output, with the sampler's own message, not as a write error.
    std::fs::write(&wp, "a,b\n0,0\n1,-1\n").unwrap();
    refused_and_untouched(&traj(&wp, &out, &svg), "needs times", &out, &svg);

    // The same command with good waypoints replaces both, through a symbolic link too (the
    // link stays a link to the new content).
    std::fs::write(&wp, "t,a,b\n0,0,0\n1,1,-1\n").unwrap();
    let link = d.join("link.csv");
    std::os::unix::fs::symlink(&out, &link).unwrap();
    let o = traj(&wp, &link, &svg);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    let csv = std::fs::read_to_string(&out).unwrap();
    assert!(csv.starts_with("t,") && csv.lines().count() > 10, "{csv}");
    assert!(std::fs::read_to_string(&svg).unwrap().len() > 1000);
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn an_output_that_is_a_device_is_written_in_place() {
    let d = dir("device");
    let wp = d.join("wp.csv");
    std::fs::write(&wp, "t,a,b\n0,0,0\n1,1,-1\n").unwrap();
    let o = rl(&[
        "traj",
        wp.to_str().unwrap(),
        "--profile",
        "quintic",
        "--out",
        "/dev/null",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let null = std::fs::metadata("/dev/null").unwrap();
    assert!(null.file_type().is_char_device(), "/dev/null was replaced");
    assert!(!Path::new("/dev/null.partial").exists());
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn a_plan_that_cannot_read_its_files_exits_2_and_leaves_outputs() {
    let d = dir("plan");
    let out = d.join("path.csv");
    let trajectory = d.join("trajectory.csv");
    std::fs::write(&out, "kept\n").unwrap();
    std::fs::write(&trajectory, "kept too\n").unwrap();
    let missing = d.join("no-such-scene.yaml");
    let o = rl(&[
        "plan",
        &data("mbm/panda/panda_spherized.urdf"),
        "--scene",
        missing.to_str().unwrap(),
        "--request",
        &data("mbm/panda/problems/bookshelf_small_panda/request0001.yaml"),
        "--out",
        out.to_str().unwrap(),
        "--trajectory",
        trajectory.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("no-such-scene.yaml"), "{err}");
    untouched(&out, "kept\n");
    untouched(&trajectory, "kept too\n");

    // A missing robot is a bad argument too.
    let o = rl(&[
        "plan",
        d.join("no-such-robot.urdf").to_str().unwrap(),
        "--scene",
        missing.to_str().unwrap(),
        "--request",
        missing.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("no-such-robot.urdf"), "{err}");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn a_scenario_refuses_the_trajectory_flag_it_cannot_write() {
    let d = dir("scenario");
    let trajectory = d.join("trajectory.csv");
    let o = rl(&[
        "plan",
        &data("rlplan/mitsubishi-rv6sl_boxes_rrtConCon.xml"),
        "--trajectory",
        trajectory.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--trajectory"), "{err}");
    assert!(!trajectory.exists());
    std::fs::remove_dir_all(&d).ok();
}
