//! What a fake device is, in a few lines: identity, name, ESC, mailbox, process data objects,
//! distributed-clock support and the object dictionary behind them. From a description the
//! fake generates the SII EEPROM image a master reads ([`DeviceDescription::sii`]) and the
//! object dictionary its CoE server answers from ([`DeviceDescription::dictionary`]), so the
//! two always agree, as they do in a real device's ESI file and firmware.

use super::axis::MotorParams;
use super::dictionary::{Access, Dictionary, le_bytes, mapping_subs, sub};
use super::esc::EscIdentity;
use crate::cia402::object as obj;
use crate::proto::canopen::object::DataType;
use crate::proto::canopen::pdo::Entry;
use crate::proto::ecat::mailbox::MailboxType;
use crate::proto::ecat::sii::{
    self, CategoryType, DcMode, General, MailboxWindow, PdoEntry, PdoHeader, SiiHeader,
    SiiSyncManager, SiiWriter, SmUsage,
};
use crate::proto::ecat::sync_manager::{Kind, SyncManager};

/// The vendor id of the fake devices. Not an ETG-assigned id: "RL" in the low bytes.
pub const FAKE_VENDOR_ID: u32 = 0x0000_524C;
/// The product code of the fake CiA 402 drive (profile 402, model 1).
pub const FAKE_DRIVE_PRODUCT: u32 = 0x0402_0001;
/// The product code of the fake coupler.
pub const FAKE_COUPLER_PRODUCT: u32 = 0x0000_1100;

/// One process data object of a description.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PdoDescription {
    /// Its index (0x1600.. RxPDO, 0x1A00.. TxPDO).
    pub index: u16,
    /// Its name.
    pub name: String,
    /// Its entries (index 0: padding) with their names.
    pub entries: Vec<(Entry, String)>,
}

/// What a device does behind its process data.
#[derive(Clone, Debug, PartialEq)]
pub enum Profile {
    /// A CiA 402 servo drive with one axis.
    Cia402 {
        /// The motor.
        motor: MotorParams,
        /// Position at power-up in counts.
        initial_position: i32,
        /// Software position limits in counts (min, max; equal: none).
        limits: (i32, i32),
        /// Whether the drive needs DC SYNC0 to leave PRE-OP (as most drives in CSP do): it
        /// refuses SAFE-OP with AL status code 0x0030 without it.
        requires_dc: bool,
    },
    /// No application (a coupler), or one whose objects are listed in `extra_objects`.
    Plain,
}

/// A device.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceDescription {
    /// The name (SII general name string, 0x1008).
    pub name: String,
    /// The group name.
    pub group: String,
    /// The order number.
    pub order: String,
    /// Vendor id.
    pub vendor_id: u32,
    /// Product code.
    pub product_code: u32,
    /// Revision.
    pub revision: u32,
    /// Serial number.
    pub serial: u32,
    /// The ESC.
    pub esc: EscIdentity,
    /// Mailbox out (size 0: no mailbox).
    pub mailbox_out: MailboxWindow,
    /// Mailbox in.
    pub mailbox_in: MailboxWindow,
    /// Start of the outputs sync manager (SM2).
    pub outputs_start: u16,
    /// Start of the inputs sync manager (SM3).
    pub inputs_start: u16,
    /// Receive PDOs (master → device), assigned to SM2 in this order.
    pub rx_pdos: Vec<PdoDescription>,
    /// Transmit PDOs (device → master), assigned to SM3.
    pub tx_pdos: Vec<PdoDescription>,
    /// The distributed-clock operation mode, if the device supports DC.
    pub dc: Option<DcMode>,
    /// CoE details of the SII general category.
    pub coe_details: u8,
    /// The application.
    pub profile: Profile,
    /// More objects: `(index, sub, type, access, mappable, value)`; sub > 0 makes a record.
    pub extra_objects: Vec<(u16, u8, DataType, Access, bool, Vec<u8>)>,
    /// A raw SII image to use instead of the generated one (a real device's EEPROM).
    pub sii_image: Option<Vec<u8>>,
    /// The firmware's reaction time in ns: AL control and mailbox messages are handled this
    /// long after they arrive (0: before the next frame).
    pub firmware_latency_ns: u64,
}

