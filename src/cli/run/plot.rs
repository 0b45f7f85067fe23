//! `--plot`: joint tracking and the wake-up latency histogram on one SVG page.

use std::fmt::Write as _;
use std::path::Path;

use plotters::prelude::*;
use rl::controller::CycleRecord;
use rl::controller::report::RunReport;

/// Draws positions (commanded thin, measured thick), tracking error per joint, and the
/// latency histogram (log counts) into `path`.
pub fn draw<const J: usize>(
    path: &Path,
    report: &RunReport,
    rows: &[CycleRecord<J>],
) -> Result<(), String> {
    let e = |e: &dyn std::fmt::Display| e.to_string();
    let root = SVGBackend::new(path, (1200, 1100)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let (top, rest) = root.split_vertically(420);
    let (middle, bottom) = rest.split_vertically(340);
    let dof = report.joints.len();
    let t_end = rows.last().map_or(1.0, |r| r.time_s).max(1e-3);
    let colour = |k: usize| Palette99::pick(k).to_rgba();

    // Joint positions.
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for r in rows {
        for k in 0..dof {
            lo = lo.min(r.commanded[k]).min(r.measured[k]);
            hi = hi.max(r.commanded[k]).max(r.measured[k]);
        }
    }
    if !lo.is_finite() || !hi.is_finite() || lo >= hi {
        (lo, hi) = (-1.0, 1.0);
    }
    let pad = 0.05 * (hi - lo);
    let mut chart = ChartBuilder::on(&top)
        .caption(
            format!(
                "{}: commanded (thin) and measured (thick) joints",
                report.model
            ),
            ("sans-serif", 20),
        )
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t_end, (lo - pad)..(hi + pad))
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_desc("trajectory time [s]")
        .y_desc("position [rad]")
        .draw()
        .map_err(|x| e(&x))?;
    for k in 0..dof {
        let c = colour(k);
        chart
            .draw_series(LineSeries::new(
                rows.iter().map(|r| (r.time_s, r.measured[k])),
                c.stroke_width(3),
            ))
            .map_err(|x| e(&x))?
            .label(report.joints[k].clone())
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], c.stroke_width(3)));
        chart
            .draw_series(LineSeries::new(
                rows.iter().map(|r| (r.time_s, r.commanded[k])),
                BLACK.mix(0.6).stroke_width(1),
            ))
            .map_err(|x| e(&x))?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|x| e(&x))?;

    // Tracking error: solid where the report's statistics count it (fresh replies up to the
    // first fault), faded elsewhere; the fault marked; each joint's bound where it fits.
    let panel = ErrorPanel::new(report, rows);
    let mut chart = ChartBuilder::on(&middle)
        .caption(panel.caption(report), ("sans-serif", 20))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t_end, (-1.05 * panel.y_max)..(1.05 * panel.y_max))
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_desc("trajectory time [s]")
        .y_desc("error [mrad]")
        .draw()
        .map_err(|x| e(&x))?;
    for k in 0..dof {
        let c = colour(k);
        let error = |r: &CycleRecord<J>| (r.time_s, (r.commanded[k] - r.measured[k]) * 1e3);
        // Every cycle faded, the counted ones solid over it (a gap where a reply was lost).
        chart
            .draw_series(LineSeries::new(
                rows.iter().map(error),
                c.mix(0.3).stroke_width(1),
            ))
            .map_err(|x| e(&x))?;
        for run in rows.split(|r| !panel.counts(r)) {
            chart
                .draw_series(LineSeries::new(run.iter().map(error), c.stroke_width(2)))
                .map_err(|x| e(&x))?;
        }
        if let Some(&b) = panel.bounds.get(k) {
            for y in [b, -b] {
                chart
                    .draw_series(DashedLineSeries::new(
                        [(0.0, y), (t_end, y)],
                        6,
                        4,
                        c.stroke_width(1),
                    ))
                    .map_err(|x| e(&x))?;
            }
        }
    }
    if let Some(at) = report.fault_at {
        let (lo, hi) = (-1.05 * panel.y_max, 1.05 * panel.y_max);
        chart
            .draw_series(LineSeries::new(
                [(at.time_s, lo), (at.time_s, hi)],
                RED.stroke_width(2),
            ))
            .map_err(|x| e(&x))?;
        chart
            .draw_series(std::iter::once(Text::new(
                format!(" fault at cycle {}, t = {:.3} s", at.cycle, at.time_s),
                (at.time_s, 0.9 * hi),
                ("sans-serif", 16).into_font().color(&RED),
            )))
            .map_err(|x| e(&x))?;
    }

    // Wake-up latency histogram, 1 µs bins merged into about 100 bars, log counts.
    let w = report.stats.wakeup.summary();
    let (bars, x_end) = latency_bars(report.stats.wakeup.bins(), w.max_ns);
    let top_count = bars.iter().map(|b| b.2).max().unwrap_or(1) as f64;
    let mut chart = ChartBuilder::on(&bottom)
        .caption(
            format!(
                "wake-up latency ({} cycles): min {:.1}  mean {:.1}  p99 {:.1}  p99.9 {:.1}  max {:.1} µs{}",
                w.count,
                w.min_ns as f64 / 1e3,
                w.mean_ns as f64 / 1e3,
                w.p99_ns as f64 / 1e3,
                w.p999_ns as f64 / 1e3,
                w.max_ns as f64 / 1e3,
                if w.overflow > 0 {
                    format!(" ({} beyond the histogram)", w.overflow)
                } else {
                    String::new()
                }
            ),
            ("sans-serif", 20),
        )
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..x_end, (0.5..top_count * 2.0).log_scale())
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_desc("wake-up latency [µs]")
        .y_desc("cycles")
        .draw()
        .map_err(|x| e(&x))?;
    chart
        .draw_series(bars.iter().map(|&(x0, x1, n)| {
            Rectangle::new([(x0, 0.5), (x1, n as f64)], BLUE.mix(0.6).filled())
        }))
        .map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))
}

