//! Distributed clocks (ETG.1000.4 §9; Beckhoff ESC datasheet section I, chapter 9): the master
//! latches every port's receive time with one broadcast write to 0x0900, computes each
//! device's propagation delay from the reference clock (the first device with DC) out of the
//! loop times of its neighbours, writes the delay (0x0928) and the offset that makes each
//! device's system time equal the master's (0x0920), lets the devices' control loops settle
//! with a burst of FRMW datagrams distributing the reference's time (static drift
//! compensation), and starts SYNC0 on each device at the loop's period.
//!
//! Topology: a line (each device's port 0 towards the master, port 1 to the next). Branches
//! (junction devices with ports 2 or 3 in use) are refused with a configuration error rather
//! than given wrong delays.

use std::time::{Duration, Instant};

use super::error::EcError;
use super::master::Master;
use crate::proto::ecat::command::Command;
use crate::proto::ecat::datagram::physical;
use crate::proto::ecat::register as reg;

/// One device's latched receive times.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PortTimes {
    /// Receive time at port 0 (frame in) and port 1 (frame back), low 32 bits of local time.
    pub port0: u32,
    /// Port 1; meaningful when `port1_open`.
    pub port1: u32,
    /// Whether port 1 leads to further devices.
    pub port1_open: bool,
}

impl PortTimes {
    /// The time the frame spent beyond this device (0 for the last device).
    pub fn loop_time(&self) -> u32 {
        if self.port1_open {
            self.port1.wrapping_sub(self.port0)
        } else {
            0
        }
    }
}

/// Propagation delays in ns from the first entry (the reference) for devices on a line, in
/// position order: each hop's delay is half the difference of the two neighbours' loop times.
pub fn propagation_delays(devices: &[PortTimes]) -> Vec<u32> {
    let mut out = Vec::with_capacity(devices.len());
    let mut delay = 0u64;
    for (k, d) in devices.iter().enumerate() {
        if k > 0 {
            let prev = devices[k - 1].loop_time();
            let hop = prev.saturating_sub(d.loop_time()) / 2;
            delay += u64::from(hop);
        }
        out.push(delay.min(u64::from(u32::MAX)) as u32);
    }
    out
}

/// What the master knows about the distributed clocks once set up.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct DcSetup {
    /// Index (in the master's device list) of the reference clock.
    pub reference: usize,
    /// The devices with DC, in order.
    pub devices: Vec<usize>,
    /// Each DC device's propagation delay (ns), same order.
    pub delays: Vec<u32>,
    /// SYNC0 cycle time (ns), once started.
    pub sync0_cycle: u32,
    /// The largest system time difference a device reported after the static compensation.
    pub max_difference_ns: u32,
}

/// The master's own clock for system time: nanoseconds of CLOCK_MONOTONIC.
pub fn master_time_ns(origin: Instant) -> u64 {
    origin.elapsed().as_nanos() as u64 + 1_000_000_000
}

