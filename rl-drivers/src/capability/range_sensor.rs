use crate::Device;

/// A scanning range sensor such as a laser scanner (RL's `RangeSensor`).
pub trait RangeSensor: Device {
    /// Number of beams in one scan.
    fn distance_count(&self) -> usize;
    /// Angle of the first beam in rad.
    fn start_angle_rad(&self) -> f64;
    /// Angle between neighbouring beams in rad.
    fn angle_increment_rad(&self) -> f64;
    /// Writes the last scan in m into `distances` (length [`distance_count`](Self::distance_count)).
    fn distances(&self, distances: &mut [f64]) -> Result<(), Self::Error>;
}
