//! Electronic data sheets (CiA 306): the INI file that describes a node's object dictionary,
//! read through the `rust-ini` crate, so mappings and writes can be checked against a node's
//! dictionary before anything is sent.
//!
//! The objects are listed in `[MandatoryObjects]`, `[OptionalObjects]` and
//! `[ManufacturerObjects]` (`SupportedObjects=n`, then `1=0x1000`, …). A simple object has a
//! section named by its hex index (`[6040]`); an array or record has `SubNumber` and one
//! section per sub-index (`[1018sub0]`, `[1018sub1]`, …). Keys: `ParameterName`, `ObjectType`,
//! `DataType`, `AccessType`, `DefaultValue`, `PDOMapping`, `LowLimit`, `HighLimit`. Numbers are
//! decimal, `0x` hex or `0` octal; defaults may be relative to the node id (`$NODEID+0x180`).
//! Section and key names are case-insensitive.
//!
//! Every error names the section and key (and value) at fault.

use std::collections::{BTreeMap, HashMap};
use std::fmt;
use std::path::Path;

use super::object::{AccessType, DataType, ObjectType};
use super::pdo::{Direction, Entry};

/// Why an EDS is refused.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum EdsError {
    /// The file could not be read.
    Io {
        /// The path.
        path: String,
        /// The operating system's message.
        message: String,
    },
    /// Not INI syntax.
    Syntax {
        /// Line (1-based).
        line: usize,
        /// Column (1-based).
        column: usize,
        /// What the INI parser says.
        message: String,
    },
    /// A section the file needs is not there.
    MissingSection {
        /// The section.
        section: String,
        /// Why it is needed.
        needed_by: String,
    },
    /// A key is missing.
    MissingKey {
        /// The section.
        section: String,
        /// The key.
        key: &'static str,
    },
    /// A key's value is invalid.
    InvalidValue {
        /// The section.
        section: String,
        /// The key.
        key: String,
        /// The value.
        value: String,
        /// What was expected.
        expected: &'static str,
    },
}

impl fmt::Display for EdsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EdsError::Io { path, message } => write!(f, "{path}: {message}"),
            EdsError::Syntax {
                line,
                column,
                message,
            } => write!(f, "line {line}, column {column}: {message}"),
            EdsError::MissingSection { section, needed_by } => {
                write!(f, "section [{section}] is missing (needed by {needed_by})")
            }
            EdsError::MissingKey { section, key } => {
                write!(f, "section [{section}]: key {key} is missing")
            }
            EdsError::InvalidValue {
                section,
                key,
                value,
                expected,
            } => write!(
                f,
                "section [{section}], key {key}: `{value}` is not {expected}"
            ),
        }
    }
}

impl std::error::Error for EdsError {}

/// Why a use of an object is refused by the dictionary.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CheckError {
    /// No such object.
    NoObject {
        /// Index.
        index: u16,
    },
    /// No such sub-index.
    NoSub {
        /// Index.
        index: u16,
        /// Sub-index.
        sub: u8,
    },
    /// The object may not be mapped into a PDO.
    NotMappable {
        /// Index.
        index: u16,
        /// Sub-index.
        sub: u8,
    },
    /// The access type does not allow it (writing a read-only object, mapping a read-only
    /// object into an RPDO, …).
    Access {
        /// Index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// The object's access type.
        access: AccessType,
        /// What was attempted.
        attempted: &'static str,
    },
    /// The size does not match the data type.
    Size {
        /// Index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// The data type.
        data_type: DataType,
        /// Bits used.
        bits: u32,
    },
}

impl fmt::Display for CheckError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CheckError::NoObject { index } => {
                write!(f, "object {index:#06x} is not in the dictionary")
            }
            CheckError::NoSub { index, sub } => {
                write!(f, "object {index:#06x} has no sub-index {sub}")
            }
            CheckError::NotMappable { index, sub } => {
                write!(
                    f,
                    "object {index:#06x}:{sub:02x} may not be mapped into a PDO"
                )
            }
            CheckError::Access {
                index,
                sub,
                access,
                attempted,
            } => write!(
                f,
                "object {index:#06x}:{sub:02x} is {access:?}: cannot {attempted}"
            ),
            CheckError::Size {
                index,
                sub,
                data_type,
                bits,
            } => write!(
                f,
                "object {index:#06x}:{sub:02x} is {data_type} but {bits} bits were used"
            ),
        }
    }
}

impl std::error::Error for CheckError {}

