//! One record per control cycle, small and `Copy`, for a lock-free queue from the real-time
//! thread to a writer thread, and its CSV form (written by the writer, never on the real-time
//! thread).

use std::io::{self, Write};

use super::MAX_JOINTS;

/// What one control cycle saw and did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CycleRecord {
    /// Cycle index.
    pub cycle: u64,
    /// Trajectory time of the cycle, s.
    pub time_s: f64,
    /// The position commanded for this time (sent one cycle earlier).
    pub commanded: [f64; MAX_JOINTS],
    /// The measured position (the device's last reply).
    pub measured: [f64; MAX_JOINTS],
    /// Inverse-dynamics feed-forward torque for the position commanded in this cycle.
    pub feed_forward: [f64; MAX_JOINTS],
    /// How late the cycle woke after its deadline, ns (filled by the loop).
    pub wakeup_latency_ns: u64,
    /// From wake-up to the end of the control step, device exchange included, ns (filled by
    /// the loop).
    pub step_ns: u64,
}

impl CycleRecord {
    /// A zeroed record.
    pub const ZERO: Self = Self {
        cycle: 0,
        time_s: 0.0,
        commanded: [0.0; MAX_JOINTS],
        measured: [0.0; MAX_JOINTS],
        feed_forward: [0.0; MAX_JOINTS],
        wakeup_latency_ns: 0,
        step_ns: 0,
    };
}

/// Writes the CSV header: `cycle,t_s,cmd_<joint>…,meas_<joint>…,ff_<joint>…,latency_us,step_us`.
pub fn write_header<W: Write>(mut w: W, joints: &[String]) -> io::Result<()> {
    write!(w, "cycle,t_s")?;
    for prefix in ["cmd", "meas", "ff"] {
        for j in joints {
            write!(w, ",{prefix}_{}", sanitize(j))?;
        }
    }
    writeln!(w, ",latency_us,step_us")
}

/// Writes one record as a CSV row for `dof` joints.
pub fn write_row<W: Write>(mut w: W, r: &CycleRecord, dof: usize) -> io::Result<()> {
    write!(w, "{},{:.6}", r.cycle, r.time_s)?;
    for values in [&r.commanded, &r.measured] {
        for v in &values[..dof] {
            write!(w, ",{v:.7}")?;
        }
    }
    for v in &r.feed_forward[..dof] {
        write!(w, ",{v:.4}")?;
    }
    writeln!(
        w,
        ",{:.3},{:.3}",
        r.wakeup_latency_ns as f64 / 1e3,
        r.step_ns as f64 / 1e3
    )
}

/// A joint name usable as a CSV column name (no commas, quotes or spaces).
fn sanitize(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}
