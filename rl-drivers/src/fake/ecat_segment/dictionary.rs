//! The fake device's object dictionary: the objects its CoE SDO server reads and writes, the
//! PDO mapping and assignment objects (writable in PRE-OP only, checked as a device checks
//! them) and the packing of mapped objects into process data, bit by bit. The dictionary is the
//! one store of the device's values: the firmware unpacks outputs into it, the CiA 402 axis
//! reads its commands from it and writes its measurements back, and inputs are packed from it.

use std::collections::BTreeMap;

use crate::proto::canopen::object::DataType;
use crate::proto::canopen::pdo::Entry;
use crate::proto::canopen::sdo::{AbortCode, Address};
use crate::proto::canopen::sdo_server;

/// Who may write a sub-index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// Read only.
    Ro,
    /// Read and write.
    Rw,
    /// Writable in PRE-OP only (PDO mapping and assignment, sync parameters).
    RwPreOp,
}

/// One sub-index.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Sub {
    /// Its value, little-endian.
    pub data: Vec<u8>,
    /// Its type.
    pub data_type: DataType,
    /// Access.
    pub access: Access,
    /// Whether it can be mapped into process data.
    pub mappable: bool,
}

/// One object.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Object {
    /// Its name (0x1008-style text for SDO information and messages).
    pub name: String,
    /// Its sub-indices (a VAR has only sub 0).
    pub subs: BTreeMap<u8, Sub>,
    /// Whether it is an ARRAY or RECORD (sub 0 holds the count).
    pub compound: bool,
}

/// The object dictionary.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Dictionary {
    objects: BTreeMap<u16, Object>,
    /// Whether the device is in PRE-OP (PRE-OP-writable objects accept writes).
    pub pre_op: bool,
    /// Most bytes one PDO may map.
    pub max_pdo_bytes: usize,
}

/// An integer value as `len` little-endian bytes.
pub fn le_bytes(v: i64, len: usize) -> Vec<u8> {
    v.to_le_bytes()[..len.min(8)].to_vec()
}

impl Dictionary {
    /// An empty dictionary.
    pub fn new() -> Self {
        Self {
            objects: BTreeMap::new(),
            pre_op: false,
            max_pdo_bytes: 64,
        }
    }

    /// Adds (or replaces) a VAR object.
    pub fn var(
        &mut self,
        index: u16,
        name: &str,
        data_type: DataType,
        access: Access,
        mappable: bool,
        value: Vec<u8>,
    ) -> &mut Self {
        let mut subs = BTreeMap::new();
        subs.insert(
            0,
            Sub {
                data: value,
                data_type,
                access,
                mappable,
            },
        );
        self.objects.insert(
            index,
            Object {
                name: name.into(),
                subs,
                compound: false,
            },
        );
        self
    }

    /// Adds (or replaces) an ARRAY/RECORD: sub 0 = the count (u8), then `subs`.
    pub fn compound(
        &mut self,
        index: u16,
        name: &str,
        access0: Access,
        subs: Vec<(u8, Sub)>,
    ) -> &mut Self {
        let count = subs.iter().map(|(k, _)| *k).max().unwrap_or(0);
        let mut map = BTreeMap::new();
        map.insert(
            0,
            Sub {
                data: vec![count],
                data_type: DataType::Unsigned8,
                access: access0,
                mappable: false,
            },
        );
        for (k, s) in subs {
            map.insert(k, s);
        }
        self.objects.insert(
            index,
            Object {
                name: name.into(),
                subs: map,
                compound: true,
            },
        );
        self
    }

    /// The object at `index`.
    pub fn object(&self, index: u16) -> Option<&Object> {
        self.objects.get(&index)
    }