/// What the tracking-error panel shows: the largest error the report's statistics count
/// (fresh replies before the first fault: the caption's max is the largest solid point), the
/// largest after the fault or on a lost reply (faded), and the joints' bounds that fit.
struct ErrorPanel {
    /// The first fault's cycle, if any.
    fault_cycle: Option<u64>,
    /// Largest counted error, mrad.
    counted_max: f64,
    /// Largest error not counted (after the fault, or on a lost reply), mrad.
    other_max: f64,
    /// The y axis' half range, mrad.
    y_max: f64,
    /// Each joint's tracking bound, mrad, where it fits the panel (empty where none does).
    bounds: Vec<f64>,
    /// Bounds too large to draw next to the errors, mrad (smallest, largest).
    off_scale: Option<(f64, f64)>,
}

impl ErrorPanel {
    /// Bounds are drawn when the largest is at most this many times the largest error: beyond,
    /// the curves would flatten to a line.
    const BOUND_SCALE: f64 = 4.0;

    fn new<const J: usize>(report: &RunReport, rows: &[CycleRecord<J>]) -> Self {
        let dof = report.joints.len();
        let fault_cycle = report.fault_at.map(|a| a.cycle);
        let mut panel = Self {
            fault_cycle,
            counted_max: 0.0,
            other_max: 0.0,
            y_max: 0.0,
            bounds: Vec::new(),
            off_scale: None,
        };
        for r in rows {
            let worst = (0..dof)
                .map(|k| (r.commanded[k] - r.measured[k]).abs() * 1e3)
                .fold(0.0, f64::max);
            if panel.counts(r) {
                panel.counted_max = panel.counted_max.max(worst);
            } else {
                panel.other_max = panel.other_max.max(worst);
            }
        }
        let errors = panel.counted_max.max(panel.other_max).max(1e-3);
        let bounds: Vec<f64> = report
            .tracking_bound
            .iter()
            .take(dof)
            .map(|b| b * 1e3)
            .filter(|b| b.is_finite() && *b > 0.0)
            .collect();
        let largest = bounds.iter().copied().fold(0.0, f64::max);
        if !bounds.is_empty() && largest <= Self::BOUND_SCALE * errors {
            panel.y_max = errors.max(largest);
            panel.bounds = bounds;
        } else {
            panel.y_max = errors;
            if !bounds.is_empty() {
                let smallest = bounds.iter().copied().fold(f64::INFINITY, f64::min);
                panel.off_scale = Some((smallest, largest));
            }
        }
        panel
    }

    /// Whether the report's statistics count this cycle's error.
    fn counts<const J: usize>(&self, r: &CycleRecord<J>) -> bool {
        r.counted
    }

    fn caption(&self, report: &RunReport) -> String {
        let mut s = format!(
            "tracking error: max {:.3} mrad, rms {:.3} mrad{}",
            self.counted_max,
            report.tracking_error_rms * 1e3,
            if self.fault_cycle.is_some() {
                " up to the fault"
            } else {
                ""
            }
        );
        if self.other_max > 0.0 {
            let _ = write!(
                s,
                "; faded: {} up to {:.3} mrad",
                if self.fault_cycle.is_some() {
                    "after the fault or lost replies"
                } else {
                    "lost replies"
                },
                self.other_max
            );
        }
        match self.off_scale {
            Some((lo, hi)) => {
                let _ = write!(s, "; bounds {lo:.0}–{hi:.0} mrad, off scale");
            }
            None if !self.bounds.is_empty() => s.push_str("; bounds dashed"),
            None => {}
        }
        s
    }
}

