use crate::Device;

/// What a device's link has seen so far: every exchange is accounted for, so nothing is lost
/// silently. Kept by the driver, not the socket, so the counts survive `close` (a report
/// written after the device is closed still shows them); they accumulate over the life of the
/// driver object.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct LinkStatistics {
    /// Requests (packets, frames, lines) sent, end packets included.
    pub sent: u64,
    /// Valid replies used.
    pub received: u64,
    /// Exchanges whose reply did not come by the cycle's deadline.
    pub lost: u64,
    /// Replies that came after their exchange had given up (found and dropped later).
    pub late: u64,
    /// Packets refused without being read: from another sender, for another node or model.
    pub rejected: u64,
    /// Packets from the device that were malformed: wrong length, bad checksum, unparsable,
    /// other contents than requested, a replayed or frozen reply.
    pub corrupt: u64,
    /// The current run of failed exchanges.
    pub consecutive_failures: u32,
}

impl LinkStatistics {
    /// Lost replies as a fraction of exchanges that expected one (0 when none did).
    pub fn loss_rate(&self) -> f64 {
        let expected = self.received + self.lost;
        if expected == 0 {
            0.0
        } else {
            self.lost as f64 / expected as f64
        }
    }
}

/// Reports the link's counts (a capability every networked driver has; generic control code
/// bounds the run on them).
pub trait LinkStatisticsSensor: Device {
    /// The counts so far.
    fn link_statistics(&self) -> LinkStatistics;
}