fn entry_name(index: u16, sub: u8) -> String {
    let known = [
        obj::CONTROLWORD,
        obj::STATUSWORD,
        obj::TARGET_POSITION,
        obj::TARGET_VELOCITY,
        obj::TARGET_TORQUE,
        obj::TORQUE_OFFSET,
        obj::MODES_OF_OPERATION,
        obj::MODES_DISPLAY,
        obj::POSITION_ACTUAL,
        obj::VELOCITY_ACTUAL,
        obj::TORQUE_ACTUAL,
        obj::ERROR_CODE,
    ];
    known
        .iter()
        .find(|o| o.index == index && o.sub == sub)
        .map_or_else(String::new, |o| o.name.to_string())
}

fn pdo(index: u16, name: &str, entries: &[Entry]) -> PdoDescription {
    PdoDescription {
        index,
        name: name.into(),
        entries: entries
            .iter()
            .map(|e| (*e, entry_name(e.index, e.sub)))
            .collect(),
    }
}

/// The fake drive's receive PDO 0x1600: controlword, target position, target velocity, target
/// torque, torque offset, modes of operation, 8 bits padding (16 bytes).
pub fn cia402_rx_entries() -> Vec<Entry> {
    vec![
        obj::CONTROLWORD.entry(),
        obj::TARGET_POSITION.entry(),
        obj::TARGET_VELOCITY.entry(),
        obj::TARGET_TORQUE.entry(),
        obj::TORQUE_OFFSET.entry(),
        obj::MODES_OF_OPERATION.entry(),
        Entry::new(0, 0, 8),
    ]
}

/// The fake drive's transmit PDO 0x1A00: statusword, position, velocity, torque, modes
/// display, 8 bits padding, error code (16 bytes).
pub fn cia402_tx_entries() -> Vec<Entry> {
    vec![
        obj::STATUSWORD.entry(),
        obj::POSITION_ACTUAL.entry(),
        obj::VELOCITY_ACTUAL.entry(),
        obj::TORQUE_ACTUAL.entry(),
        obj::MODES_DISPLAY.entry(),
        Entry::new(0, 0, 8),
        obj::ERROR_CODE.entry(),
    ]
}

impl DeviceDescription {
    /// A CiA 402 servo drive: serial `1000 + k`, standing at `initial_position` counts.
    pub fn cia402_drive(k: u32, initial_position: i32) -> Self {
        Self {
            name: "rl-rs CiA 402 axis".into(),
            group: "Drives".into(),
            order: "RL-AXIS-1".into(),
            vendor_id: FAKE_VENDOR_ID,
            product_code: FAKE_DRIVE_PRODUCT,
            revision: 1,
            serial: 1000 + k,
            esc: EscIdentity::ET1100,
            mailbox_out: MailboxWindow {
                offset: 0x1000,
                size: 128,
            },
            mailbox_in: MailboxWindow {
                offset: 0x1080,
                size: 128,
            },
            outputs_start: 0x1100,
            inputs_start: 0x1400,
            rx_pdos: vec![pdo(0x1600, "Outputs", &cia402_rx_entries())],
            tx_pdos: vec![pdo(0x1A00, "Inputs", &cia402_tx_entries())],
            dc: Some(DcMode {
                cycle_time_0: 0,
                shift_time_0: 0,
                shift_time_1: 0,
                sync1_factor: 0,
                assign_activate: 0x0300,
                sync0_factor: 1,
                name_index: 5,
            }),
            // SDO, SDO information would be bit 1 (not served), PDO assign and configuration.
            coe_details: 0x0D,
            profile: Profile::Cia402 {
                motor: MotorParams::default(),
                initial_position,
                limits: (0, 0),
                requires_dc: true,
            },
            extra_objects: Vec::new(),
            sii_image: None,
            firmware_latency_ns: 0,
        }
    }

    /// A coupler: an ESC with device emulation, no mailbox and no process data (like an
    /// EK1100).
    pub fn coupler(k: u32) -> Self {
        Self {
            name: "rl-rs coupler".into(),
            group: "Couplers".into(),
            order: "RL-COUPLER".into(),
            product_code: FAKE_COUPLER_PRODUCT,
            serial: 1000 + k,
            esc: EscIdentity {
                device_emulation: true,
                ..EscIdentity::ET1100
            },
            mailbox_out: MailboxWindow::default(),
            mailbox_in: MailboxWindow::default(),
            rx_pdos: Vec::new(),
            tx_pdos: Vec::new(),
            dc: None,
            coe_details: 0,
            profile: Profile::Plain,
            ..Self::cia402_drive(k, 0)
        }
    }

