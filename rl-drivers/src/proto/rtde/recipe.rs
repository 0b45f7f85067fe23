//! A recipe: the fields of a data package, in order, with their types and offsets; built from
//! the controller's answer to a setup (its comma-separated types) or from the types of known
//! variables. Reading a field of a payload checks its type and bounds.

use heapless::Vec;

use super::types::DataType;
use super::{MAX_PACKAGE, RtdeError};

/// A recipe of at most `N` fields.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Recipe<const N: usize> {
    fields: Vec<(DataType, usize), N>,
    size: usize,
}

impl<const N: usize> Recipe<N> {
    /// An empty recipe.
    pub const fn new() -> Self {
        Self {
            fields: Vec::new(),
            size: 0,
        }
    }

    /// Appends a field.
    pub fn push(&mut self, t: DataType) -> Result<(), RtdeError> {
        self.fields
            .push((t, self.size))
            .map_err(|_| RtdeError::RecipeTooLong(N))?;
        self.size += t.size();
        if self.size > MAX_PACKAGE {
            return Err(RtdeError::TooLong {
                what: "recipe",
                expected: MAX_PACKAGE,
                got: self.size,
            });
        }
        Ok(())
    }

    /// The recipe of the controller's answer: types, comma-separated (an empty entry, from a
    /// trailing comma, is skipped). `NOT_FOUND` and `IN_USE` are [`RtdeError::RecipeRefused`].
    pub fn from_types(types: &str) -> Result<Self, RtdeError> {
        let mut r = Self::new();
        for (k, t) in types.split(',').filter(|t| !t.is_empty()).enumerate() {
            match t {
                "NOT_FOUND" => {
                    return Err(RtdeError::RecipeRefused {
                        field: k,
                        in_use: false,
                    });
                }
                "IN_USE" => {
                    return Err(RtdeError::RecipeRefused {
                        field: k,
                        in_use: true,
                    });
                }
                t => r.push(DataType::from_name(t)?)?,
            }
        }
        Ok(r)
    }

    /// Number of fields.
    pub fn len(&self) -> usize {
        self.fields.len()
    }

    /// Whether it has no field.
    pub fn is_empty(&self) -> bool {
        self.fields.is_empty()
    }

    /// Bytes of a data package's values.
    pub const fn size(&self) -> usize {
        self.size
    }

    /// Field `i`'s type.
    pub fn data_type(&self, i: usize) -> Option<DataType> {
        self.fields.get(i).map(|f| f.0)
    }

    /// The types in order.
    pub fn types(&self) -> impl Iterator<Item = DataType> + '_ {
        self.fields.iter().map(|f| f.0)
    }

    /// Checks a payload's length against the recipe.
    pub fn check(&self, payload: &[u8]) -> Result<(), RtdeError> {
        if payload.len() != self.size {
            return Err(if payload.len() < self.size {
                RtdeError::TooShort {
                    what: "data package",
                    need: self.size,
                    got: payload.len(),
                }
            } else {
                RtdeError::TooLong {
                    what: "data package",
                    expected: self.size,
                    got: payload.len(),
                }
            });
        }
        Ok(())
    }

    fn bytes<'p>(&self, payload: &'p [u8], i: usize, t: DataType) -> Option<&'p [u8]> {
        let &(ft, at) = self.fields.get(i)?;
        if ft != t {
            return None;
        }
        payload.get(at..at + t.size())
    }

    /// Field `i` as a `DOUBLE` (`None` if it is not one, or the payload is short).
    pub fn f64(&self, payload: &[u8], i: usize) -> Option<f64> {
        let b = self.bytes(payload, i, DataType::Double)?;
        Some(f64::from_be_bytes(b.try_into().ok()?))
    }

    /// Field `i` as an `INT32`.
    pub fn i32(&self, payload: &[u8], i: usize) -> Option<i32> {
        let b = self.bytes(payload, i, DataType::Int32)?;
        Some(i32::from_be_bytes(b.try_into().ok()?))
    }

    /// Field `i` as a `UINT32`.
    pub fn u32(&self, payload: &[u8], i: usize) -> Option<u32> {
        let b = self.bytes(payload, i, DataType::Uint32)?;
        Some(u32::from_be_bytes(b.try_into().ok()?))
    }

    /// Field `i` as a `UINT64`.
    pub fn u64(&self, payload: &[u8], i: usize) -> Option<u64> {
        let b = self.bytes(payload, i, DataType::Uint64)?;
        Some(u64::from_be_bytes(b.try_into().ok()?))
    }

    /// Field `i` as a `UINT8`.
    pub fn u8(&self, payload: &[u8], i: usize) -> Option<u8> {
        Some(self.bytes(payload, i, DataType::Uint8)?[0])
    }

    /// Field `i` as a `BOOL`.
    pub fn bool(&self, payload: &[u8], i: usize) -> Option<bool> {
        Some(self.bytes(payload, i, DataType::Bool)?[0] != 0)
    }

    /// Field `i` as a `VECTOR6D`.
    pub fn vector6d(&self, payload: &[u8], i: usize) -> Option<[f64; 6]> {
        let b = self.bytes(payload, i, DataType::Vector6d)?;
        let mut out = [0.0; 6];
        for (k, o) in out.iter_mut().enumerate() {
            *o = f64::from_be_bytes(b[8 * k..8 * k + 8].try_into().ok()?);
        }
        Some(out)
    }

    /// Field `i` as a `VECTOR6INT32`.
    pub fn vector6i32(&self, payload: &[u8], i: usize) -> Option<[i32; 6]> {
        let b = self.bytes(payload, i, DataType::Vector6Int32)?;
        let mut out = [0; 6];
        for (k, o) in out.iter_mut().enumerate() {
            *o = i32::from_be_bytes(b[4 * k..4 * k + 4].try_into().ok()?);
        }
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_and_typed_reads() {
        let r = Recipe::<8>::from_types("DOUBLE,VECTOR6D,INT32,UINT64,").unwrap();
        assert_eq!((r.len(), r.size()), (4, 8 + 48 + 4 + 8));
        let mut p = [0u8; 68];
        p[0..8].copy_from_slice(&1.5f64.to_be_bytes());
        p[8 + 40..8 + 48].copy_from_slice(&(-2.0f64).to_be_bytes());
        p[56..60].copy_from_slice(&7i32.to_be_bytes());
        p[60..68].copy_from_slice(&u64::MAX.to_be_bytes());
        assert_eq!(r.f64(&p, 0), Some(1.5));
        assert_eq!(r.vector6d(&p, 1).unwrap()[5], -2.0);
        assert_eq!(r.i32(&p, 2), Some(7));
        assert_eq!(r.u64(&p, 3), Some(u64::MAX));
        assert_eq!(r.f64(&p, 2), None, "wrong type");
        assert_eq!(r.f64(&p, 9), None, "no such field");
        assert!(r.check(&p).is_ok());
        assert!(r.check(&p[..67]).is_err());
        assert_eq!(
            Recipe::<8>::from_types("DOUBLE,NOT_FOUND"),
            Err(RtdeError::RecipeRefused {
                field: 1,
                in_use: false
            })
        );
        assert_eq!(
            Recipe::<8>::from_types("IN_USE"),
            Err(RtdeError::RecipeRefused {
                field: 0,
                in_use: true
            })
        );
        assert_eq!(
            Recipe::<1>::from_types("DOUBLE,DOUBLE"),
            Err(RtdeError::RecipeTooLong(1))
        );
        assert_eq!(
            Recipe::<4>::from_types("FLOAT"),
            Err(RtdeError::UnknownDataType)
        );
    }
}
