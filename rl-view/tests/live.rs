//! The live side: pages over the WebSocket, Coach clients over TCP (RL's lines on a raw
//! socket), and the state they share.

mod support;

use serde_json::json;
use support::*;

fn q_of(state: &serde_json::Value, m: usize) -> Vec<f64> {
    floats(&state["models"][m]["q"])
}

fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

#[test]
fn coach_joint_lines_move_the_model_in_the_page() {
    let v = start(vec![ur5()]);
    let (mut page, hello) = Page::connect(v.http_addr());
    assert_eq!(hello["scene"]["version"], 1);
    let nq = hello["scene"]["models"][0]["joints"]
        .as_array()
        .unwrap()
        .len();
    assert_eq!(nq, 6);
    let before = bodies(&hello["state"], 0);
    assert_eq!(
        before.len(),
        hello["scene"]["models"][0]["bodies"]
            .as_array()
            .unwrap()
            .len()
    );

    let mut coach = Coach::connect(v.coach_addr().unwrap());
    let q = [0.1, -1.0, 1.2, 0.3, 0.4, 0.5];
    coach.send("2 0 0.1 -1 1.2 0.3 0.4 0.5\n");
    let s = page.wait_state(|s| close(&q_of(s, 0), &q, 1e-12));
    assert_eq!(s["models"][0]["source"], "coach");
    let after = bodies(&s, 0);
    assert!(max_diff(&before, &after) > 0.05, "bodies moved");
    assert_eq!(s["coach"]["clients"], 1);

    // `6 <i>`: the joint positions, RL's %g format; an unknown model: `6 <i>` alone.
    coach.send("6 0\n");
    assert_eq!(coach.read_line(), "6 0 0.1 -1 1.2 0.3 0.4 0.5");
    coach.send("6 7\n");
    assert_eq!(coach.read_line(), "6 7");

    // A body pose (`0`) overrides the body until the next joint line.
    coach.send("0 0 1 1 2 3 0 0 0\n");
    let s = page.wait_state(|s| {
        let b = bodies(s, 0);
        close(&b[1][..3], &[1.0, 2.0, 3.0], 1e-12)
    });
    assert!(close(&bodies(&s, 0)[1][3..], &[0.0, 0.0, 0.0, 1.0], 1e-12));
    coach.send("2 0 0.1 -1 1.2 0.3 0.4 0.6\n");
    page.wait_state(|s| {
        (q_of(s, 0)[5] - 0.6).abs() < 1e-12 && !close(&bodies(s, 0)[1][..3], &[1.0, 2.0, 3.0], 1e-9)
    });
}

#[test]
fn bad_coach_lines_are_counted_and_reported() {
    let v = start(vec![ur5()]);
    let (mut page, hello) = Page::connect(v.http_addr());
    let q0 = q_of(&hello["state"], 0);
    let mut coach = Coach::connect(v.coach_addr().unwrap());
    let long = format!("2 0 {}\n", "1 ".repeat(20_000));
    let bad = [
        "2 0 1 2\n",            // wrong count: ignored, as rlCoachMdl does, and counted
        "2 0 nan 0 0 0 0 0\n",  // not finite
        "2 0 1 x 0 0 0 0\n",    // not a number
        "9 1 2\n",              // unknown command
        "2 5 0 0 0 0 0 0\n",    // unknown model
        "0 0 99 0 0 0 0 0 0\n", // unknown body
        long.as_str(),          // longer than the line limit
    ];
    for line in bad {
        coach.send(line);
    }
    let s = page.wait_state(|s| s["coach"]["rejected"] == bad.len());
    assert!(close(&q_of(&s, 0), &q0, 0.0), "bad lines moved nothing");
    let last = s["coach"]["last_error"].as_str().unwrap();
    assert!(last.contains("longer"), "{last}");
    // Still answering; a good line clears the error shown (the count stays).
    coach.send("6 0\n");
    let reply = coach.read_line();
    assert!(reply.starts_with("6 0 "), "{reply}");
    let s = page.wait_state(|s| s["coach"]["lines"] == bad.len() + 1);
    assert_eq!(s["coach"]["rejected"], bad.len());
    assert!(s["coach"]["last_error"].is_null(), "{}", s["coach"]);
    // Each reason is reported in turn.
    let mut c2 = Coach::connect(v.coach_addr().unwrap());
    c2.send("2 0 1 2\n");
    let s = page.wait_state(|s| s["coach"]["rejected"] == bad.len() + 1);
    let last = s["coach"]["last_error"].as_str().unwrap();
    assert!(last.contains("6 joints, 2 values"), "{last}");
    c2.send("2 0 inf 0 0 0 0 0\n");
    let s = page.wait_state(|s| s["coach"]["rejected"] == bad.len() + 2);
    assert!(
        s["coach"]["last_error"]
            .as_str()
            .unwrap()
            .contains("not a finite"),
        "{}",
        s["coach"]["last_error"]
    );
    c2.send("2 0 0.1 0.2 0.3 0.4 0.5 0.6\n");
    let s = page.wait_state(|s| close(&q_of(s, 0), &[0.1, 0.2, 0.3, 0.4, 0.5, 0.6], 1e-12));
    assert!(s["coach"]["last_error"].is_null(), "{}", s["coach"]);
    assert_eq!(s["coach"]["rejected"], bad.len() + 2);
}