    /// Whether the device has a mailbox.
    pub fn has_mailbox(&self) -> bool {
        self.mailbox_out.size > 0 && self.mailbox_in.size > 0
    }

    /// Output bytes (SM2) of the default mapping.
    pub fn output_bytes(&self) -> usize {
        bits(&self.rx_pdos).div_ceil(8)
    }

    /// Input bytes (SM3) of the default mapping.
    pub fn input_bytes(&self) -> usize {
        bits(&self.tx_pdos).div_ceil(8)
    }

    /// The sync managers as the SII lists them (mailboxes first, then process data).
    pub fn sync_managers(&self) -> Vec<SiiSyncManager> {
        let mut v = Vec::new();
        let sm = |kind, start: u16, length: u16, usage| {
            let s = SyncManager::new(kind, start, length);
            SiiSyncManager {
                start: s.start,
                length: s.length,
                control: s.control,
                enable: 1,
                usage,
            }
        };
        if self.has_mailbox() {
            v.push(sm(
                Kind::MailboxOut,
                self.mailbox_out.offset,
                self.mailbox_out.size,
                SmUsage::MailboxOut,
            ));
            v.push(sm(
                Kind::MailboxIn,
                self.mailbox_in.offset,
                self.mailbox_in.size,
                SmUsage::MailboxIn,
            ));
        }
        if !self.rx_pdos.is_empty() || !self.tx_pdos.is_empty() {
            v.push(sm(
                Kind::Outputs,
                self.outputs_start,
                self.output_bytes() as u16,
                SmUsage::Outputs,
            ));
            v.push(sm(
                Kind::Inputs,
                self.inputs_start,
                self.input_bytes() as u16,
                SmUsage::Inputs,
            ));
        }
        v
    }