/// A default value, possibly relative to the node id.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DefaultValue {
    /// A number (`$NODEID` added where it appeared).
    Number {
        /// The constant part.
        value: i128,
        /// Whether `$NODEID` is added.
        plus_node_id: bool,
    },
    /// Text (strings).
    Text(String),
}

impl DefaultValue {
    /// The number for node `node` (`None` for text).
    pub fn number(&self, node: u8) -> Option<i128> {
        match self {
            DefaultValue::Number {
                value,
                plus_node_id,
            } => Some(value + if *plus_node_id { i128::from(node) } else { 0 }),
            DefaultValue::Text(_) => None,
        }
    }
}

/// One sub-index (or the single value of a `VAR`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SubObject {
    /// `ParameterName`.
    pub name: String,
    /// `DataType`.
    pub data_type: DataType,
    /// `AccessType`.
    pub access: AccessType,
    /// `DefaultValue`, if given.
    pub default: Option<DefaultValue>,
    /// `PDOMapping`.
    pub pdo_mappable: bool,
    /// `LowLimit`, if given.
    pub low_limit: Option<i128>,
    /// `HighLimit`, if given.
    pub high_limit: Option<i128>,
}

/// One object.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Object {
    /// Its index.
    pub index: u16,
    /// `ParameterName`.
    pub name: String,
    /// `ObjectType`.
    pub object_type: ObjectType,
    /// Its sub-indexes (a `VAR` has only sub 0).
    pub subs: BTreeMap<u8, SubObject>,
}

/// `[DeviceInfo]`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct DeviceInfo {
    /// `VendorName`.
    pub vendor_name: String,
    /// `VendorNumber`.
    pub vendor_number: u32,
    /// `ProductName`.
    pub product_name: String,
    /// `ProductNumber`.
    pub product_number: u32,
    /// `RevisionNumber`.
    pub revision_number: u32,
}

/// A parsed EDS.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Eds {
    /// `[DeviceInfo]`.
    pub device: DeviceInfo,
    /// The objects by index.
    pub objects: BTreeMap<u16, Object>,
}

/// A section: its name as written, and its keys (lower case) → (key as written, value).
type Section = (String, HashMap<String, (String, String)>);
type Sections = HashMap<String, Section>;

struct Reader {
    sections: Sections,
}

impl Reader {
    fn section(&self, name: &str) -> Option<&Section> {
        self.sections.get(&name.to_ascii_lowercase())
    }

    fn get(&self, section: &str, key: &'static str) -> Option<(&str, &str)> {
        let (_, keys) = self.section(section)?;
        keys.get(&key.to_ascii_lowercase())
            .map(|(k, v)| (k.as_str(), v.as_str()))
    }

    fn require(&self, section: &str, key: &'static str) -> Result<(&str, &str), EdsError> {
        self.get(section, key).ok_or_else(|| EdsError::MissingKey {
            section: self.name(section),
            key,
        })
    }

    /// The section's name as written in the file.
    fn name(&self, section: &str) -> String {
        self.section(section)
            .map_or_else(|| section.to_owned(), |(n, _)| n.clone())
    }

    fn number(&self, section: &str, key: &'static str) -> Result<Option<i128>, EdsError> {
        match self.get(section, key) {
            None => Ok(None),
            Some((_, v)) if v.trim().is_empty() => Ok(None),
            Some((k, v)) => parse_number(v)
                .map(Some)
                .ok_or_else(|| self.invalid(section, k, v, "a number")),
        }
    }

    fn invalid(&self, section: &str, key: &str, value: &str, expected: &'static str) -> EdsError {
        EdsError::InvalidValue {
            section: self.name(section),
            key: key.to_owned(),
            value: value.to_owned(),
            expected,
        }
    }
}

/// Parses a CiA 306 number: decimal, `0x` hex, or octal with a leading `0`.
pub fn parse_number(s: &str) -> Option<i128> {
    let s = s.trim();
    let (neg, s) = match s.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, s),
    };
    let v = if let Some(h) = s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        i128::from_str_radix(h, 16).ok()?
    } else if s.len() > 1 && s.starts_with('0') {
        i128::from_str_radix(&s[1..], 8).ok()?
    } else {
        s.parse::<i128>().ok()?
    };
    Some(if neg { -v } else { v })
}

fn parse_default(s: &str) -> Option<DefaultValue> {
    let t = s.trim();
    let upper = t.to_ascii_uppercase();
    if let Some(pos) = upper.find("$NODEID") {
        let rest = format!("{}{}", &t[..pos], &t[pos + 7..]);
        let rest = rest.trim().trim_matches('+').trim();
        let value = if rest.is_empty() {
            0
        } else {
            parse_number(rest)?
        };
        return Some(DefaultValue::Number {
            value,
            plus_node_id: true,
        });
    }
    Some(DefaultValue::Number {
        value: parse_number(t)?,
        plus_node_id: false,
    })
}

