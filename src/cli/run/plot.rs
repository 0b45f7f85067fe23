//! `--plot`: joint tracking and the wake-up latency histogram on one SVG page.

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

    // Tracking error.
    let err_max = rows
        .iter()
        .flat_map(|r| (0..dof).map(move |k| (r.commanded[k] - r.measured[k]).abs()))
        .fold(1e-6, f64::max)
        * 1e3;
    let mut chart = ChartBuilder::on(&middle)
        .caption(
            format!(
                "tracking error (commanded − measured): max {:.3} mrad, rms {:.3} mrad",
                report.tracking_error_max * 1e3,
                report.tracking_error_rms * 1e3
            ),
            ("sans-serif", 20),
        )
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t_end, (-1.05 * err_max)..(1.05 * err_max))
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_desc("trajectory time [s]")
        .y_desc("error [mrad]")
        .draw()
        .map_err(|x| e(&x))?;
    for k in 0..dof {
        chart
            .draw_series(LineSeries::new(
                rows.iter()
                    .map(|r| (r.time_s, (r.commanded[k] - r.measured[k]) * 1e3)),
                colour(k).stroke_width(2),
            ))
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
    use super::latency_bars;

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
