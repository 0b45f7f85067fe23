//! RTDE data types: their names in recipe answers and their sizes, big endian on the wire.

use super::RtdeError;

/// A field's type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DataType {
    /// `BOOL`: one byte, 0 or 1.
    Bool,
    /// `UINT8`.
    Uint8,
    /// `UINT32`.
    Uint32,
    /// `UINT64`.
    Uint64,
    /// `INT32`.
    Int32,
    /// `DOUBLE` (IEEE 754 binary64).
    Double,
    /// `VECTOR3D`: three doubles.
    Vector3d,
    /// `VECTOR6D`: six doubles.
    Vector6d,
    /// `VECTOR6INT32`.
    Vector6Int32,
    /// `VECTOR6UINT32`.
    Vector6Uint32,
}

impl DataType {
    /// Every type.
    pub const ALL: [Self; 10] = [
        Self::Bool,
        Self::Uint8,
        Self::Uint32,
        Self::Uint64,
        Self::Int32,
        Self::Double,
        Self::Vector3d,
        Self::Vector6d,
        Self::Vector6Int32,
        Self::Vector6Uint32,
    ];

    /// Bytes on the wire.
    pub const fn size(self) -> usize {
        match self {
            Self::Bool | Self::Uint8 => 1,
            Self::Uint32 | Self::Int32 => 4,
            Self::Uint64 | Self::Double => 8,
            Self::Vector3d => 24,
            Self::Vector6d => 48,
            Self::Vector6Int32 | Self::Vector6Uint32 => 24,
        }
    }

    /// The name in a recipe answer.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Bool => "BOOL",
            Self::Uint8 => "UINT8",
            Self::Uint32 => "UINT32",
            Self::Uint64 => "UINT64",
            Self::Int32 => "INT32",
            Self::Double => "DOUBLE",
            Self::Vector3d => "VECTOR3D",
            Self::Vector6d => "VECTOR6D",
            Self::Vector6Int32 => "VECTOR6INT32",
            Self::Vector6Uint32 => "VECTOR6UINT32",
        }
    }

    /// The type of a name.
    pub fn from_name(name: &str) -> Result<Self, RtdeError> {
        Self::ALL
            .into_iter()
            .find(|t| t.name() == name)
            .ok_or(RtdeError::UnknownDataType)
    }
}

/// Reads big-endian values from a payload, front to back; a read past the end is
/// [`RtdeError::TooShort`].
#[derive(Clone, Debug)]
pub struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    /// A reader at the start of `bytes`.
    pub const fn new(bytes: &'a [u8]) -> Self {
        Self { bytes, at: 0 }
    }

    /// Bytes not read yet.
    pub fn rest(&self) -> &'a [u8] {
        &self.bytes[self.at..]
    }

    /// The next `n` bytes.
    pub fn take(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], RtdeError> {
        let end = self.at + n;
        if end > self.bytes.len() {
            return Err(RtdeError::TooShort {
                what,
                need: end,
                got: self.bytes.len(),
            });
        }
        let b = &self.bytes[self.at..end];
        self.at = end;
        Ok(b)
    }

    /// A `u8`.
    pub fn u8(&mut self, what: &'static str) -> Result<u8, RtdeError> {
        Ok(self.take(1, what)?[0])
    }

    /// A `u16`.
    pub fn u16(&mut self, what: &'static str) -> Result<u16, RtdeError> {
        let b = self.take(2, what)?;
        Ok(u16::from_be_bytes([b[0], b[1]]))
    }

    /// A `u32`.
    pub fn u32(&mut self, what: &'static str) -> Result<u32, RtdeError> {
        let b = self.take(4, what)?;
        Ok(u32::from_be_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// A `u64`.
    pub fn u64(&mut self, what: &'static str) -> Result<u64, RtdeError> {
        let b = self.take(8, what)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(u64::from_be_bytes(a))
    }

    /// An `f64`.
    pub fn f64(&mut self, what: &'static str) -> Result<f64, RtdeError> {
        Ok(f64::from_bits(self.u64(what)?))
    }
}

/// Writes big-endian values into a buffer, front to back.
#[derive(Debug)]
pub struct Writer<'a> {
    bytes: &'a mut [u8],
    at: usize,
}

impl<'a> Writer<'a> {
    /// A writer at the start of `bytes`.
    pub fn new(bytes: &'a mut [u8]) -> Self {
        Self { bytes, at: 0 }
    }

    /// Bytes written.
    pub const fn len(&self) -> usize {
        self.at
    }

    /// Whether nothing was written.
    pub const fn is_empty(&self) -> bool {
        self.at == 0
    }

    /// Appends `b`.
    pub fn put(&mut self, b: &[u8]) -> Result<(), RtdeError> {
        let end = self.at + b.len();
        if end > self.bytes.len() {
            return Err(RtdeError::BufferTooSmall {
                need: end,
                got: self.bytes.len(),
            });
        }
        self.bytes[self.at..end].copy_from_slice(b);
        self.at = end;
        Ok(())
    }

    /// A `u8`.
    pub fn u8(&mut self, v: u8) -> Result<(), RtdeError> {
        self.put(&[v])
    }

    /// A `u16`.
    pub fn u16(&mut self, v: u16) -> Result<(), RtdeError> {
        self.put(&v.to_be_bytes())
    }

    /// A `u32`.
    pub fn u32(&mut self, v: u32) -> Result<(), RtdeError> {
        self.put(&v.to_be_bytes())
    }

    /// A `u64`.
    pub fn u64(&mut self, v: u64) -> Result<(), RtdeError> {
        self.put(&v.to_be_bytes())
    }

    /// An `i32`.
    pub fn i32(&mut self, v: i32) -> Result<(), RtdeError> {
        self.put(&v.to_be_bytes())
    }

    /// An `f64`.
    pub fn f64(&mut self, v: f64) -> Result<(), RtdeError> {
        self.put(&v.to_be_bytes())
    }
}
