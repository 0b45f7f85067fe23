//! The bus budget of one control cycle: a SYNC, each axis's RPDOs and TPDOs, in bits and in µs
//! at the bus's bit rate, nominal and with worst-case bit stuffing — and the check that a
//! cycle fits: the worst case plus one worst-case 8-byte frame of headroom (for the
//! heartbeats, EMCYs and SDOs between the PDOs, and the arbitration delay of a SYNC behind a
//! frame already on the wire) must not exceed the period.

use core::fmt;
use core::time::Duration;

use crate::proto::can::timing::{standard_frame_bits, standard_frame_bits_worst};

/// The bits one cycle puts on the bus.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BusLoad {
    /// Frames per cycle (SYNC included).
    pub frames: u32,
    /// Bits without stuffing.
    pub bits: u32,
    /// Bits with worst-case stuffing.
    pub bits_worst: u32,
    /// Headroom kept free: one worst-case 8-byte frame.
    pub headroom_bits: u32,
    /// The bus bit rate.
    pub bitrate: u32,
}

impl BusLoad {
    /// The load of a SYNC plus the given PDO data lengths (bytes), at `bitrate` bit/s.
    pub fn of(pdo_lengths: impl IntoIterator<Item = usize>, bitrate: u32) -> Self {
        let mut frames = 1;
        let mut bits = standard_frame_bits(0);
        let mut bits_worst = standard_frame_bits_worst(0);
        for len in pdo_lengths {
            frames += 1;
            bits += standard_frame_bits(len);
            bits_worst += standard_frame_bits_worst(len);
        }
        Self {
            frames,
            bits,
            bits_worst,
            headroom_bits: standard_frame_bits_worst(8),
            bitrate,
        }
    }

    /// The load of `axes` axes each with one 8-byte RPDO and one 8-byte TPDO.
    pub fn symmetric(axes: usize, bitrate: u32) -> Self {
        Self::of(core::iter::repeat_n(8, 2 * axes), bitrate)
    }

    fn us(&self, bits: u32) -> f64 {
        f64::from(bits) * 1e6 / f64::from(self.bitrate.max(1))
    }

    /// Bus time without stuffing, µs.
    pub fn time_us(&self) -> f64 {
        self.us(self.bits)
    }

    /// Bus time with worst-case stuffing, µs.
    pub fn time_worst_us(&self) -> f64 {
        self.us(self.bits_worst)
    }

    /// The shortest period that fits: worst case plus headroom.
    pub fn min_period(&self) -> Duration {
        let bits = u64::from(self.bits_worst + self.headroom_bits);
        Duration::from_nanos((bits * 1_000_000_000).div_ceil(u64::from(self.bitrate.max(1))))
    }

    /// Whether a cycle of `period` carries this load.
    pub fn fits(&self, period: Duration) -> bool {
        period >= self.min_period()
    }

    /// Worst-case load as a fraction of `period`.
    pub fn utilisation(&self, period: Duration) -> f64 {
        self.time_worst_us() / (period.as_secs_f64() * 1e6)
    }
}

impl fmt::Display for BusLoad {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} frames per cycle = {} bits ({} with worst-case bit stuffing) = {:.0} µs ({:.0} µs) \
             at {} kbit/s, plus {} bits ({:.0} µs) kept free for heartbeats, EMCY, SDO and \
             arbitration: the cycle needs at least {:.0} µs",
            self.frames,
            self.bits,
            self.bits_worst,
            self.time_us(),
            self.time_worst_us(),
            self.bitrate / 1000,
            self.headroom_bits,
            self.us(self.headroom_bits),
            self.min_period().as_secs_f64() * 1e6
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn six_axes_fit_2_ms_and_not_1_ms_at_1_mbit() {
        let l = BusLoad::symmetric(6, 1_000_000);
        assert_eq!(l.frames, 13);
        assert_eq!(l.bits, 47 + 12 * 111);
        assert_eq!(l.bits_worst, 55 + 12 * 135);
        // The reference's ≈1.4 ms (≈1.7 ms stuffed).
        assert!((l.time_us() - 1379.0).abs() < 1.0);
        assert!((l.time_worst_us() - 1675.0).abs() < 1.0);
        assert!(l.fits(Duration::from_millis(2)));
        assert!(!l.fits(Duration::from_millis(1)));
        assert!(!BusLoad::symmetric(8, 1_000_000).fits(Duration::from_millis(2)));
        assert!(BusLoad::symmetric(1, 1_000_000).fits(Duration::from_micros(500)));
        assert!(l.to_string().contains("1810 µs"), "{l}");
    }
}