    /// The SII EEPROM image (the raw image if one was given).
    pub fn sii(&self) -> Vec<u8> {
        if let Some(img) = &self.sii_image {
            return img.clone();
        }
        let mut strings: Vec<Vec<u8>> = vec![
            self.name.clone().into_bytes(),
            self.group.clone().into_bytes(),
            self.order.clone().into_bytes(),
            b"Standard".to_vec(),
            b"DC SYNC0".to_vec(),
        ];
        let mut string_index = |s: &str| -> u8 {
            if s.is_empty() {
                return 0;
            }
            match strings.iter().position(|x| x == s.as_bytes()) {
                Some(i) => (i + 1) as u8,
                None => {
                    strings.push(s.as_bytes().to_vec());
                    strings.len() as u8
                }
            }
        };
        let pdo_bytes = |pdos: &[PdoDescription], sm: u8, index: &mut dyn FnMut(&str) -> u8| {
            let mut out = Vec::new();
            for p in pdos {
                let header = PdoHeader {
                    index: p.index,
                    entries: p.entries.len() as u8,
                    sync_manager: sm,
                    dc_sync: 0,
                    name_index: index(&p.name),
                    flags: 0,
                };
                let entries: Vec<PdoEntry> = p
                    .entries
                    .iter()
                    .map(|(e, name)| PdoEntry {
                        index: e.index,
                        sub: e.sub,
                        name_index: index(name),
                        data_type: data_type_code(e.bits),
                        bits: e.bits,
                    })
                    .collect();
                let mut buf = vec![0u8; 8 + 8 * entries.len()];
                sii::encode_pdo(&mut buf, &header, &entries);
                out.extend_from_slice(&buf);
            }
            out
        };
        let sm_base = if self.has_mailbox() { 2 } else { 0 };
        let tx = pdo_bytes(&self.tx_pdos, sm_base + 1, &mut string_index);
        let rx = pdo_bytes(&self.rx_pdos, sm_base, &mut string_index);
        let header = SiiHeader {
            esc_config: [
                u16::from(self.esc.pdi_control)
                    | u16::from(u8::from(self.esc.device_emulation) | (self.esc.esc_config & 0xFE))
                        << 8,
                0,
                0x03E8,
                0,
            ],
            alias: 0,
            vendor_id: self.vendor_id,
            product_code: self.product_code,
            revision: self.revision,
            serial: self.serial,
            mailbox_out: self.mailbox_out,
            mailbox_in: self.mailbox_in,
            mailbox_protocols: if self.has_mailbox() {
                MailboxType::Coe.sii_bit()
            } else {
                0
            },
            size: 0x000F,
            version: 1,
        };
        let mut buf = vec![0u8; 4096];
        let general = General {
            group_index: 2,
            image_index: 0,
            order_index: 3,
            name_index: 1,
            coe_details: self.coe_details,
            ds402_channels: u8::from(matches!(self.profile, Profile::Cia402 { .. })),
            flags: 0,
            ..General::default()
        };
        let sms = self.sync_managers();
        let mut fmmu_usage = Vec::new();
        if !self.rx_pdos.is_empty() {
            fmmu_usage.push(1);
        }
        if !self.tx_pdos.is_empty() {
            fmmu_usage.push(2);
        }
        if self.has_mailbox() {
            fmmu_usage.push(3);
        }
        let refs: Vec<&[u8]> = strings.iter().map(Vec::as_slice).collect();
        let n = (|| -> Result<usize, sii::SiiError> {
            let mut w = SiiWriter::new(&mut buf, &header)?;
            w.strings(&refs)?;
            w.category(CategoryType::General, 32, |d| {
                d.copy_from_slice(&general.encode(1))
            })?;
            if !fmmu_usage.is_empty() {
                w.category(CategoryType::Fmmu, fmmu_usage.len(), |d| {
                    d.copy_from_slice(&fmmu_usage)
                })?;
            }
            if !sms.is_empty() {
                w.category(CategoryType::SyncManager, 8 * sms.len(), |d| {
                    for (k, s) in sms.iter().enumerate() {
                        d[8 * k..8 * k + 8].copy_from_slice(&s.encode());
                    }
                })?;
            }
            if !tx.is_empty() {
                w.category(CategoryType::TxPdo, tx.len(), |d| d.copy_from_slice(&tx))?;
            }
            if !rx.is_empty() {
                w.category(CategoryType::RxPdo, rx.len(), |d| d.copy_from_slice(&rx))?;
            }
            if let Some(dc) = &self.dc {
                w.category(CategoryType::Dc, sii::DC_MODE_LEN, |d| {
                    d.copy_from_slice(&dc.encode())
                })?;
            }
            Ok(w.finish())
        })()
        .unwrap_or(0);
        buf.truncate(n);
        buf
    }

