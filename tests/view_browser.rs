//! `rl view`'s page in a real browser: runs `rl-view/web/test/browser.mjs` (playwright-core
//! driving Debian's headless Chromium, WebGL on SwiftShader) against this build's `rl`. The
//! script loads the page for ur5 (URDF) and an RL XML model, moves the robot with Coach joint
//! commands, a slider and the IK target, checks collisions drawn red, the distance label and
//! the reconnect after a server restart, the default robot's visual meshes all loaded, a value
//! beyond a joint's limit and a Coach error (cleared by a good line) shown, an RL scenario's
//! start and goal ghosts and tool trail before and while its planned path plays, and the page
//! saying how an `rl run --view` run ended; and measures screenshot differences (see the
//! script's head). Screenshots go to `target/view-screenshots/`.
//!
//! Prints `SKIPPED:` and passes when node, the npm packages (`rl-view/web/node_modules`, from
//! `npm ci`) or Chromium (`/usr/bin/chromium`, or `$RL_CHROMIUM`) are missing: scripts/test
//! installs them.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The script has its own 360 s watchdog; this bounds the wait if node itself hangs.
const DEADLINE: Duration = Duration::from_secs(420);

fn missing_tool() -> Option<String> {
    let web = Path::new(env!("CARGO_MANIFEST_DIR")).join("rl-view/web");
    let node_ok = Command::new("node")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !node_ok {
        return Some("node is not installed (Debian package nodejs)".into());
    }
    if !web.join("node_modules/playwright-core").is_dir() {
        return Some("rl-view/web/node_modules is missing (scripts/test runs npm ci there)".into());
    }
    let chromium = chromium();
    if !chromium.is_file() {
        return Some(format!(
            "{} is missing (Debian package chromium)",
            chromium.display()
        ));
    }
    None
}

fn chromium() -> PathBuf {
    std::env::var_os("RL_CHROMIUM")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/usr/bin/chromium"))
}

fn drain(mut r: impl Read + Send + 'static) -> std::thread::JoinHandle<String> {
    std::thread::spawn(move || {
        let mut s = String::new();
        let _ = r.read_to_string(&mut s);
        s
    })
}

#[test]
fn page_in_headless_chromium() {
    if let Some(reason) = missing_tool() {
        println!("SKIPPED: {reason}");
        return;
    }
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let rl = Path::new(env!("CARGO_BIN_EXE_rl"));
    // target/<profile>/rl -> target/view-screenshots
    let out = rl
        .parent()
        .and_then(Path::parent)
        .map(|t| t.join("view-screenshots"))
        .unwrap_or_else(|| repo.join("target/view-screenshots"));
    let mut child = Command::new("node")
        .arg(repo.join("rl-view/web/test/browser.mjs"))
        .arg("--rl")
        .arg(rl)
        .arg("--out")
        .arg(&out)
        .arg("--chromium")
        .arg(chromium())
        .current_dir(repo)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start node");
    let stdout = drain(child.stdout.take().expect("piped"));
    let stderr = drain(child.stderr.take().expect("piped"));
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait for node") {
            break Some(s);
        }
        if start.elapsed() > DEADLINE {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    let (stdout, stderr) = (stdout.join().unwrap(), stderr.join().unwrap());
    println!("{stdout}");
    eprintln!("{stderr}");
    let status = status.unwrap_or_else(|| panic!("the browser test ran past {DEADLINE:?}"));
    assert!(
        status.success(),
        "the browser test failed ({status}):\n{stdout}\n{stderr}"
    );
    assert!(
        stdout.contains(" passed, 0 failed"),
        "the browser test did not report its checks:\n{stdout}"
    );
}
