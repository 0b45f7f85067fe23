//! One record per control cycle, small and `Copy`, for a lock-free queue from the real-time
//! thread to a writer thread, and its CSV form (written by the writer, never on the real-time
//! thread). [`TelemetryFile`] writes the CSV next to its destination and moves it into place
//! only once it has rows, so a run that fails early never empties an existing file.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use super::DEFAULT_JOINTS;

/// What the run was doing in a cycle (the CSV's `state` column).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum RunState {
    /// Running the law.
    #[default]
    Running,
    /// Bringing the arm to rest (a stop request, the end of the duration, stale inputs).
    Braking,
    /// A fault was found in this cycle or before: coming to rest, or ending at once.
    Fault,
    /// The run ended: the device was not stepped in this cycle.
    Stopped,
}

impl RunState {
    /// The CSV value: `running`, `braking`, `fault` or `stopped`.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Running => "running",
            Self::Braking => "braking",
            Self::Fault => "fault",
            Self::Stopped => "stopped",
        }
    }
}

/// What one control cycle saw and did, for up to `J` joints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CycleRecord<const J: usize = DEFAULT_JOINTS> {
    /// Cycle index.
    pub cycle: u64,
    /// Time of the cycle, s: the law's (trajectory time for the trajectory follower, which
    /// slows down while it brakes) or the run's.
    pub time_s: f64,
    /// The position commanded for this time (sent one cycle earlier); for a law commanding
    /// velocities or torques, its reference position.
    pub commanded: [f64; J],
    /// The measured position (the device's last reply).
    pub measured: [f64; J],
    /// The torques sent in this cycle: inverse-dynamics feed-forward for the position
    /// commanded (the trajectory follower), or a torque law's command.
    pub feed_forward: [f64; J],
    /// How late the cycle woke after its deadline, ns (filled by the loop).
    pub wakeup_latency_ns: u64,
    /// From wake-up to the end of the control step, device exchange included, ns (filled by
    /// the loop).
    pub step_ns: u64,
    /// The report's tracking statistics count this cycle: its measurement came with this
    /// cycle's reply and no fault had been found yet (false: a lost reply, whose `measured` is
    /// the last one held, or a cycle after the first fault).
    pub counted: bool,
    /// What the run was doing.
    pub state: RunState,
}

impl<const J: usize> CycleRecord<J> {
    /// A zeroed record.
    pub const ZERO: Self = Self {
        cycle: 0,
        time_s: 0.0,
        commanded: [0.0; J],
        measured: [0.0; J],
        feed_forward: [0.0; J],
        wakeup_latency_ns: 0,
        step_ns: 0,
        counted: false,
        state: RunState::Running,
    };
}

/// Writes the CSV header:
/// `cycle,t_s,cmd_<joint>…,meas_<joint>…,ff_<joint>…,latency_us,step_us,counted,state`
/// (`counted`: 1 when the report's tracking statistics count the row — a fresh measurement
/// before the first fault — else 0).
pub fn write_header<W: Write>(mut w: W, joints: &[String]) -> io::Result<()> {
    write!(w, "cycle,t_s")?;
    for prefix in ["cmd", "meas", "ff"] {
        for j in joints {
            write!(w, ",{prefix}_{}", sanitize(j))?;
        }
    }
    writeln!(w, ",latency_us,step_us,counted,state")
}

/// Writes one record as a CSV row for `dof` joints.
pub fn write_row<W: Write, const J: usize>(
    mut w: W,
    r: &CycleRecord<J>,
    dof: usize,
) -> io::Result<()> {
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
        ",{:.3},{:.3},{},{}",
        r.wakeup_latency_ns as f64 / 1e3,
        r.step_ns as f64 / 1e3,
        u8::from(r.counted),
        r.state.as_str()
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

/// A telemetry CSV being written: rows go to `<file>.partial` beside the destination, which is
/// replaced only when [`finish`](Self::finish) has rows to put there. Creating it checks that
/// the directory is writable before anything runs.
#[derive(Debug)]
pub struct TelemetryFile {
    path: PathBuf,
    partial: PathBuf,
    writer: Option<BufWriter<File>>,
    dof: usize,
    rows: u64,
    error: Option<String>,
}

impl TelemetryFile {
    /// Creates `<path>.partial` and writes the header for `joints`.
    pub fn create(path: &Path, joints: &[String]) -> io::Result<Self> {
        let mut name = path.file_name().unwrap_or_default().to_os_string();
        name.push(".partial");
        let partial = path.with_file_name(name);
        let mut writer = BufWriter::new(File::create(&partial)?);
        if let Err(e) = write_header(&mut writer, joints) {
            drop(writer);
            let _ = std::fs::remove_file(&partial);
            return Err(e);
        }
        Ok(Self {
            path: path.to_owned(),
            partial,
            writer: Some(writer),
            dof: joints.len(),
            rows: 0,
            error: None,
        })
    }

    /// The destination.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Rows written so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Appends a record; the first write error is kept and later rows are skipped.
    pub fn write<const J: usize>(&mut self, record: &CycleRecord<J>) {
        if self.error.is_some() {
            return;
        }
        if let Some(w) = &mut self.writer {
            match write_row(w, record, self.dof.min(J)) {
                Ok(()) => self.rows += 1,
                Err(e) => self.error = Some(e.to_string()),
            }
        }
    }

    /// Flushes and, if any row was written, moves the file into place (replacing what was
    /// there); with no rows the destination is left as it was. Returns the rows written, or
    /// the first write error.
    pub fn finish(mut self) -> Result<u64, String> {
        let flushed = self.writer.take().map_or(Ok(()), |mut w| w.flush());
        if let (Err(e), None) = (flushed, &self.error) {
            self.error = Some(e.to_string());
        }
        if self.rows > 0 {
            std::fs::rename(&self.partial, &self.path).map_err(|e| {
                format!(
                    "cannot move {} to {}: {e}",
                    self.partial.display(),
                    self.path.display()
                )
            })?;
        }
        match self.error.take() {
            Some(e) => Err(e),
            None => Ok(self.rows),
        }
    }
}

impl Drop for TelemetryFile {
    fn drop(&mut self) {
        // Unfinished, or finished without rows: the partial file goes, the destination stays.
        self.writer = None;
        if self.partial.exists() {
            let _ = std::fs::remove_file(&self.partial);
        }
    }
}
