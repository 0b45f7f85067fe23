//! The object dictionary's vocabulary (CiA 301 §7.4): object codes, data types and access
//! types as EDS files (CiA 306) and SDO transfers use them.

use core::fmt;

/// The kind of an object (`ObjectType` in an EDS).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ObjectType {
    /// 0x0: no data.
    Null,
    /// 0x2: a large amount of data.
    Domain,
    /// 0x5: a type definition.
    DefType,
    /// 0x6: a structure definition.
    DefStruct,
    /// 0x7: a single value.
    Var,
    /// 0x8: sub-indexes of one type.
    Array,
    /// 0x9: sub-indexes of different types.
    Record,
}

impl ObjectType {
    /// The object code of a number.
    pub const fn from_code(code: u32) -> Option<Self> {
        Some(match code {
            0x0 => ObjectType::Null,
            0x2 => ObjectType::Domain,
            0x5 => ObjectType::DefType,
            0x6 => ObjectType::DefStruct,
            0x7 => ObjectType::Var,
            0x8 => ObjectType::Array,
            0x9 => ObjectType::Record,
            _ => return None,
        })
    }

    /// Whether the object has sub-indexes described in their own sections.
    pub const fn has_subs(self) -> bool {
        matches!(
            self,
            ObjectType::Array | ObjectType::Record | ObjectType::DefStruct
        )
    }
}

/// A basic data type (CiA 301 table 44; the index of its definition object).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DataType {
    /// 0x0001.
    Boolean,
    /// 0x0002.
    Integer8,
    /// 0x0003.
    Integer16,
    /// 0x0004.
    Integer32,
    /// 0x0005.
    Unsigned8,
    /// 0x0006.
    Unsigned16,
    /// 0x0007.
    Unsigned32,
    /// 0x0008.
    Real32,
    /// 0x0009.
    VisibleString,
    /// 0x000A.
    OctetString,
    /// 0x000B.
    UnicodeString,
    /// 0x000F.
    Domain,
    /// 0x0010.
    Integer24,
    /// 0x0011.
    Real64,
    /// 0x0015.
    Integer64,
    /// 0x0016.
    Unsigned24,
    /// 0x001B.
    Unsigned64,
}

impl DataType {
    /// The type of a data type index.
    pub const fn from_code(code: u32) -> Option<Self> {
        Some(match code {
            0x01 => DataType::Boolean,
            0x02 => DataType::Integer8,
            0x03 => DataType::Integer16,
            0x04 => DataType::Integer32,
            0x05 => DataType::Unsigned8,
            0x06 => DataType::Unsigned16,
            0x07 => DataType::Unsigned32,
            0x08 => DataType::Real32,
            0x09 => DataType::VisibleString,
            0x0A => DataType::OctetString,
            0x0B => DataType::UnicodeString,
            0x0F => DataType::Domain,
            0x10 => DataType::Integer24,
            0x11 => DataType::Real64,
            0x15 => DataType::Integer64,
            0x16 => DataType::Unsigned24,
            0x1B => DataType::Unsigned64,
            _ => return None,
        })
    }

    /// Bits of a value of fixed size (`None` for strings and domains).
    pub const fn bits(self) -> Option<u32> {
        Some(match self {
            DataType::Boolean => 1,
            DataType::Integer8 | DataType::Unsigned8 => 8,
            DataType::Integer16 | DataType::Unsigned16 => 16,
            DataType::Integer24 | DataType::Unsigned24 => 24,
            DataType::Integer32 | DataType::Unsigned32 | DataType::Real32 => 32,
            DataType::Integer64 | DataType::Unsigned64 | DataType::Real64 => 64,
            DataType::VisibleString
            | DataType::OctetString
            | DataType::UnicodeString
            | DataType::Domain => return None,
        })
    }

    /// Whether values are signed integers.
    pub const fn is_signed(self) -> bool {
        matches!(
            self,
            DataType::Integer8
                | DataType::Integer16
                | DataType::Integer24
                | DataType::Integer32
                | DataType::Integer64
        )
    }
}

impl fmt::Display for DataType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self, f)
    }
}

/// Who may read and write an object.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum AccessType {
    /// `ro`: read only (may change).
    ReadOnly,
    /// `wo`: write only.
    WriteOnly,
    /// `rw`: read and write.
    ReadWrite,
    /// `rwr`: read and write, mapped into TPDOs.
    ReadWriteRead,
    /// `rww`: read and write, mapped into RPDOs.
    ReadWriteWrite,
    /// `const`: read only, never changes.
    Const,
}

impl AccessType {
    /// The access type of an EDS `AccessType` value (case-insensitive).
    pub fn parse(s: &str) -> Option<Self> {
        let s = s.trim();
        Some(if s.eq_ignore_ascii_case("ro") {
            AccessType::ReadOnly
        } else if s.eq_ignore_ascii_case("wo") {
            AccessType::WriteOnly
        } else if s.eq_ignore_ascii_case("rw") {
            AccessType::ReadWrite
        } else if s.eq_ignore_ascii_case("rwr") {
            AccessType::ReadWriteRead
        } else if s.eq_ignore_ascii_case("rww") {
            AccessType::ReadWriteWrite
        } else if s.eq_ignore_ascii_case("const") {
            AccessType::Const
        } else {
            return None;
        })
    }

    /// Whether an SDO client may read it.
    pub const fn readable(self) -> bool {
        !matches!(self, AccessType::WriteOnly)
    }

    /// Whether an SDO client may write it.
    pub const fn writable(self) -> bool {
        !matches!(self, AccessType::ReadOnly | AccessType::Const)
    }
}