impl Eds {
    /// Reads an EDS file (at most 16 MiB, a regular file: rl-core's bounded reader; the EDS
    /// of a large drive is under 1 MB).
    pub fn load(path: &Path) -> Result<Self, EdsError> {
        let text = rl_core::loader::read_text(path, 16 << 20).map_err(|e| EdsError::Io {
            path: path.display().to_string(),
            message: e.kind.to_string(),
        })?;
        Self::parse(&text)
    }

    /// Parses EDS text.
    pub fn parse(text: &str) -> Result<Self, EdsError> {
        let ini = ini::Ini::load_from_str_opt(
            text,
            ini::ParseOption {
                enabled_quote: false,
                enabled_escape: false,
                ..ini::ParseOption::default()
            },
        )
        .map_err(|e| EdsError::Syntax {
            line: e.line,
            column: e.col,
            message: e.msg.to_string(),
        })?;
        let mut sections: Sections = HashMap::new();
        for (name, props) in ini.iter() {
            let Some(name) = name else { continue };
            let entry = sections
                .entry(name.trim().to_ascii_lowercase())
                .or_insert_with(|| (name.trim().to_owned(), HashMap::new()));
            for (k, v) in props.iter() {
                entry.1.insert(
                    k.trim().to_ascii_lowercase(),
                    (k.trim().to_owned(), v.trim().to_owned()),
                );
            }
        }
        let r = Reader { sections };
        let device = DeviceInfo {
            vendor_name: r
                .get("DeviceInfo", "VendorName")
                .map(|(_, v)| v.to_owned())
                .unwrap_or_default(),
            vendor_number: r.number("DeviceInfo", "VendorNumber")?.unwrap_or(0) as u32,
            product_name: r
                .get("DeviceInfo", "ProductName")
                .map(|(_, v)| v.to_owned())
                .unwrap_or_default(),
            product_number: r.number("DeviceInfo", "ProductNumber")?.unwrap_or(0) as u32,
            revision_number: r.number("DeviceInfo", "RevisionNumber")?.unwrap_or(0) as u32,
        };
        let mut objects = BTreeMap::new();
        let mut listed_any = false;
        for list in ["MandatoryObjects", "OptionalObjects", "ManufacturerObjects"] {
            if r.section(list).is_none() {
                continue;
            }
            listed_any = true;
            let count =
                r.number(list, "SupportedObjects")?
                    .ok_or_else(|| EdsError::MissingKey {
                        section: r.name(list),
                        key: "SupportedObjects",
                    })?;
            for k in 1..=count {
                let key = k.to_string();
                let (_, keys) = r.section(list).ok_or_else(|| EdsError::MissingSection {
                    section: list.to_owned(),
                    needed_by: "the object lists".to_owned(),
                })?;
                let (kname, v) = keys.get(&key).ok_or_else(|| EdsError::InvalidValue {
                    section: r.name(list),
                    key: key.clone(),
                    value: String::new(),
                    expected: "an object index (SupportedObjects counts it)",
                })?;
                let index = parse_number(v)
                    .and_then(|i| u16::try_from(i).ok())
                    .ok_or_else(|| r.invalid(list, kname, v, "an object index 0x0000..0xFFFF"))?;
                let object = read_object(&r, index, list)?;
                objects.insert(index, object);
            }
        }
        if !listed_any {
            return Err(EdsError::MissingSection {
                section: "MandatoryObjects".to_owned(),
                needed_by: "every EDS (CiA 306)".to_owned(),
            });
        }
        Ok(Self { device, objects })
    }

    /// The sub-object `index:sub` (sub 0 of a `VAR` is the value).
    pub fn sub(&self, index: u16, sub: u8) -> Result<&SubObject, CheckError> {
        let o = self
            .objects
            .get(&index)
            .ok_or(CheckError::NoObject { index })?;
        o.subs.get(&sub).ok_or(CheckError::NoSub { index, sub })
    }

