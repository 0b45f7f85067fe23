//! RIHS01 type hashes, as ROS 2 (Iron and later) computes them for the key expressions and
//! liveliness tokens of rmw_zenoh: the SHA-256 of the type's description — its fields and those
//! of every type it refers to, without default values or comments — written as JSON, shown as
//! `RIHS01_` and 64 lowercase hex digits.
//!
//! The JSON is Python's `json.dumps` of
//! `{"type_description": T, "referenced_type_descriptions": [R...]}` with its default
//! separators (`", "`, `": "`), each description `{"type_name": ..., "fields": [{"name": ...,
//! "type": {"type_id": ..., "capacity": ..., "string_capacity": ..., "nested_type_name": ...}}]}`
//! and the referenced types sorted by name (rosidl_generator_type_description; ROS 2's
//! `type_description_interfaces/msg/FieldType` numbers the types). The tests check the result
//! against hashes ROS 2 Jazzy reports and against PyPI `rosbags`.

use core::fmt::Write as _;

use sha2::{Digest, Sha256};

/// A field's type, as `type_description_interfaces/msg/FieldType` numbers them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldType {
    /// Another message, named.
    Nested(&'static str),
    /// `uint8`.
    U8,
    /// `int32`.
    I32,
    /// `uint32`.
    U32,
    /// `float64`.
    F64,
    /// `string` (unbounded).
    String,
}

impl FieldType {
    fn id(self) -> u8 {
        match self {
            Self::Nested(_) => 1,
            Self::U8 => 3,
            Self::I32 => 6,
            Self::U32 => 7,
            Self::F64 => 11,
            Self::String => 17,
        }
    }

    fn nested(self) -> &'static str {
        match self {
            Self::Nested(name) => name,
            _ => "",
        }
    }
}

/// How many values a field holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// One.
    Single,
    /// An unbounded sequence `T[]`.
    Sequence,
}

/// One field of a message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Field {
    /// Its name.
    pub name: &'static str,
    /// Its element type.
    pub ty: FieldType,
    /// One value or a sequence.
    pub shape: Shape,
}

/// A field holding one value.
pub const fn one(name: &'static str, ty: FieldType) -> Field {
    Field {
        name,
        ty,
        shape: Shape::Single,
    }
}

/// A field holding an unbounded sequence.
pub const fn seq(name: &'static str, ty: FieldType) -> Field {
    Field {
        name,
        ty,
        shape: Shape::Sequence,
    }
}

/// A message type: its full name (`sensor_msgs/msg/JointState`) and fields in order.
#[derive(Debug)]
pub struct TypeDescription {
    /// `package/msg/Name`.
    pub name: &'static str,
    /// The fields.
    pub fields: &'static [Field],
    /// The message types its fields name, directly (each with its own).
    pub nested: &'static [&'static TypeDescription],
}

impl TypeDescription {
    /// The DDS type name rmw_zenoh puts in key expressions: `sensor_msgs::msg::dds_::JointState_`.
    pub fn dds_name(&self) -> String {
        let (package_and_kind, name) = self.name.rsplit_once('/').unwrap_or(("", self.name));
        format!("{}::dds_::{name}_", package_and_kind.replace('/', "::"))
    }

    /// The JSON text whose SHA-256 is the RIHS01 hash.
    pub fn hashed_json(&self) -> String {
        let mut referenced: Vec<&TypeDescription> = Vec::new();
        collect(self, &mut referenced);
        referenced.retain(|t| t.name != self.name);
        referenced.sort_by(|a, b| a.name.cmp(b.name));
        referenced.dedup_by(|a, b| a.name == b.name);
        let mut s = String::from("{\"type_description\": ");
        write_type(&mut s, self);
        s.push_str(", \"referenced_type_descriptions\": [");
        for (k, t) in referenced.iter().enumerate() {
            if k > 0 {
                s.push_str(", ");
            }
            write_type(&mut s, t);
        }
        s.push_str("]}");
        s
    }

    /// The RIHS01 hash: `RIHS01_` and 64 lowercase hex digits.
    pub fn rihs01(&self) -> String {
        let digest = Sha256::digest(self.hashed_json().as_bytes());
        let mut s = String::with_capacity(71);
        s.push_str("RIHS01_");
        for b in digest {
            let _ = write!(s, "{b:02x}");
        }
        s
    }
}

fn collect<'a>(t: &'a TypeDescription, out: &mut Vec<&'a TypeDescription>) {
    for n in t.nested {
        if !out.iter().any(|o| o.name == n.name) {
            out.push(n);
            collect(n, out);
        }
    }
}

fn write_type(s: &mut String, t: &TypeDescription) {
    // Names here are ASCII identifiers and slashes: no JSON escaping is needed.
    let _ = write!(s, "{{\"type_name\": \"{}\", \"fields\": [", t.name);
    for (k, f) in t.fields.iter().enumerate() {
        if k > 0 {
            s.push_str(", ");
        }
        let id = f.ty.id()
            + match f.shape {
                Shape::Single => 0,
                Shape::Sequence => 144,
            };
        let _ = write!(
            s,
            "{{\"name\": \"{}\", \"type\": {{\"type_id\": {id}, \"capacity\": 0, \
             \"string_capacity\": 0, \"nested_type_name\": \"{}\"}}}}",
            f.name,
            f.ty.nested()
        );
    }
    s.push_str("]}");
}