    /// The object dictionary: identity, sync manager types, PDO mapping and assignment, the
    /// CiA 402 objects for a drive, and the extra objects.
    pub fn dictionary(&self) -> Dictionary {
        use Access::{Ro, Rw, RwPreOp};
        use DataType::*;
        let mut d = Dictionary::new();
        let device_type: u32 = match self.profile {
            Profile::Cia402 { .. } => 0x0002_0192,
            Profile::Plain => 0,
        };
        d.var(
            0x1000,
            "device type",
            Unsigned32,
            Ro,
            false,
            le_bytes(i64::from(device_type), 4),
        );
        d.var(0x1001, "error register", Unsigned8, Ro, false, vec![0]);
        d.var(
            0x1008,
            "device name",
            VisibleString,
            Ro,
            false,
            self.name.clone().into_bytes(),
        );
        d.var(
            0x1009,
            "hardware version",
            VisibleString,
            Ro,
            false,
            b"1".to_vec(),
        );
        d.var(
            0x100A,
            "software version",
            VisibleString,
            Ro,
            false,
            b"rl-rs fake".to_vec(),
        );
        d.compound(
            0x1018,
            "identity",
            Ro,
            vec![
                (1, sub(Unsigned32, Ro, false, i64::from(self.vendor_id))),
                (2, sub(Unsigned32, Ro, false, i64::from(self.product_code))),
                (3, sub(Unsigned32, Ro, false, i64::from(self.revision))),
                (4, sub(Unsigned32, Ro, false, i64::from(self.serial))),
            ],
        );
        let sms = self.sync_managers();
        d.compound(
            0x1C00,
            "sync manager communication type",
            Ro,
            sms.iter()
                .enumerate()
                .map(|(k, s)| {
                    (
                        k as u8 + 1,
                        sub(Unsigned8, Ro, false, i64::from(s.usage.code())),
                    )
                })
                .collect(),
        );
        for p in self.rx_pdos.iter().chain(&self.tx_pdos) {
            let entries: Vec<Entry> = p.entries.iter().map(|(e, _)| *e).collect();
            d.compound(p.index, &p.name, RwPreOp, mapping_subs(&entries, 16));
            d.set_int(p.index, 0, entries.len() as i64);
        }
        for (index, name, pdos) in [
            (0x1C12u16, "RxPDO assign", &self.rx_pdos),
            (0x1C13, "TxPDO assign", &self.tx_pdos),
        ] {
            if self.has_mailbox() || !pdos.is_empty() {
                let subs = (1..=4u8)
                    .map(|k| {
                        let v = pdos
                            .get(usize::from(k) - 1)
                            .map_or(0, |p| i64::from(p.index));
                        (k, sub(Unsigned16, RwPreOp, false, v))
                    })
                    .collect();
                d.compound(index, name, RwPreOp, subs);
                d.set_int(index, 0, pdos.len() as i64);
            }
        }
        if self.dc.is_some() {
            for index in [0x1C32u16, 0x1C33] {
                d.compound(
                    index,
                    if index == 0x1C32 {
                        "SM output parameter"
                    } else {
                        "SM input parameter"
                    },
                    Ro,
                    vec![
                        (1, sub(Unsigned16, RwPreOp, false, 0)),
                        (2, sub(Unsigned32, Ro, false, 0)),
                        (3, sub(Unsigned32, Ro, false, 0)),
                        (4, sub(Unsigned16, Ro, false, 0x0007)),
                        (5, sub(Unsigned32, Ro, false, 125_000)),
                    ],
                );
            }
        }
        if let Profile::Cia402 { motor, limits, .. } = &self.profile {
            let var =
                |d: &mut Dictionary, o: obj::Object, access: Access, mappable: bool, v: i64| {
                    d.var(
                        o.index,
                        o.name,
                        o.data_type,
                        access,
                        mappable,
                        le_bytes(v, o.len()),
                    );
                };
            var(&mut d, obj::ERROR_CODE, Ro, true, 0);
            var(&mut d, obj::CONTROLWORD, Rw, true, 0);
            var(&mut d, obj::STATUSWORD, Ro, true, 0x0240);
            var(&mut d, obj::QUICK_STOP_OPTION, Rw, false, 2);
            var(&mut d, obj::MODES_OF_OPERATION, Rw, true, 8);
            var(&mut d, obj::MODES_DISPLAY, Ro, true, 8);
            var(&mut d, obj::POSITION_ACTUAL, Ro, true, 0);
            var(&mut d, obj::FOLLOWING_ERROR_WINDOW, Rw, false, 0);
            var(&mut d, obj::VELOCITY_ACTUAL, Ro, true, 0);
            var(&mut d, obj::TARGET_TORQUE, Rw, true, 0);
            var(&mut d, obj::MAX_TORQUE, Rw, true, 3000);
            var(
                &mut d,
                obj::MOTOR_RATED_TORQUE,
                Ro,
                false,
                (motor.units.rated_torque_nm * 1000.0).round() as i64,
            );
            var(&mut d, obj::TORQUE_ACTUAL, Ro, true, 0);
            var(&mut d, obj::TARGET_POSITION, Rw, true, 0);
            var(&mut d, obj::MAX_PROFILE_VELOCITY, Rw, false, 0);
            var(&mut d, obj::VELOCITY_OFFSET, Rw, true, 0);
            var(&mut d, obj::TORQUE_OFFSET, Rw, true, 0);
            var(&mut d, obj::FOLLOWING_ERROR_ACTUAL, Ro, true, 0);
            var(&mut d, obj::TARGET_VELOCITY, Rw, true, 0);
            let modes = obj::SUPPORTED_DRIVE_MODES;
            let bits = crate::cia402::Mode::CyclicPosition.supported_bit()
                | crate::cia402::Mode::CyclicVelocity.supported_bit()
                | crate::cia402::Mode::CyclicTorque.supported_bit();
            var(&mut d, modes, Ro, false, i64::from(bits));
            d.compound(
                0x607D,
                "software position limit",
                Ro,
                vec![
                    (1, sub(Integer32, Rw, false, i64::from(limits.0))),
                    (2, sub(Integer32, Rw, false, i64::from(limits.1))),
                ],
            );
            d.compound(
                0x60C2,
                "interpolation time period",
                Ro,
                vec![
                    (1, sub(Unsigned8, Rw, false, 1)),
                    (2, sub(Integer8, Rw, false, -3)),
                ],
            );
            if motor.unit_objects {
                // The factor group as the rationals the objects hold (values the fake cannot
                // write exactly are refused by `FakeSegment::spawn`).
                let u = &motor.units;
                for (index, name, value) in [
                    (0x608F, "position encoder resolution", u.counts_per_rev),
                    (0x6091, "gear ratio", u.gear_ratio),
                    (0x6092, "feed constant", u.units_per_rev()),
                ] {
                    let (n, den) = crate::cia402::units::ratio(value).unwrap_or((0, 1));
                    d.compound(
                        index,
                        name,
                        Ro,
                        vec![
                            (1, sub(Unsigned32, Ro, false, i64::from(n))),
                            (2, sub(Unsigned32, Ro, false, i64::from(den))),
                        ],
                    );
                }
            }
        }
        let mut records: std::collections::BTreeMap<u16, Vec<(u8, super::dictionary::Sub)>> =
            Default::default();
        for (index, s, t, access, mappable, value) in &self.extra_objects {
            if *s == 0 {
                d.var(*index, "", *t, *access, *mappable, value.clone());
            } else {
                records.entry(*index).or_default().push((
                    *s,
                    super::dictionary::Sub {
                        data: value.clone(),
                        data_type: *t,
                        access: *access,
                        mappable: *mappable,
                    },
                ));
            }
        }
        for (index, subs) in records {
            d.compound(index, "", Access::Ro, subs);
        }
        d
    }
}

