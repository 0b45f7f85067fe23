//! The real-time hook: `Publisher::publish` hands joint positions to the viewer through rl-rt's
//! lock-free mailbox without allocating (counted by rl-testkit's allocator), and the page shows
//! the newest of them.

mod support;

use rl_view::PublishError;
use support::*;

#[global_allocator]
static GLOBAL: rl_testkit::CountingAllocator = rl_testkit::CountingAllocator;

#[test]
fn publish_allocates_nothing_and_reaches_the_page() {
    let v = start(vec![puma(), ur5()]);
    let (mut page, _) = Page::connect(v.http_addr());
    let mut publisher = v.publisher();
    let mut q = [0.0; 6];
    let (allocations, results) = rl_testkit::allocations(|| {
        let mut ok = 0;
        for k in 0..10_000 {
            q[0] = k as f64 * 1e-4;
            q[5] = -q[0];
            if publisher.publish(0, &q).is_ok() {
                ok += 1;
            }
            std::hint::black_box(&q);
        }
        let unknown = publisher.publish(2, &q);
        let short = publisher.publish(1, &q[..2]);
        (ok, unknown, short)
    });
    assert_eq!(allocations, 0, "publish allocated");
    assert_eq!(results.0, 10_000);
    assert_eq!(results.1, Err(PublishError::UnknownModel { model: 2 }));
    assert_eq!(
        results.2,
        Err(PublishError::Dimension {
            expected: 6,
            got: 2
        })
    );
    // The page gets the newest values, marked as coming from a live loop.
    let s = page.wait_state(|s| {
        let q0 = floats(&s["models"][0]["q"]);
        (q0[0] - 0.9999).abs() < 1e-12 && (q0[5] + 0.9999).abs() < 1e-12
    });
    assert_eq!(s["models"][0]["source"], "live");
    assert!(
        publisher.overwritten(0).unwrap() > 0,
        "older frames are overwritten, counted"
    );
}

#[test]
fn publish_commanded_allocates_nothing_and_the_page_gets_q_cmd() {
    let v = start(vec![puma()]);
    let (mut page, hello) = Page::connect(v.http_addr());
    assert!(
        hello["state"]["models"][0]["q_cmd"].is_null(),
        "no commanded positions before a controller sends them"
    );
    let mut publisher = v.publisher();
    let mut q = [0.0; 6];
    let mut q_cmd = [0.0; 6];
    let (allocations, results) = rl_testkit::allocations(|| {
        let mut ok = 0;
        for k in 0..10_000 {
            q_cmd[1] = k as f64 * 1e-4;
            q[1] = q_cmd[1] - 0.01;
            if publisher.publish_commanded(0, &q, &q_cmd).is_ok() {
                ok += 1;
            }
            std::hint::black_box((&q, &q_cmd));
        }
        let short = publisher.publish_commanded(0, &q, &q_cmd[..3]);
        (ok, short)
    });
    assert_eq!(allocations, 0, "publish_commanded allocated");
    assert_eq!(results.0, 10_000);
    assert_eq!(
        results.1,
        Err(PublishError::Dimension {
            expected: 6,
            got: 3
        })
    );
    let s = page.wait_state(|s| {
        let c = floats(&s["models"][0]["q_cmd"]);
        c.len() == 6 && (c[1] - 0.9999).abs() < 1e-12
    });
    let m = &s["models"][0];
    assert_eq!(m["source"], "live");
    let (q, c) = (floats(&m["q"]), floats(&m["q_cmd"]));
    assert!(((c[1] - q[1]) - 0.01).abs() < 1e-12, "q {q:?}, q_cmd {c:?}");
    // A joint update without a command (here: the page's own `set_q`) clears q_cmd: the
    // state never pairs a q with a command that was not given for it.
    page.send(
        serde_json::json!({"type": "set_q", "model": 0, "q": [0.1, 0.0, 0.0, 0.0, 0.0, 0.0]}),
    );
    let s = page.wait_state(|s| s["models"][0]["source"] == "ui");
    assert!(s["models"][0]["q_cmd"].is_null(), "{}", s["models"][0]);
}
