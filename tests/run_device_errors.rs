//! The errors a user meets first with `rl run --device`, said in words and with what to do:
//! no CAN sockets in this kernel (not "os error 97"), nothing listening at an H7 or Coach
//! address (the address, and the fake to start), nobody on a CAN bus, no EtherCAT device on an
//! interface. Each run fails before anything moves, with exit code 1.

use std::process::Command;

fn rl_run(device: &str) -> (Option<i32>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_rl"))
        .args(["run", "--device", device, "--duration", "1s"])
        .output()
        .expect("rl run");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A TCP port on 127.0.0.1 where nothing listens (bound, then freed).
fn closed_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port()
}

#[test]
fn socketcan_without_af_can_says_so() {
    let (code, err) = rl_run("socketcan://can0");
    assert_eq!(code, Some(1), "{err}");
    if err.contains("no CAN sockets") {
        assert!(
            err.contains("AF_CAN") && err.contains("modprobe can-raw"),
            "{err}"
        );
        assert!(!err.contains("os error 97"), "{err}");
    } else {
        // A kernel with CAN sockets but no can0.
        assert!(
            err.contains("no interface `can0`") || err.contains("`can0`"),
            "{err}"
        );
    }
}

#[test]
fn an_h7_address_where_nothing_listens_names_it_and_the_fake_to_start() {
    let (udp, r3) = (closed_port(), closed_port());
    let (code, err) = rl_run(&format!("h7://127.0.0.1:{udp}?r3={r3}"));
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains(&format!("no H7 controller listens at 127.0.0.1:{r3}")),
        "{err}"
    );
    assert!(
        err.contains(&format!(
            "rl fake-robot h7 --bind 127.0.0.1:{udp} --r3-bind 127.0.0.1:{r3}"
        )),
        "{err}"
    );
}

#[test]
fn a_coach_address_where_nothing_listens_names_it() {
    let port = closed_port();
    let (code, err) = rl_run(&format!("coach://127.0.0.1:{port}"));
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains(&format!("no Coach server listens at 127.0.0.1:{port}")),
        "{err}"
    );
}

#[test]
fn a_can_bus_where_no_drive_answers_says_so() {
    let port = closed_port();
    let (code, err) = rl_run(&format!("cannelloni+udp://127.0.0.1:{port}?nodes=1-6"));
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains(&format!(
            "no drive answers on cannelloni+udp://127.0.0.1:{port}"
        )) && err.contains("rl fake-robot canopen"),
        "{err}"
    );
}

#[test]
fn an_interface_without_ethercat_devices_says_so() {
    let (code, err) = rl_run("ethercat://lo");
    assert_eq!(code, Some(1), "{err}");
    if err.contains("CAP_NET_RAW") {
        println!("SKIPPED: not root, raw sockets refused: {err}");
        return;
    }
    assert!(err.contains("no EtherCAT device answers on `lo`"), "{err}");
}

#[test]
fn lost_reply_bounds_and_units_are_checked_before_anything_starts() {
    for (args, what) in [
        (&["--rest-after-lost", "0"][..], "--rest-after-lost 0"),
        (
            &["--rest-after-lost", "5", "--stop-after-lost", "4"],
            "--rest-after-lost 5",
        ),
        (
            &["--units", "cpr:4096,gear:121"],
            "--units: only CiA 402 drives",
        ),
        (&["--units", "gear:121"], "`cpr` and `gear` go together"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_rl"))
            .arg("run")
            .args(args)
            .output()
            .expect("rl run");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(what), "{args:?}: {err}");
    }
}
