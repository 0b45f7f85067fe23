//! The machine-readable outputs parse as JSON and carry the documented keys and values.

use rl_rt::{LoopStats, preflight};

#[test]
fn loop_stats_json_parses_with_documented_keys() {
    let mut s = LoopStats::new(1_000_000, 100);
    for ns in [12_345, 20_000, 150_000] {
        s.record_cycle(ns, 800);
    }
    s.overruns = 1;
    let v: serde_json::Value = serde_json::from_str(&s.to_json()).expect("valid JSON");
    assert_eq!(v["cycles"], 3);
    assert_eq!(v["overruns"], 1);
    assert_eq!(v["period_ns"], 1_000_000);
    let w = &v["wakeup"];
    assert_eq!(w["min_us"].as_f64(), Some(12.345));
    assert_eq!(w["max_us"].as_f64(), Some(150.0));
    assert_eq!(w["overflow"], 1, "150 µs is beyond a 100 µs range");
    for key in ["mean_us", "p50_us", "p99_us", "p999_us", "p9999_us"] {
        assert!(w[key].is_f64(), "{key} missing");
    }
    assert_eq!(v["step"]["count"], 3);
}

#[test]
fn preflight_json_parses_and_every_warning_has_a_fix() {
    let report = preflight::check();
    let v: serde_json::Value = serde_json::from_str(&report.to_json()).expect("valid JSON");
    let items = v.as_array().expect("an array");
    assert_eq!(items.len(), report.items.len());
    for item in items {
        let status = item["status"].as_str().expect("status");
        assert!(["ok", "info", "warn", "FAIL"].contains(&status), "{status}");
        if status == "warn" || status == "FAIL" {
            assert!(item["fix"].is_string(), "{item}");
        }
    }
}