fn bits(pdos: &[PdoDescription]) -> usize {
    pdos.iter()
        .flat_map(|p| p.entries.iter())
        .map(|(e, _)| usize::from(e.bits))
        .sum()
}

/// The CoE data type code of an entry of `bits` bits (padding and odd sizes as bit strings).
fn data_type_code(bits: u8) -> u8 {
    match bits {
        1 => 0x01,
        8 => 0x05,
        16 => 0x06,
        32 => 0x07,
        _ => 0x00,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::proto::ecat::sii::Sii;

    #[test]
    fn the_drive_description_makes_a_consistent_sii_and_dictionary() {
        let d = DeviceDescription::cia402_drive(3, 0);
        let img = d.sii();
        let sii = Sii::new(&img);
        assert!(sii.checksum_ok().unwrap());
        assert_eq!(sii.vendor_id(), Ok(FAKE_VENDOR_ID));
        assert_eq!(sii.serial(), Ok(1003));
        assert_eq!(sii.name(), Ok(&b"rl-rs CiA 402 axis"[..]));
        assert_eq!(sii.mailbox_protocols(), Ok(0x04));
        let sms: Vec<_> = sii.sync_managers().unwrap().collect();
        assert_eq!(sms.len(), 4);
        assert_eq!(
            (sms[2].start, sms[2].length, sms[2].usage),
            (0x1100, 16, SmUsage::Outputs)
        );
        let rx: Vec<_> = sii.pdos(false).map(Result::unwrap).collect();
        assert_eq!(rx[0].header.sync_manager, 2);
        assert_eq!(rx[0].bits(), 128);
        assert_eq!(
            sii.dc_modes().unwrap().next().unwrap().assign_activate,
            0x0300
        );
        let od = d.dictionary();
        assert_eq!(od.assigned(false), cia402_rx_entries());
        assert_eq!(od.assigned(true), cia402_tx_entries());
        assert_eq!(od.int(0x1018, 4), 1003);
        assert_eq!(od.int(0x1000, 0), 0x0002_0192);
        let c = DeviceDescription::coupler(0);
        let sii_c = c.sii();
        let s = Sii::new(&sii_c);
        assert_eq!(s.mailbox_out().unwrap().size, 0);
        assert_eq!(s.sync_managers().unwrap().count(), 0);
    }
}