    /// Checks that `entry` may be mapped into a PDO of `direction`: the object exists, may be
    /// mapped, is readable (TPDO) or writable (RPDO), and has `entry.bits` bits.
    pub fn check_mapping(&self, direction: Direction, entry: Entry) -> Result<(), CheckError> {
        let (index, sub) = (entry.index, entry.sub);
        let s = self.sub(index, sub)?;
        if !s.pdo_mappable {
            return Err(CheckError::NotMappable { index, sub });
        }
        let ok = match direction {
            Direction::Rpdo => s.access.writable(),
            Direction::Tpdo => s.access.readable(),
        };
        if !ok {
            return Err(CheckError::Access {
                index,
                sub,
                access: s.access,
                attempted: match direction {
                    Direction::Rpdo => "map it into an RPDO",
                    Direction::Tpdo => "map it into a TPDO",
                },
            });
        }
        if s.data_type.bits() != Some(u32::from(entry.bits)) {
            return Err(CheckError::Size {
                index,
                sub,
                data_type: s.data_type,
                bits: u32::from(entry.bits),
            });
        }
        Ok(())
    }

    /// Checks that `len` bytes may be written to `index:sub` by SDO.
    pub fn check_write(&self, index: u16, sub: u8, len: usize) -> Result<(), CheckError> {
        let s = self.sub(index, sub)?;
        if !s.access.writable() {
            return Err(CheckError::Access {
                index,
                sub,
                access: s.access,
                attempted: "write it",
            });
        }
        if let Some(bits) = s.data_type.bits() {
            if bits.div_ceil(8) as usize != len {
                return Err(CheckError::Size {
                    index,
                    sub,
                    data_type: s.data_type,
                    bits: 8 * len as u32,
                });
            }
        }
        Ok(())
    }

    /// Checks that `index:sub` may be read by SDO.
    pub fn check_read(&self, index: u16, sub: u8) -> Result<(), CheckError> {
        let s = self.sub(index, sub)?;
        if !s.access.readable() {
            return Err(CheckError::Access {
                index,
                sub,
                access: s.access,
                attempted: "read it",
            });
        }
        Ok(())
    }
}

fn read_sub(r: &Reader, section: &str) -> Result<SubObject, EdsError> {
    let name = r.require(section, "ParameterName")?.1.to_owned();
    let (dk, dv) = r.require(section, "DataType")?;
    let data_type = parse_number(dv)
        .and_then(|c| u32::try_from(c).ok())
        .and_then(DataType::from_code)
        .ok_or_else(|| r.invalid(section, dk, dv, "a data type index (0x0001..0x001B)"))?;
    let (ak, av) = r.require(section, "AccessType")?;
    let access = AccessType::parse(av).ok_or_else(|| {
        r.invalid(
            section,
            ak,
            av,
            "an access type (ro, wo, rw, rwr, rww, const)",
        )
    })?;
    let default = match r.get(section, "DefaultValue") {
        None => None,
        Some((_, "")) => None,
        Some((k, v)) => Some(match data_type {
            DataType::VisibleString
            | DataType::OctetString
            | DataType::UnicodeString
            | DataType::Domain => DefaultValue::Text(v.to_owned()),
            _ => parse_default(v)
                .ok_or_else(|| r.invalid(section, k, v, "a number or $NODEID+number"))?,
        }),
    };
    let pdo_mappable = match r.get(section, "PDOMapping") {
        None => false,
        Some((_, "0")) => false,
        Some((_, "1")) => true,
        Some((k, v)) => return Err(r.invalid(section, k, v, "0 or 1")),
    };
    Ok(SubObject {
        name,
        data_type,
        access,
        default,
        pdo_mappable,
        low_limit: r.number(section, "LowLimit")?,
        high_limit: r.number(section, "HighLimit")?,
    })
}

