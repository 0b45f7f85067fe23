use crate::Device;

/// Reads analog inputs (RL's `AnalogInputReader`), in the device's unit (usually V).
pub trait AnalogInputReader: Device {
    /// Number of analog inputs.
    fn analog_input_count(&self) -> usize;
    /// Writes the last received inputs into `values` (length [`analog_input_count`](Self::analog_input_count)).
    fn analog_inputs(&self, values: &mut [f64]) -> Result<(), Self::Error>;
}

/// Writes analog outputs (RL's `AnalogOutputWriter`).
pub trait AnalogOutputWriter: Device {
    /// Number of analog outputs.
    fn analog_output_count(&self) -> usize;
    /// Buffers the outputs for the next step (length [`analog_output_count`](Self::analog_output_count)).
    fn set_analog_outputs(&mut self, values: &[f64]) -> Result<(), Self::Error>;
}
