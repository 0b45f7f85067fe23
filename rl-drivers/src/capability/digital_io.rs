use crate::Device;

/// Reads digital inputs (RL's `DigitalInputReader`).
pub trait DigitalInputReader: Device {
    /// Number of inputs that [`digital_input`](Self::digital_input) can address.
    fn digital_input_count(&self) -> usize;
    /// The last received value of input `index`.
    fn digital_input(&self, index: usize) -> Result<bool, Self::Error>;
}

/// Writes digital outputs (RL's `DigitalOutputWriter`).
pub trait DigitalOutputWriter: Device {
    /// Number of outputs that [`set_digital_output`](Self::set_digital_output) can address.
    fn digital_output_count(&self) -> usize;
    /// Buffers output `index` for the next step.
    fn set_digital_output(&mut self, index: usize, value: bool) -> Result<(), Self::Error>;
}
