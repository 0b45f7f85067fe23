use core::time::Duration;

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
    /// When replies reached this machine, from the kernel's receive timestamps (empty for a
    /// driver or a kernel without them).
    pub delivery: Delivery,
}

/// When replies reached this machine's kernel (`SO_TIMESTAMPNS`), against when the driver read
/// them and against their exchanges' deadlines: tells a reply the loop read late (it waited in
/// the socket) from one that reached the machine late (it came after the deadline).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Delivery {
    /// Replies the driver was waiting for that carried the kernel's receive time.
    pub timestamped: u64,
    /// The longest such a reply waited in the socket between the kernel's receive and the
    /// driver's read: how late the waiting thread woke up to read it.
    pub max_wait: Duration,
    /// The total of those waits (for the mean).
    pub total_wait: Duration,
    /// Replies that reached the kernel after their exchange had given up (found later).
    pub after_deadline: u64,
    /// The longest after its exchange's deadline such a reply reached the kernel.
    pub max_after_deadline: Duration,
}

impl Delivery {
    /// Notes a reply that waited `waited` in the socket. Allocates nothing.
    pub fn note_wait(&mut self, waited: Duration) {
        self.timestamped += 1;
        self.max_wait = self.max_wait.max(waited);
        self.total_wait = self.total_wait.saturating_add(waited);
    }

    /// Notes a reply that reached the kernel `late` after its exchange's deadline.
    pub fn note_after_deadline(&mut self, late: Duration) {
        self.after_deadline += 1;
        self.max_after_deadline = self.max_after_deadline.max(late);
    }

    /// The mean wait in the socket (zero without timestamps).
    pub fn mean_wait(&self) -> Duration {
        match u32::try_from(self.timestamped) {
            Ok(0) => Duration::ZERO,
            Ok(n) => self.total_wait / n,
            Err(_) => {
                Duration::from_secs_f64(self.total_wait.as_secs_f64() / self.timestamped as f64)
            }
        }
    }
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