    /// Indices present.
    pub fn indices(&self) -> impl Iterator<Item = u16> + '_ {
        self.objects.keys().copied()
    }

    /// The bytes of `index:sub`.
    pub fn get(&self, index: u16, sub: u8) -> Option<&[u8]> {
        self.objects
            .get(&index)?
            .subs
            .get(&sub)
            .map(|s| s.data.as_slice())
    }

    /// `index:sub` as a sign-extended integer (0 if absent).
    pub fn int(&self, index: u16, sub: u8) -> i64 {
        let Some(s) = self.objects.get(&index).and_then(|o| o.subs.get(&sub)) else {
            return 0;
        };
        let mut b = [0u8; 8];
        let n = s.data.len().min(8);
        b[..n].copy_from_slice(&s.data[..n]);
        let v = i64::from_le_bytes(b);
        let signed = matches!(
            s.data_type,
            DataType::Integer8 | DataType::Integer16 | DataType::Integer32 | DataType::Integer64
        );
        if signed && n < 8 && n > 0 {
            let shift = 64 - 8 * n as u32;
            (v << shift) >> shift
        } else {
            v
        }
    }

    /// Stores an integer into `index:sub` (its length kept; absent objects are ignored).
    pub fn set_int(&mut self, index: u16, sub: u8, v: i64) {
        if let Some(s) = self
            .objects
            .get_mut(&index)
            .and_then(|o| o.subs.get_mut(&sub))
        {
            let n = s.data.len().min(8);
            s.data[..n].copy_from_slice(&v.to_le_bytes()[..n]);
        }
    }

    fn sub_mut(&mut self, a: Address) -> Result<&mut Sub, AbortCode> {
        let o = self.objects.get_mut(&a.index).ok_or(AbortCode::NO_OBJECT)?;
        o.subs.get_mut(&a.sub).ok_or(AbortCode::NO_SUB_INDEX)
    }

    /// Reads the whole object (complete access): sub 0 as 16 bits, then every sub-index.
    pub fn read_complete(&self, index: u16, out: &mut Vec<u8>) -> Result<(), AbortCode> {
        let o = self.objects.get(&index).ok_or(AbortCode::NO_OBJECT)?;
        if !o.compound {
            return Err(AbortCode::UNSUPPORTED_ACCESS);
        }
        let count = o.subs.get(&0).map_or(0, |s| s.data[0]);
        out.extend_from_slice(&[count, 0]);
        for k in 1..=count {
            if let Some(s) = o.subs.get(&k) {
                out.extend_from_slice(&s.data);
            }
        }
        Ok(())
    }

    /// Writes the whole object (complete access): sub 0 as 16 bits, then the sub-indices.
    pub fn write_complete(&mut self, index: u16, data: &[u8]) -> Result<(), AbortCode> {
        let o = self.objects.get(&index).ok_or(AbortCode::NO_OBJECT)?;
        if !o.compound || data.len() < 2 {
            return Err(AbortCode::UNSUPPORTED_ACCESS);
        }
        let count = data[0];
        let mut pos = 2;
        let mut values = Vec::new();
        for k in 1..=count {
            let len = o.subs.get(&k).ok_or(AbortCode::NO_SUB_INDEX)?.data.len();
            let v = data.get(pos..pos + len).ok_or(AbortCode::LENGTH_TOO_LOW)?;
            values.push((k, v.to_vec()));
            pos += len;
        }
        if pos != data.len() {
            return Err(AbortCode::LENGTH_TOO_HIGH);
        }
        sdo_server::Dictionary::write(self, Address::new(index, 0), &[0])?;
        for (k, v) in values {
            sdo_server::Dictionary::write(self, Address::new(index, k), &v)?;
        }
        sdo_server::Dictionary::write(self, Address::new(index, 0), &[count])
    }

    /// The entries of mapping object `index` (0x1600.., 0x1A00..), in order.
    pub fn mapping(&self, index: u16) -> Vec<Entry> {
        let n = self.int(index, 0) as u8;
        (1..=n)
            .filter_map(|k| self.get(index, k))
            .map(|d| Entry::from_u32(u32::from_le_bytes([d[0], d[1], d[2], d[3]])))
            .collect()
    }

    /// The entries of all PDOs assigned in 0x1C12 (outputs, `transmit = false`) or 0x1C13.
    pub fn assigned(&self, transmit: bool) -> Vec<Entry> {
        let assign = if transmit { 0x1C13 } else { 0x1C12 };
        let n = self.int(assign, 0) as u8;
        (1..=n)
            .flat_map(|k| self.mapping(self.int(assign, k) as u16))
            .collect()
    }

    /// Bits of a list of entries.
    pub fn bits(entries: &[Entry]) -> usize {
        entries.iter().map(|e| usize::from(e.bits)).sum()
    }

    /// Packs the values of `entries` into `out` bit by bit (padding entries are zero).
    pub fn pack(&self, entries: &[Entry], out: &mut [u8]) {
        out.fill(0);
        let mut bit = 0usize;
        for e in entries {
            let value = self.get(e.index, e.sub).unwrap_or(&[]);
            for b in 0..usize::from(e.bits) {
                let v = value
                    .get(b / 8)
                    .is_some_and(|byte| byte >> (b % 8) & 1 != 0);
                let at = bit + b;
                if v && at / 8 < out.len() {
                    out[at / 8] |= 1 << (at % 8);
                }
            }
            bit += usize::from(e.bits);
        }
    }

    /// Unpacks `data` into the objects of `entries`.
    pub fn unpack(&mut self, entries: &[Entry], data: &[u8]) {
        let mut bit = 0usize;
        for e in entries {
            if let Some(s) = self
                .objects
                .get_mut(&e.index)
                .and_then(|o| o.subs.get_mut(&e.sub))
            {
                for b in 0..usize::from(e.bits) {
                    let at = bit + b;
                    let v = data
                        .get(at / 8)
                        .is_some_and(|byte| byte >> (at % 8) & 1 != 0);
                    if let Some(byte) = s.data.get_mut(b / 8) {
                        if v {
                            *byte |= 1 << (b % 8);
                        } else {
                            *byte &= !(1 << (b % 8));
                        }
                    }
                }
            }
            bit += usize::from(e.bits);
        }
    }

    fn check_mapping_entry(&self, value: &[u8], transmit: bool) -> Result<(), AbortCode> {
        let v = u32::from_le_bytes(value.try_into().map_err(|_| AbortCode::LENGTH_MISMATCH)?);
        let e = Entry::from_u32(v);
        if e.index == 0 {
            return Ok(()); // padding
        }
        let s = self
            .objects
            .get(&e.index)
            .and_then(|o| o.subs.get(&e.sub))
            .ok_or(AbortCode::NOT_MAPPABLE)?;
        let writable = s.access != Access::Ro;
        if !s.mappable || (!transmit && !writable) || usize::from(e.bits) > s.data.len() * 8 {
            return Err(AbortCode::NOT_MAPPABLE);
        }
        Ok(())
    }
}

