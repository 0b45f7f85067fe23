//! Keeping CPUs out of deep idle states while a loop runs (PM QoS `/dev/cpu_dma_latency`).
//!
//! Waking a core from a deep C-state takes tens to hundreds of microseconds, which shows up
//! directly as wake-up latency. Writing a limit to `/dev/cpu_dma_latency` asks the kernel to
//! use only idle states that wake faster; the request holds while the file stays open. This is
//! what cyclictest does by default ("/dev/cpu_dma_latency set to 0us"), so a fair comparison
//! does it too.

use std::fs::{File, OpenOptions};
use std::io::{self, Write};

/// Path of the PM QoS CPU latency device.
pub const CPU_DMA_LATENCY: &str = "/dev/cpu_dma_latency";

/// A held CPU wake-up latency limit; released when dropped.
#[derive(Debug)]
pub struct CpuLatencyHint {
    _file: File,
    max_latency_us: u32,
}

impl CpuLatencyHint {
    /// Asks that no CPU idle state take longer than `max_latency_us` to leave (0: stay in the
    /// shallowest state) for as long as the returned value lives. Needs write access to
    /// `/dev/cpu_dma_latency` (root by default).
    pub fn hold(max_latency_us: u32) -> io::Result<Self> {
        let mut file = OpenOptions::new().write(true).open(CPU_DMA_LATENCY)?;
        let value = i32::try_from(max_latency_us).unwrap_or(i32::MAX);
        file.write_all(&value.to_ne_bytes())?;
        Ok(Self {
            _file: file,
            max_latency_us,
        })
    }

    /// The limit held, in µs.
    pub fn max_latency_us(&self) -> u32 {
        self.max_latency_us
    }
}