#[test]
fn page_messages() {
    let v = start(vec![ur5()]);
    let (mut page, hello) = Page::connect(v.http_addr());
    let before = bodies(&hello["state"], 0);
    let q = [0.5, -0.5, 0.5, -0.5, 0.5, -0.5];
    page.send(json!({"type": "set_q", "model": 0, "q": q}));
    let s = page.wait_state(|s| close(&q_of(s, 0), &q, 1e-12));
    assert_eq!(s["models"][0]["source"], "ui");
    assert!(max_diff(&before, &bodies(&s, 0)) > 0.05);
    page.send(json!({"type": "set_q", "model": 0, "q": vec![0.0; 6], "source": "path"}));
    let s = page.wait_state(|s| close(&q_of(s, 0), &[0.0; 6], 0.0));
    assert_eq!(s["models"][0]["source"], "path");

    page.send(json!({"type": "ping"}));
    page.wait_for(|m| m["type"] == "pong");
    for bad in [
        json!({"type": "set_q", "model": 0, "q": [1.0, 2.0]}),
        json!({"type": "set_q", "model": 3, "q": q}),
        json!({"type": "set_q", "model": 0, "q": [0, 0, 0, 0, 0, "x"]}),
        json!({"type": "ik", "model": 0, "target": [0.0, 0.0]}),
        json!({"type": "fly"}),
        json!({"no": "type"}),
    ] {
        page.send(bad.clone());
        let e = page.wait_for(|m| m["type"] == "error");
        assert!(
            e["message"].as_str().is_some_and(|m| !m.is_empty()),
            "{bad}"
        );
    }
    page.ws
        .send(tungstenite::Message::text("{not json"))
        .unwrap();
    page.wait_for(|m| m["type"] == "error");
    let s = page.wait_state(|s| s["page_errors"] == 7);
    assert!(close(&q_of(&s, 0), &[0.0; 6], 0.0), "errors moved nothing");
}

#[test]
fn two_pages_get_every_update() {
    let v = start(vec![ur5(), puma()]);
    let (mut a, _) = Page::connect(v.http_addr());
    let (mut b, hello) = Page::connect(v.http_addr());
    assert_eq!(hello["scene"]["models"].as_array().unwrap().len(), 2);
    let mut coach = Coach::connect(v.coach_addr().unwrap());
    coach.send("2 1 0.1 0.2 0.3 0.4 0.5 0.6\n");
    let q = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6];
    for p in [&mut a, &mut b] {
        let s = p.wait_state(|s| close(&q_of(s, 1), &q, 1e-12));
        assert_eq!(s["models"][1]["source"], "coach");
    }
    // A change from one page reaches the other.
    a.send(json!({"type": "set_q", "model": 0, "q": vec![0.2; 6]}));
    b.wait_state(|s| close(&q_of(s, 0), &[0.2; 6], 1e-12));
    assert_eq!(v.pages(), 2);
}

#[test]
fn a_page_reconnecting_after_a_restart_gets_the_current_state() {
    let v = start(vec![ur5()]);
    let port = v.http_addr();
    let (mut page, _) = Page::connect(port);
    drop(v);
    // The page sees its connection end.
    let end = std::time::Instant::now() + WAIT;
    loop {
        match page.ws.read() {
            Ok(_) => {}
            Err(tungstenite::Error::Io(e))
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            Err(_) => break,
        }
        assert!(
            std::time::Instant::now() < end,
            "the connection did not end"
        );
    }
    // A new server with the same models on the same address; a controller moves the robot
    // before the page is back.
    let mut o = options(vec![ur5()]);
    o.http = port;
    let v = rl_view::Viewer::start(&o).expect("restart on the same port");
    let mut coach = Coach::connect(v.coach_addr().unwrap());
    coach.send("2 0 0.3 0.3 0.3 0.3 0.3 0.3\n6 0\n");
    assert_eq!(coach.read_line(), "6 0 0.3 0.3 0.3 0.3 0.3 0.3");
    let (_page, hello) = Page::connect(port);
    assert!(close(&q_of(&hello["state"], 0), &[0.3; 6], 1e-12));
    assert_eq!(hello["state"]["models"][0]["source"], "coach");
}

/// rl-drivers' Coach device (what `rl run --device coach://…` uses) against the viewer: every
/// step's reply is the configuration it sent, and the page follows.
#[test]
fn the_coach_device_of_rl_drivers_drives_the_viewer() {
    use rl_drivers::coach::{Coach as CoachDevice, CoachConfig};
    use rl_drivers::{CyclicDevice, Device, JointPositionActuator, JointPositionSensor};

    let v = start(vec![ur5()]);
    let (mut page, _) = Page::connect(v.http_addr());
    let mut config = CoachConfig::new(6);
    config.server = v.coach_addr().unwrap();
    config.reply_timeout = std::time::Duration::from_secs(2);
    let mut coach = CoachDevice::new(config).unwrap();
    coach.open().unwrap();
    coach.start().unwrap();
    let mut got = [0.0; 6];
    let mut q = [0.0; 6];
    for k in 0..50 {
        q = core::array::from_fn(|i| 0.01 * k as f64 * (i as f64 - 2.5));
        coach.set_joint_position(&q).unwrap();
        coach.step().unwrap_or_else(|e| panic!("cycle {k}: {e}"));
        coach.joint_position(&mut got).unwrap();
        assert!(close(&got, &q, 1e-5), "cycle {k}: {got:?} vs {q:?}");
    }
    let s = page.wait_state(|s| close(&q_of(s, 0), &q, 1e-5));
    assert_eq!(s["models"][0]["source"], "coach");
    assert_eq!(s["coach"]["rejected"], 0);
}