/// The latency histogram's bars (1 µs bins merged into about 100: start µs, end µs, count;
/// empty ones left out) up to the worst wake-up `max_ns`, and where the x axis ends: after the
/// last bar (the worst wake-up), so it stands inside the frame, not on it.
fn latency_bars(bins: &[u64], max_ns: u64) -> (Vec<(f64, f64, u64)>, f64) {
    let shown_us = ((max_ns / 1000 + 1) as usize).min(bins.len()).max(10);
    let per_bar = shown_us.div_ceil(100).max(1);
    let bars = bins[..shown_us.min(bins.len())]
        .chunks(per_bar)
        .enumerate()
        .map(|(i, c)| {
            let x0 = (i * per_bar) as f64;
            (x0, x0 + c.len() as f64, c.iter().sum())
        })
        .filter(|b| b.2 > 0)
        .collect();
    let x_end = shown_us as f64 + (per_bar as f64).max(0.03 * shown_us as f64);
    (bars, x_end)
}

#[cfg(test)]
mod tests {
    use super::{CycleRecord, RunReport, draw, latency_bars};
    use rl::controller::FaultAt;

    /// Two joints tracking within 1 mrad until a fault at cycle 20, then 8 mrad off; one reply
    /// lost at cycle 10 with a 30 mrad stale error. The caption's max is the counted one (the
    /// report's), the rest is said faded; the fault is marked; bounds of 5 mrad are drawn, of
    /// 500 mrad called off scale.
    #[test]
    fn the_error_panel_agrees_with_the_report_and_marks_the_fault() {
        let rows: Vec<CycleRecord<2>> = (0..40u64)
            .map(|c| {
                let error = match c {
                    10 => 0.030,
                    c if c >= 20 => 0.008,
                    _ => 0.001 * (c as f64 / 20.0),
                };
                CycleRecord {
                    cycle: c,
                    time_s: c as f64 * 0.01,
                    commanded: [error, -error / 2.0],
                    counted: c != 10 && c < 20,
                    ..CycleRecord::ZERO
                }
            })
            .collect();
        let mut report =
            RunReport::failed_early("m".into(), "d".into(), vec!["a".into(), "b".into()], "x");
        report.fault_at = Some(FaultAt {
            cycle: 20,
            time_s: 0.2,
        });
        report.tracking_error_max = 0.00095;
        let svg = |report: &RunReport, name: &str| {
            let path = std::env::temp_dir()
                .join(format!("rl-plot-test-{}-{name}.svg", std::process::id()));
            draw(&path, report, &rows).expect("drawn");
            let text = std::fs::read_to_string(&path).expect("svg");
            let _ = std::fs::remove_file(&path);
            text
        };
        report.tracking_bound = vec![0.005, 0.005];
        let text = svg(&report, "near");
        assert!(
            text.contains("tracking error: max 0.950 mrad"),
            "the counted max (the report's)"
        );
        assert!(
            text.contains("faded: after the fault or lost replies up to 30.000 mrad"),
            "{text}"
        );
        assert!(text.contains("fault at cycle 20, t = 0.200 s"), "{text}");
        assert!(text.contains("bounds dashed"), "{text}");
        report.tracking_bound = vec![0.5, 0.5];
        let text = svg(&report, "far");
        assert!(text.contains("bounds 500–500 mrad, off scale"), "{text}");
    }

    /// The bar of the worst wake-up ends inside the frame, with room after it, whatever the
    /// worst wake-up is.
    #[test]
    fn the_last_latency_bar_stands_inside_the_frame() {
        for max_us in [3_usize, 9, 10, 57, 99, 100, 101, 999, 4_321, 9_999] {
            let mut bins = vec![0_u64; 10_000];
            bins[0] = 5;
            bins[max_us] = 1;
            let (bars, x_end) = latency_bars(&bins, max_us as u64 * 1000 + 400);
            let last = bars.last().expect("bars");
            assert!(
                last.0 <= max_us as f64 && (max_us as f64) < last.1,
                "{max_us} µs in its bar {last:?}"
            );
            assert!(
                last.1 < x_end && x_end - last.1 >= 0.01 * x_end,
                "{max_us} µs: the bar ends at {}, the frame at {x_end}",
                last.1
            );
            assert_eq!(bars.iter().map(|b| b.2).sum::<u64>(), 6);
        }
    }
}