impl Master {
    /// Measures delays, sets offsets and delays, and runs `static_frames` FRMW datagrams so
    /// the devices' clocks settle on the reference. `None` if no device has DC.
    pub fn dc_setup(
        &mut self,
        origin: Instant,
        static_frames: u32,
    ) -> Result<Option<DcSetup>, EcError> {
        let dc: Vec<usize> = (0..self.devices.len())
            .filter(|&k| self.devices[k].has_dc())
            .collect();
        if dc.is_empty() {
            return Ok(None);
        }
        for &k in &dc {
            let s = self.devices[k].dl_status;
            if s.port_open(2) || s.port_open(3) {
                return Err(EcError::Config {
                    device: Some(self.devices[k].reference()),
                    what: "a branch (port 2 or 3 in use): DC delays are measured on a line only",
                });
            }
        }
        let latched_at = master_time_ns(origin);
        self.bwr(reg::DC_RECEIVE_TIME_PORT0, &[0; 4])?;
        let mut ports = Vec::with_capacity(dc.len());
        let mut local = Vec::with_capacity(dc.len());
        for &k in &dc {
            let mut b = [0u8; 8];
            self.fprd(k, reg::DC_RECEIVE_TIME_PORT0, &mut b)?;
            let open = self.devices[k].dl_status.port_open(1);
            ports.push(PortTimes {
                port0: u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                port1: u32::from_le_bytes([b[4], b[5], b[6], b[7]]),
                port1_open: open,
            });
            let mut t = [0u8; 8];
            self.fprd(k, reg::DC_RECEIVE_TIME_UNIT, &mut t)?;
            local.push(u64::from_le_bytes(t));
        }
        let delays = propagation_delays(&ports);
        for (i, &k) in dc.iter().enumerate() {
            let offset = latched_at
                .wrapping_add(u64::from(delays[i]))
                .wrapping_sub(local[i]);
            self.fpwr(k, reg::DC_SYSTEM_TIME_OFFSET, &offset.to_le_bytes())?;
            self.fpwr(k, reg::DC_SYSTEM_TIME_DELAY, &delays[i].to_le_bytes())?;
        }
        let reference = dc[0];
        let station = self.devices[reference].station;
        for _ in 0..static_frames {
            let mut t = [0u8; 8];
            self.datagram(
                Command::Frmw,
                physical(station, reg::DC_SYSTEM_TIME),
                &mut t,
            )?;
        }
        let mut max_difference_ns = 0;
        for &k in &dc {
            let mut d = [0u8; 4];
            self.fprd(k, reg::DC_SYSTEM_TIME_DIFFERENCE, &mut d)?;
            max_difference_ns = max_difference_ns.max(u32::from_le_bytes(d) & 0x7FFF_FFFF);
        }
        Ok(Some(DcSetup {
            reference,
            devices: dc,
            delays,
            sync0_cycle: 0,
            max_difference_ns,
        }))
    }

    /// Starts SYNC0 every `cycle` on device `k` (its SII AssignActivate, 0x0300 if none),
    /// `lead` after the reference's current system time, aligned to the cycle, plus `shift`.
    pub fn dc_start_sync0(
        &mut self,
        k: usize,
        cycle: Duration,
        lead: Duration,
        shift: Duration,
    ) -> Result<u64, EcError> {
        let cycle_ns = u32::try_from(cycle.as_nanos()).map_err(|_| EcError::Config {
            device: Some(self.devices[k].reference()),
            what: "a SYNC0 cycle above 4.29 s",
        })?;
        if cycle_ns == 0 {
            return Err(EcError::Config {
                device: Some(self.devices[k].reference()),
                what: "a SYNC0 cycle of 0",
            });
        }
        let activate = match self.devices[k].dc_assign_activate {
            0 => 0x0300u16,
            a => a,
        };
        self.fpwr(k, reg::DC_ACTIVATION, &[0])?;
        self.fpwr(k, reg::DC_SYNC0_CYCLE, &cycle_ns.to_le_bytes())?;
        let mut now = [0u8; 8];
        self.fprd(k, reg::DC_SYSTEM_TIME, &mut now)?;
        let now = u64::from_le_bytes(now);
        let c = u64::from(cycle_ns);
        let start = ((now + lead.as_nanos() as u64) / c + 1) * c + shift.as_nanos() as u64;
        self.fpwr(k, reg::DC_SYNC0_START, &start.to_le_bytes())?;
        self.fpwr(k, reg::DC_CYCLIC_UNIT_CONTROL, &activate.to_le_bytes())?;
        Ok(start)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delays_on_a_line_are_half_the_loop_differences() {
        // Three devices, 500 ns per hop: loops 2000, 1000, 0 (the last closes the ring).
        let p = |t0: u32, loop_ns: u32, open: bool| PortTimes {
            port0: t0,
            port1: t0.wrapping_add(loop_ns),
            port1_open: open,
        };
        let d = propagation_delays(&[
            p(u32::MAX - 100, 2000, true), // the clock wraps between the ports
            p(7, 1000, true),
            p(99, 0, false),
        ]);
        assert_eq!(d, vec![0, 500, 1000]);
        // A device without a loop of its own after one with: the whole loop is two hops.
        assert_eq!(
            propagation_delays(&[p(0, 1200, true), p(0, 0, false)]),
            vec![0, 600]
        );
    }
}