fn read_object(r: &Reader, index: u16, list: &str) -> Result<Object, EdsError> {
    let section = format!("{index:04X}");
    if r.section(&section).is_none() {
        return Err(EdsError::MissingSection {
            section,
            needed_by: format!("[{}]", r.name(list)),
        });
    }
    let name = r.require(&section, "ParameterName")?.1.to_owned();
    let object_type = match r.get(&section, "ObjectType") {
        None => ObjectType::Var,
        Some((k, v)) => parse_number(v)
            .and_then(|c| u32::try_from(c).ok())
            .and_then(ObjectType::from_code)
            .ok_or_else(|| {
                r.invalid(
                    &section,
                    k,
                    v,
                    "an object type (0x7 VAR, 0x8 ARRAY, 0x9 RECORD, …)",
                )
            })?,
    };
    let mut subs = BTreeMap::new();
    if object_type.has_subs() {
        let (nk, nv) = r.require(&section, "SubNumber")?;
        let count = parse_number(nv)
            .filter(|n| (1..=256).contains(n))
            .ok_or_else(|| r.invalid(&section, nk, nv, "a sub-index count 1..=256"))?;
        // Sub-indexes need not be contiguous: look for each of 0..=255 until `count` are found.
        for sub in 0..=255u8 {
            if subs.len() as i128 == count {
                break;
            }
            let s = format!("{section}sub{sub:X}");
            if r.section(&s).is_some() {
                subs.insert(sub, read_sub(r, &s)?);
            }
        }
        if subs.len() as i128 != count {
            return Err(EdsError::MissingSection {
                section: format!("{section}sub…"),
                needed_by: format!("[{section}] SubNumber={nv} (found {})", subs.len()),
            });
        }
    } else {
        subs.insert(0, read_sub(r, &section)?);
    }
    Ok(Object {
        index,
        name,
        object_type,
        subs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINI: &str = "\
[DeviceInfo]
VendorName=rl-rs
VendorNumber=0x1234
ProductName=mini

[MandatoryObjects]
SupportedObjects=2
1=0x1000
2=0x1018

[OptionalObjects]
SupportedObjects=1
1=0x6040

[1000]
ParameterName=Device type
ObjectType=0x7
DataType=0x0007
AccessType=ro
DefaultValue=0x00020192
PDOMapping=0

[1018]
ParameterName=Identity
ObjectType=0x9
SubNumber=2

[1018sub0]
ParameterName=Highest sub-index supported
DataType=0x0005
AccessType=const
DefaultValue=1

[1018sub1]
ParameterName=Vendor-ID
DataType=0x0007
AccessType=ro
DefaultValue=0x1234

[6040]
ParameterName=Controlword
DataType=0x0006
AccessType=rww
PDOMapping=1
DefaultValue=$NODEID+0x180
";

    #[test]
    fn objects_subs_and_checks() {
        let eds = Eds::parse(MINI).unwrap();
        assert_eq!(eds.device.vendor_number, 0x1234);
        assert_eq!(eds.objects.len(), 3);
        assert_eq!(eds.sub(0x1018, 1).unwrap().name, "Vendor-ID");
        let cw = eds.sub(0x6040, 0).unwrap();
        assert_eq!(cw.default.as_ref().unwrap().number(5), Some(0x185));
        eds.check_mapping(Direction::Rpdo, Entry::new(0x6040, 0, 16))
            .unwrap();
        assert_eq!(
            eds.check_mapping(Direction::Rpdo, Entry::new(0x6040, 0, 32)),
            Err(CheckError::Size {
                index: 0x6040,
                sub: 0,
                data_type: DataType::Unsigned16,
                bits: 32
            })
        );
        assert!(matches!(
            eds.check_mapping(Direction::Tpdo, Entry::new(0x1000, 0, 32)),
            Err(CheckError::NotMappable { .. })
        ));
        assert!(matches!(
            eds.check_write(0x1018, 1, 4),
            Err(CheckError::Access { .. })
        ));
        assert_eq!(
            eds.check_read(0x6041, 0),
            Err(CheckError::NoObject { index: 0x6041 })
        );
        assert_eq!(parse_number("010"), Some(8));
        assert_eq!(parse_number("-12"), Some(-12));
    }

    #[test]
    fn a_bad_eds_names_the_section_and_key() {
        let bad = MINI.replace("DataType=0x0006", "DataType=0x0099");
        assert_eq!(
            Eds::parse(&bad).unwrap_err().to_string(),
            "section [6040], key DataType: `0x0099` is not a data type index (0x0001..0x001B)"
        );
        let bad = MINI.replace("AccessType=rww", "AccessType=sometimes");
        assert!(
            Eds::parse(&bad)
                .unwrap_err()
                .to_string()
                .starts_with("section [6040], key AccessType")
        );
        let bad = MINI
            .replace("[1018sub1]", "[1018sub7]")
            .replace("SubNumber=2", "SubNumber=3");
        assert!(matches!(
            Eds::parse(&bad),
            Err(EdsError::MissingSection { .. })
        ));
        let bad = MINI.replace("ParameterName=Device type\n", "");
        assert_eq!(
            Eds::parse(&bad).unwrap_err(),
            EdsError::MissingKey {
                section: "1000".into(),
                key: "ParameterName"
            }
        );
        let bad = MINI.replace("2=0x1018", "2=0x2000");
        assert_eq!(
            Eds::parse(&bad).unwrap_err().to_string(),
            "section [2000] is missing (needed by [MandatoryObjects])"
        );
        let e = Eds::parse("[DeviceInfo]\n[x").unwrap_err();
        assert!(matches!(e, EdsError::Syntax { line: 2, .. }), "{e:?}");
    }
}