impl sdo_server::Dictionary for Dictionary {
    fn read(&mut self, address: Address, out: &mut [u8]) -> Result<usize, AbortCode> {
        let o = self
            .objects
            .get(&address.index)
            .ok_or(AbortCode::NO_OBJECT)?;
        let s = o.subs.get(&address.sub).ok_or(AbortCode::NO_SUB_INDEX)?;
        if s.data.len() > out.len() {
            return Err(AbortCode::OUT_OF_MEMORY);
        }
        out[..s.data.len()].copy_from_slice(&s.data);
        Ok(s.data.len())
    }

    fn write(&mut self, address: Address, data: &[u8]) -> Result<(), AbortCode> {
        let pre_op = self.pre_op;
        let index = address.index;
        let is_rx_mapping = (0x1600..0x1800).contains(&index);
        let is_tx_mapping = (0x1A00..0x1C00).contains(&index);
        let is_assign = index == 0x1C12 || index == 0x1C13;
        {
            let s = self.sub_mut(address)?;
            match s.access {
                Access::Ro => return Err(AbortCode::READ_ONLY),
                Access::RwPreOp if !pre_op => return Err(AbortCode::DEVICE_STATE),
                _ => {}
            }
            let strings = matches!(
                s.data_type,
                DataType::VisibleString | DataType::OctetString | DataType::Domain
            );
            if !strings && data.len() != s.data.len() {
                return Err(if data.len() > s.data.len() {
                    AbortCode::LENGTH_TOO_HIGH
                } else {
                    AbortCode::LENGTH_TOO_LOW
                });
            }
        }
        if is_rx_mapping || is_tx_mapping || is_assign {
            let count = self.int(index, 0);
            if address.sub == 0 {
                let n = *data.first().ok_or(AbortCode::LENGTH_TOO_LOW)?;
                let max = self.objects[&index].subs.len() as u8 - 1;
                if n > max {
                    return Err(AbortCode::VALUE_TOO_HIGH);
                }
                if is_assign {
                    for k in 1..=n {
                        let pdo = self.int(index, k) as u16;
                        let range = if index == 0x1C12 {
                            0x1600..0x1800
                        } else {
                            0x1A00..0x1C00
                        };
                        if !range.contains(&pdo) || !self.objects.contains_key(&pdo) {
                            return Err(AbortCode::INVALID_VALUE);
                        }
                    }
                } else {
                    let mut bits = 0usize;
                    for k in 1..=n {
                        let d = self.get(index, k).unwrap_or(&[0; 4]);
                        bits += usize::from(d[0]);
                    }
                    if bits > self.max_pdo_bytes * 8 {
                        return Err(AbortCode::PDO_TOO_LONG);
                    }
                }
            } else {
                if count != 0 {
                    // CiA 301: entries change only while sub 0 is 0.
                    return Err(AbortCode::DEVICE_STATE);
                }
                if !is_assign {
                    self.check_mapping_entry(data, is_tx_mapping)?;
                }
            }
        }
        let s = self.sub_mut(address)?;
        s.data.clear();
        s.data.extend_from_slice(data);
        Ok(())
    }
}

/// A sub-index description, for building objects.
pub fn sub(data_type: DataType, access: Access, mappable: bool, value: i64) -> Sub {
    let len = data_type.bits().map_or(0, |b| b.div_ceil(8) as usize);
    Sub {
        data: le_bytes(value, len),
        data_type,
        access,
        mappable,
    }
}

/// A mapping object's entries as sub-indices (writable in PRE-OP).
pub fn mapping_subs(entries: &[Entry], capacity: u8) -> Vec<(u8, Sub)> {
    (1..=capacity)
        .map(|k| {
            let v = entries.get(usize::from(k) - 1).map_or(0, |e| e.to_u32());
            (
                k,
                sub(DataType::Unsigned32, Access::RwPreOp, false, i64::from(v)),
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::proto::canopen::sdo_server::Dictionary as _;

    fn od() -> Dictionary {
        let mut d = Dictionary::new();
        d.var(
            0x6040,
            "controlword",
            DataType::Unsigned16,
            Access::Rw,
            true,
            vec![0, 0],
        );
        d.var(
            0x6041,
            "statusword",
            DataType::Unsigned16,
            Access::Ro,
            true,
            vec![0x40, 0x02],
        );
        d.var(
            0x6064,
            "position",
            DataType::Integer32,
            Access::Ro,
            true,
            le_bytes(-5, 4),
        );
        d.compound(
            0x1A00,
            "TxPDO",
            Access::RwPreOp,
            mapping_subs(&[Entry::new(0x6041, 0, 16), Entry::new(0x6064, 0, 32)], 8),
        );
        d.set_int(0x1A00, 0, 2);
        d.compound(
            0x1C13,
            "TxPDO assign",
            Access::RwPreOp,
            vec![(1, sub(DataType::Unsigned16, Access::RwPreOp, false, 0x1A00))],
        );
        d
    }

    #[test]
    fn mapping_rules_and_packing() {
        let mut d = od();
        assert_eq!(d.int(0x6064, 0), -5);
        assert_eq!(d.assigned(true).len(), 2);
        let mut buf = [0u8; 6];
        d.pack(&d.assigned(true), &mut buf);
        assert_eq!(buf, [0x40, 0x02, 0xFB, 0xFF, 0xFF, 0xFF]);
        // Not in PRE-OP: the mapping is read-only for now.
        let a = Address::new(0x1A00, 0);
        assert_eq!(d.write(a, &[0]), Err(AbortCode::DEVICE_STATE));
        d.pre_op = true;
        // Entries change only while sub 0 is 0.
        let e = Entry::new(0x6064, 0, 32).to_u32().to_le_bytes();
        assert_eq!(
            d.write(Address::new(0x1A00, 1), &e),
            Err(AbortCode::DEVICE_STATE)
        );
        d.write(a, &[0]).unwrap();
        d.write(Address::new(0x1A00, 1), &e).unwrap();
        // A missing object cannot be mapped; nor a read-only one into outputs.
        let bad = Entry::new(0x2000, 0, 8).to_u32().to_le_bytes();
        assert_eq!(
            d.write(Address::new(0x1A00, 2), &bad),
            Err(AbortCode::NOT_MAPPABLE)
        );
        d.write(a, &[1]).unwrap();
        assert_eq!(d.assigned(true), vec![Entry::new(0x6064, 0, 32)]);
        assert_eq!(
            d.write(Address::new(0x6041, 0), &[0, 0]),
            Err(AbortCode::READ_ONLY)
        );
        assert_eq!(
            d.write(Address::new(0x6040, 0), &[0]),
            Err(AbortCode::LENGTH_TOO_LOW)
        );
        // Bits: unpack a 1-bit entry.
        d.unpack(&[Entry::new(0x6040, 0, 1)], &[0b1]);
        assert_eq!(d.int(0x6040, 0), 1);
        d.unpack(&[Entry::new(0, 0, 1), Entry::new(0x6040, 0, 1)], &[0b01]);
        assert_eq!(d.int(0x6040, 0), 0);
        let mut ca = Vec::new();
        d.read_complete(0x1C13, &mut ca).unwrap();
        assert_eq!(ca, [1, 0, 0x00, 0x1A]);
    }
}
