//! The slave information interface (SII): the device's EEPROM image as a master reads it
//! through registers 0x0500-0x050F (ETG.1000.6 §5.4, ETG.2010). Words, little-endian:
//!
//! | word | content | word | content |
//! |---|---|---|---|
//! | 0x00-0x03 | PDI control and configuration | 0x04 | station alias |
//! | 0x07 | checksum (CRC-8 of words 0-6) | 0x08 | vendor id (u32) |
//! | 0x0A | product code (u32) | 0x0C | revision (u32) |
//! | 0x0E | serial number (u32) | 0x14-0x17 | bootstrap mailbox out/in offset, size |
//! | 0x18/0x19 | standard mailbox out (master → device) offset, size | 0x1A/0x1B | mailbox in |
//! | 0x1C | mailbox protocols (bit 2 CoE) | 0x3E | EEPROM size (KiB − 1) |
//! | 0x3F | version | 0x40 | first category |
//!
//! Categories: a header `type u16 | size u16 (in words)` and the data, until type 0xFFFF:
//! 10 strings (a count, then length-prefixed strings, numbered from 1), 30 general, 40 FMMU
//! usage (a byte each), 41 sync managers (8 bytes each), 50 TxPDOs and 51 RxPDOs (an 8-byte PDO
//! header and 8-byte entries), 60 distributed clocks (24 bytes per operation mode).
//!
//! [`Sii`] reads an image without copying or allocating; [`SiiWriter`] writes one (the fake
//! segment's EEPROMs).

use core::fmt;

/// Word of the vendor id.
pub const WORD_VENDOR: u16 = 0x08;
/// Word of the product code.
pub const WORD_PRODUCT: u16 = 0x0A;
/// Word of the revision.
pub const WORD_REVISION: u16 = 0x0C;
/// Word of the serial number.
pub const WORD_SERIAL: u16 = 0x0E;
/// Word of the standard receive (master → device) mailbox offset.
pub const WORD_MAILBOX_OUT: u16 = 0x18;
/// Word of the standard send (device → master) mailbox offset.
pub const WORD_MAILBOX_IN: u16 = 0x1A;
/// Word of the supported mailbox protocols.
pub const WORD_MAILBOX_PROTOCOLS: u16 = 0x1C;
/// Word of the EEPROM size.
pub const WORD_SIZE: u16 = 0x3E;
/// Word of the first category.
pub const WORD_CATEGORIES: u16 = 0x40;

/// A category type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CategoryType {
    /// 10: strings.
    Strings,
    /// 20: data types.
    DataTypes,
    /// 30: general.
    General,
    /// 40: FMMU usage.
    Fmmu,
    /// 41: sync managers.
    SyncManager,
    /// 42: FMMU extended.
    FmmuExtended,
    /// 43: sync units.
    SyncUnit,
    /// 50: transmit PDOs (device → master).
    TxPdo,
    /// 51: receive PDOs (master → device).
    RxPdo,
    /// 60: distributed clocks.
    Dc,
    /// 0xFFFF: end.
    End,
    /// Anything else (vendor specific, reserved).
    Other(u16),
}

impl CategoryType {
    /// The type of a code (bit 15 of vendor categories is kept in `Other`).
    pub const fn from_code(code: u16) -> Self {
        match code {
            10 => CategoryType::Strings,
            20 => CategoryType::DataTypes,
            30 => CategoryType::General,
            40 => CategoryType::Fmmu,
            41 => CategoryType::SyncManager,
            42 => CategoryType::FmmuExtended,
            43 => CategoryType::SyncUnit,
            50 => CategoryType::TxPdo,
            51 => CategoryType::RxPdo,
            60 => CategoryType::Dc,
            0xFFFF => CategoryType::End,
            c => CategoryType::Other(c),
        }
    }

    /// The code.
    pub const fn code(self) -> u16 {
        match self {
            CategoryType::Strings => 10,
            CategoryType::DataTypes => 20,
            CategoryType::General => 30,
            CategoryType::Fmmu => 40,
            CategoryType::SyncManager => 41,
            CategoryType::FmmuExtended => 42,
            CategoryType::SyncUnit => 43,
            CategoryType::TxPdo => 50,
            CategoryType::RxPdo => 51,
            CategoryType::Dc => 60,
            CategoryType::End => 0xFFFF,
            CategoryType::Other(c) => c,
        }
    }
}

/// Why an image does not parse.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SiiError {
    /// The image ends before `need` bytes at byte `offset`.
    Truncated {
        /// Byte offset.
        offset: usize,
        /// Bytes needed there.
        need: usize,
    },
    /// A category's data is shorter than its type requires.
    CategoryTooShort {
        /// Its type code.
        kind: u16,
        /// Its word address.
        word: usize,
        /// Bytes it has.
        len: usize,
        /// Bytes it needs.
        need: usize,
    },
    /// A string index beyond the strings category.
    NoString {
        /// The index.
        index: u8,
    },
    /// The writer's buffer is full.
    Full {
        /// Bytes needed.
        need: usize,
        /// Capacity.
        capacity: usize,
    },
}

impl fmt::Display for SiiError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SiiError::Truncated { offset, need } => {
                write!(f, "SII image ends before {need} bytes at byte {offset:#x}")
            }
            SiiError::CategoryTooShort {
                kind,
                word,
                len,
                need,
            } => write!(
                f,
                "SII category {kind} at word {word:#x} has {len} bytes, needs {need}"
            ),
            SiiError::NoString { index } => write!(f, "SII has no string {index}"),
            SiiError::Full { need, capacity } => {
                write!(
                    f,
                    "SII image needs {need} bytes, the buffer holds {capacity}"
                )
            }
        }
    }
}

/// CRC-8 of the ESC configuration area (SII words 0-6): polynomial x⁸ + x² + x + 1, initial
/// value 0xFF, as the ESC checks it when it loads the EEPROM.
pub fn checksum(words_0_to_6: &[u8; 14]) -> u8 {
    crc8(words_0_to_6)
}

/// The SII's CRC-8 (polynomial 0x07, initial value 0xFF, not reflected) of any bytes.
pub fn crc8(bytes: &[u8]) -> u8 {
    let mut crc: u8 = 0xFF;
    for &b in bytes {
        crc ^= b;
        for _ in 0..8 {
            crc = if crc & 0x80 != 0 {
                (crc << 1) ^ 0x07
            } else {
                crc << 1
            };
        }
    }
    crc
}

/// A mailbox window: offset and size.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct MailboxWindow {
    /// Physical offset.
    pub offset: u16,
    /// Bytes.
    pub size: u16,
}

/// The general category (30), the fields a master uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct General {
    /// String index of the group.
    pub group_index: u8,
    /// String index of the image name.
    pub image_index: u8,
    /// String index of the order number.
    pub order_index: u8,
    /// String index of the device name.
    pub name_index: u8,
    /// CoE details: bit 0 SDO, 1 SDO information, 2 PDO assign, 3 PDO configuration, 4 upload
    /// at startup, 5 SDO complete access.
    pub coe_details: u8,
    /// FoE details.
    pub foe_details: u8,
    /// EoE details.
    pub eoe_details: u8,
    /// SoE channels.
    pub soe_channels: u8,
    /// DS402 channels.
    pub ds402_channels: u8,
    /// Flags: bit 0 enable SAFE-OP, 1 enable not-LRW, 2 mailbox data link layer, 3 identity
    /// in AL status code, 4 identity in physical memory.
    pub flags: u8,
    /// Current drawn from the E-bus in mA (negative: fed in).
    pub ebus_current_ma: i16,
}

/// Bytes of the general category a master needs.
pub const GENERAL_LEN: usize = 16;

impl General {
    fn decode(d: &[u8]) -> Self {
        Self {
            group_index: d[0],
            image_index: d[1],
            order_index: d[2],
            name_index: d[3],
            coe_details: d[5],
            foe_details: d[6],
            eoe_details: d[7],
            soe_channels: d[8],
            ds402_channels: d[9],
            flags: d[11],
            ebus_current_ma: i16::from_le_bytes([d[12], d[13]]),
        }
    }

    /// The 32 bytes as ETG.2010 lays them out (byte 4 `reserved` given, byte 14 the group
    /// index again).
    pub fn encode(&self, reserved: u8) -> [u8; 32] {
        let mut d = [0u8; 32];
        d[0] = self.group_index;
        d[1] = self.image_index;
        d[2] = self.order_index;
        d[3] = self.name_index;
        d[4] = reserved;
        d[5] = self.coe_details;
        d[6] = self.foe_details;
        d[7] = self.eoe_details;
        d[8] = self.soe_channels;
        d[9] = self.ds402_channels;
        d[11] = self.flags;
        d[12..14].copy_from_slice(&self.ebus_current_ma.to_le_bytes());
        d[14] = self.group_index;
        d
    }

    /// Whether the device supports SDO complete access.
    pub const fn complete_access(&self) -> bool {
        self.coe_details & 0x20 != 0
    }
}

/// What a sync manager entry of category 41 is for (its byte 7).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SmUsage {
    /// 0: unused.
    Unused,
    /// 1: mailbox out.
    MailboxOut,
    /// 2: mailbox in.
    MailboxIn,
    /// 3: process data outputs.
    Outputs,
    /// 4: process data inputs.
    Inputs,
    /// Another code.
    Other(u8),
}

impl SmUsage {
    /// The usage of a code.
    pub const fn from_code(c: u8) -> Self {
        match c {
            0 => SmUsage::Unused,
            1 => SmUsage::MailboxOut,
            2 => SmUsage::MailboxIn,
            3 => SmUsage::Outputs,
            4 => SmUsage::Inputs,
            c => SmUsage::Other(c),
        }
    }

    /// The code.
    pub const fn code(self) -> u8 {
        match self {
            SmUsage::Unused => 0,
            SmUsage::MailboxOut => 1,
            SmUsage::MailboxIn => 2,
            SmUsage::Outputs => 3,
            SmUsage::Inputs => 4,
            SmUsage::Other(c) => c,
        }
    }
}

/// One entry of the sync manager category (41).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SiiSyncManager {
    /// Physical start.
    pub start: u16,
    /// Default length (0 for process data sized by the mapping).
    pub length: u16,
    /// Control byte.
    pub control: u8,
    /// Enable byte (bit 0).
    pub enable: u8,
    /// Usage.
    pub usage: SmUsage,
}

impl SiiSyncManager {
    fn decode(d: &[u8]) -> Self {
        Self {
            start: u16::from_le_bytes([d[0], d[1]]),
            length: u16::from_le_bytes([d[2], d[3]]),
            control: d[4],
            enable: d[6],
            usage: SmUsage::from_code(d[7]),
        }
    }

    /// The 8 bytes.
    pub fn encode(&self) -> [u8; 8] {
        let s = self.start.to_le_bytes();
        let l = self.length.to_le_bytes();
        [
            s[0],
            s[1],
            l[0],
            l[1],
            self.control,
            0,
            self.enable,
            self.usage.code(),
        ]
    }
}

/// A PDO of category 50 or 51: its header.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PdoHeader {
    /// The PDO's object index (0x1600.., 0x1A00..).
    pub index: u16,
    /// Entries.
    pub entries: u8,
    /// The sync manager it is assigned to (0xFF: not assigned by default).
    pub sync_manager: u8,
    /// DC sync.
    pub dc_sync: u8,
    /// String index of its name.
    pub name_index: u8,
    /// Flags (bit 0 mandatory, 1 default, 4 fixed content…).
    pub flags: u16,
}

/// One entry of a PDO.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PdoEntry {
    /// Object index (0 for padding).
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// String index of its name.
    pub name_index: u8,
    /// CoE data type code.
    pub data_type: u8,
    /// Bits.
    pub bits: u8,
}

/// A PDO with its entries, borrowing the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pdo<'a> {
    /// The header.
    pub header: PdoHeader,
    entries: &'a [u8],
}

impl<'a> Pdo<'a> {
    /// Its entries.
    pub fn entries(&self) -> impl Iterator<Item = PdoEntry> + 'a {
        self.entries.chunks_exact(8).map(|e| PdoEntry {
            index: u16::from_le_bytes([e[0], e[1]]),
            sub: e[2],
            name_index: e[3],
            data_type: e[4],
            bits: e[5],
        })
    }

    /// Bits of all entries.
    pub fn bits(&self) -> u32 {
        self.entries().map(|e| u32::from(e.bits)).sum()
    }
}

/// One operation mode of the distributed clocks category (60).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DcMode {
    /// SYNC0 cycle time in ns (0: the master's cycle).
    pub cycle_time_0: u32,
    /// SYNC0 shift in ns.
    pub shift_time_0: u32,
    /// SYNC1 shift in ns.
    pub shift_time_1: u32,
    /// SYNC1 cycle factor.
    pub sync1_factor: i16,
    /// The value for register 0x0980/0x0981 (AssignActivate).
    pub assign_activate: u16,
    /// SYNC0 cycle factor.
    pub sync0_factor: i16,
    /// String index of the mode's name.
    pub name_index: u8,
}

/// Bytes of one DC mode.
pub const DC_MODE_LEN: usize = 24;

impl DcMode {
    /// The 24 bytes.
    pub fn encode(&self) -> [u8; DC_MODE_LEN] {
        let mut d = [0u8; DC_MODE_LEN];
        d[..4].copy_from_slice(&self.cycle_time_0.to_le_bytes());
        d[4..8].copy_from_slice(&self.shift_time_0.to_le_bytes());
        d[8..12].copy_from_slice(&self.shift_time_1.to_le_bytes());
        d[12..14].copy_from_slice(&self.sync1_factor.to_le_bytes());
        d[14..16].copy_from_slice(&self.assign_activate.to_le_bytes());
        d[16..18].copy_from_slice(&self.sync0_factor.to_le_bytes());
        d[18] = self.name_index;
        d
    }

    fn decode(d: &[u8]) -> Self {
        let u32_at = |i: usize| u32::from_le_bytes([d[i], d[i + 1], d[i + 2], d[i + 3]]);
        Self {
            cycle_time_0: u32_at(0),
            shift_time_0: u32_at(4),
            shift_time_1: u32_at(8),
            sync1_factor: i16::from_le_bytes([d[12], d[13]]),
            assign_activate: u16::from_le_bytes([d[14], d[15]]),
            sync0_factor: i16::from_le_bytes([d[16], d[17]]),
            name_index: d[18],
        }
    }
}

/// One category: type, where its data starts (word) and the data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Category<'a> {
    /// Its type.
    pub kind: CategoryType,
    /// Word address of its data.
    pub word: usize,
    /// Its data.
    pub data: &'a [u8],
}

/// An SII image (or its first part: everything a master read).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sii<'a> {
    bytes: &'a [u8],
}

impl<'a> Sii<'a> {
    /// An image of `bytes` (nothing is checked until read).
    pub const fn new(bytes: &'a [u8]) -> Self {
        Self { bytes }
    }

    /// The bytes.
    pub const fn bytes(&self) -> &'a [u8] {
        self.bytes
    }

    /// Word `word`.
    pub fn word(&self, word: u16) -> Result<u16, SiiError> {
        let o = usize::from(word) * 2;
        match self.bytes.get(o..o + 2) {
            Some(b) => Ok(u16::from_le_bytes([b[0], b[1]])),
            None => Err(SiiError::Truncated { offset: o, need: 2 }),
        }
    }

    /// The double word at `word`, `word + 1`.
    pub fn dword(&self, word: u16) -> Result<u32, SiiError> {
        Ok(u32::from(self.word(word)?) | u32::from(self.word(word + 1)?) << 16)
    }

    /// Vendor id.
    pub fn vendor_id(&self) -> Result<u32, SiiError> {
        self.dword(WORD_VENDOR)
    }

    /// Product code.
    pub fn product_code(&self) -> Result<u32, SiiError> {
        self.dword(WORD_PRODUCT)
    }

    /// Revision.
    pub fn revision(&self) -> Result<u32, SiiError> {
        self.dword(WORD_REVISION)
    }

    /// Serial number.
    pub fn serial(&self) -> Result<u32, SiiError> {
        self.dword(WORD_SERIAL)
    }

    /// The station alias (word 4).
    pub fn alias(&self) -> Result<u16, SiiError> {
        self.word(0x04)
    }

    /// The mailbox the master writes (offset and size; size 0: no mailbox).
    pub fn mailbox_out(&self) -> Result<MailboxWindow, SiiError> {
        Ok(MailboxWindow {
            offset: self.word(WORD_MAILBOX_OUT)?,
            size: self.word(WORD_MAILBOX_OUT + 1)?,
        })
    }

    /// The mailbox the master reads.
    pub fn mailbox_in(&self) -> Result<MailboxWindow, SiiError> {
        Ok(MailboxWindow {
            offset: self.word(WORD_MAILBOX_IN)?,
            size: self.word(WORD_MAILBOX_IN + 1)?,
        })
    }

    /// The supported mailbox protocols (bit 2: CoE).
    pub fn mailbox_protocols(&self) -> Result<u16, SiiError> {
        self.word(WORD_MAILBOX_PROTOCOLS)
    }

    /// Whether the stored checksum of words 0-6 is right.
    pub fn checksum_ok(&self) -> Result<bool, SiiError> {
        let Some(head) = self.bytes.get(..16) else {
            return Err(SiiError::Truncated {
                offset: 0,
                need: 16,
            });
        };
        let mut w = [0u8; 14];
        w.copy_from_slice(&head[..14]);
        Ok(checksum(&w) == head[14])
    }

    /// The categories, in order, up to the end marker or the end of the image.
    pub fn categories(&self) -> Categories<'a> {
        Categories {
            bytes: self.bytes,
            word: usize::from(WORD_CATEGORIES),
            done: false,
        }
    }

    /// The first category of `kind`.
    pub fn find(&self, kind: CategoryType) -> Result<Option<Category<'a>>, SiiError> {
        for c in self.categories() {
            let c = c?;
            if c.kind == kind {
                return Ok(Some(c));
            }
        }
        Ok(None)
    }

    /// String `index` (1-based; 0 is "no string" and gives `""`), as bytes.
    pub fn string(&self, index: u8) -> Result<&'a [u8], SiiError> {
        if index == 0 {
            return Ok(&[]);
        }
        let Some(c) = self.find(CategoryType::Strings)? else {
            return Err(SiiError::NoString { index });
        };
        let d = c.data;
        let count = *d.first().ok_or(SiiError::NoString { index })?;
        if index > count {
            return Err(SiiError::NoString { index });
        }
        let mut pos = 1usize;
        for k in 1..=index {
            let len = usize::from(*d.get(pos).ok_or(SiiError::Truncated {
                offset: c.word * 2 + pos,
                need: 1,
            })?);
            let s = d.get(pos + 1..pos + 1 + len).ok_or(SiiError::Truncated {
                offset: c.word * 2 + pos + 1,
                need: len,
            })?;
            if k == index {
                return Ok(s);
            }
            pos += 1 + len;
        }
        Err(SiiError::NoString { index })
    }

    /// The general category.
    pub fn general(&self) -> Result<Option<General>, SiiError> {
        let Some(c) = self.find(CategoryType::General)? else {
            return Ok(None);
        };
        if c.data.len() < GENERAL_LEN {
            return Err(SiiError::CategoryTooShort {
                kind: 30,
                word: c.word,
                len: c.data.len(),
                need: GENERAL_LEN,
            });
        }
        Ok(Some(General::decode(c.data)))
    }

    /// The device name (the general category's name string), as bytes.
    pub fn name(&self) -> Result<&'a [u8], SiiError> {
        match self.general()? {
            Some(g) => self.string(g.name_index),
            None => Ok(&[]),
        }
    }

    /// The FMMU usage bytes (category 40).
    pub fn fmmu_usage(&self) -> Result<&'a [u8], SiiError> {
        Ok(self.find(CategoryType::Fmmu)?.map_or(&[][..], |c| c.data))
    }

    /// The sync managers (category 41).
    pub fn sync_managers(&self) -> Result<impl Iterator<Item = SiiSyncManager> + 'a, SiiError> {
        let data = self
            .find(CategoryType::SyncManager)?
            .map_or(&[][..], |c| c.data);
        Ok(data.chunks_exact(8).map(SiiSyncManager::decode))
    }

    /// The PDOs of category 50 (TxPDO, `transmit = true`) or 51 (RxPDO), across all categories
    /// of that type.
    pub fn pdos(&self, transmit: bool) -> Pdos<'a> {
        Pdos {
            categories: self.categories(),
            kind: if transmit {
                CategoryType::TxPdo
            } else {
                CategoryType::RxPdo
            },
            data: &[],
            pos: 0,
            word: 0,
        }
    }

    /// The distributed-clock operation modes (category 60).
    pub fn dc_modes(&self) -> Result<impl Iterator<Item = DcMode> + 'a, SiiError> {
        let data = self.find(CategoryType::Dc)?.map_or(&[][..], |c| c.data);
        Ok(data.chunks_exact(DC_MODE_LEN).map(DcMode::decode))
    }
}

/// The categories of an image.
#[derive(Clone, Debug)]
pub struct Categories<'a> {
    bytes: &'a [u8],
    word: usize,
    done: bool,
}

impl<'a> Iterator for Categories<'a> {
    type Item = Result<Category<'a>, SiiError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        let o = self.word * 2;
        let Some(h) = self.bytes.get(o..o + 4) else {
            // An image cut right after the last category (no end marker read) ends here.
            self.done = true;
            return None;
        };
        let kind = CategoryType::from_code(u16::from_le_bytes([h[0], h[1]]));
        if kind == CategoryType::End {
            self.done = true;
            return None;
        }
        let words = usize::from(u16::from_le_bytes([h[2], h[3]]));
        let start = o + 4;
        let Some(data) = self.bytes.get(start..start + 2 * words) else {
            self.done = true;
            return Some(Err(SiiError::Truncated {
                offset: start,
                need: 2 * words,
            }));
        };
        self.word += 2 + words;
        Some(Ok(Category {
            kind,
            word: start / 2,
            data,
        }))
    }
}

/// The PDOs of one direction.
#[derive(Clone, Debug)]
pub struct Pdos<'a> {
    categories: Categories<'a>,
    kind: CategoryType,
    data: &'a [u8],
    pos: usize,
    word: usize,
}

impl<'a> Iterator for Pdos<'a> {
    type Item = Result<Pdo<'a>, SiiError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if self.pos + 8 <= self.data.len() {
                let d = &self.data[self.pos..];
                let header = PdoHeader {
                    index: u16::from_le_bytes([d[0], d[1]]),
                    entries: d[2],
                    sync_manager: d[3],
                    dc_sync: d[4],
                    name_index: d[5],
                    flags: u16::from_le_bytes([d[6], d[7]]),
                };
                let need = 8 + 8 * usize::from(header.entries);
                if d.len() < need {
                    self.data = &[];
                    return Some(Err(SiiError::CategoryTooShort {
                        kind: self.kind.code(),
                        word: self.word,
                        len: d.len(),
                        need,
                    }));
                }
                self.pos += need;
                return Some(Ok(Pdo {
                    header,
                    entries: &d[8..need],
                }));
            }
            match self.categories.next()? {
                Ok(c) if c.kind == self.kind => {
                    self.data = c.data;
                    self.pos = 0;
                    self.word = c.word;
                }
                Ok(_) => {}
                Err(e) => return Some(Err(e)),
            }
        }
    }
}

/// Writes an SII image into a caller's buffer: the header words, then categories, then the end
/// marker (allocation-free).
#[derive(Debug)]
pub struct SiiWriter<'a> {
    buf: &'a mut [u8],
    len: usize,
}

/// The identity and mailbox words of an image's header.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct SiiHeader {
    /// Words 0-3: PDI control, PDI configuration, SYNC impulse length, PDI configuration 2.
    pub esc_config: [u16; 4],
    /// Word 4: station alias.
    pub alias: u16,
    /// Vendor id.
    pub vendor_id: u32,
    /// Product code.
    pub product_code: u32,
    /// Revision.
    pub revision: u32,
    /// Serial number.
    pub serial: u32,
    /// Standard mailbox out.
    pub mailbox_out: MailboxWindow,
    /// Standard mailbox in.
    pub mailbox_in: MailboxWindow,
    /// Supported mailbox protocols.
    pub mailbox_protocols: u16,
    /// EEPROM size word (KiB − 1).
    pub size: u16,
    /// Version word.
    pub version: u16,
}

impl<'a> SiiWriter<'a> {
    /// Writes `header` (with its checksum) into `buf`; categories follow with
    /// [`category`](Self::category).
    pub fn new(buf: &'a mut [u8], header: &SiiHeader) -> Result<Self, SiiError> {
        let need = usize::from(WORD_CATEGORIES) * 2;
        if buf.len() < need {
            return Err(SiiError::Full {
                need,
                capacity: buf.len(),
            });
        }
        buf[..need].fill(0);
        let mut w = Self { buf, len: need };
        for (i, v) in header.esc_config.iter().enumerate() {
            w.put_word(i as u16, *v);
        }
        w.put_word(0x04, header.alias);
        let mut head = [0u8; 14];
        head.copy_from_slice(&w.buf[..14]);
        w.put_word(0x07, u16::from(checksum(&head)));
        w.put_dword(WORD_VENDOR, header.vendor_id);
        w.put_dword(WORD_PRODUCT, header.product_code);
        w.put_dword(WORD_REVISION, header.revision);
        w.put_dword(WORD_SERIAL, header.serial);
        w.put_word(WORD_MAILBOX_OUT, header.mailbox_out.offset);
        w.put_word(WORD_MAILBOX_OUT + 1, header.mailbox_out.size);
        w.put_word(WORD_MAILBOX_IN, header.mailbox_in.offset);
        w.put_word(WORD_MAILBOX_IN + 1, header.mailbox_in.size);
        w.put_word(WORD_MAILBOX_PROTOCOLS, header.mailbox_protocols);
        w.put_word(WORD_SIZE, header.size);
        w.put_word(0x3F, header.version);
        Ok(w)
    }

    fn put_word(&mut self, word: u16, v: u16) {
        let o = usize::from(word) * 2;
        self.buf[o..o + 2].copy_from_slice(&v.to_le_bytes());
    }

    fn put_dword(&mut self, word: u16, v: u32) {
        self.put_word(word, v as u16);
        self.put_word(word + 1, (v >> 16) as u16);
    }

    /// Appends a category of `kind` whose data is written by `fill` into a slice of `len` bytes
    /// (rounded up to whole words, padded with zero).
    pub fn category(
        &mut self,
        kind: CategoryType,
        len: usize,
        fill: impl FnOnce(&mut [u8]),
    ) -> Result<&mut Self, SiiError> {
        let words = len.div_ceil(2);
        let need = self.len + 4 + 2 * words;
        if need + 4 > self.buf.len() || words > usize::from(u16::MAX) {
            return Err(SiiError::Full {
                need: need + 4,
                capacity: self.buf.len(),
            });
        }
        let o = self.len;
        self.buf[o..o + 2].copy_from_slice(&kind.code().to_le_bytes());
        self.buf[o + 2..o + 4].copy_from_slice(&(words as u16).to_le_bytes());
        self.buf[o + 4..need].fill(0);
        fill(&mut self.buf[o + 4..o + 4 + len]);
        self.len = need;
        Ok(self)
    }

    /// Appends the strings category (`strings[0]` is string 1; each at most 255 bytes).
    pub fn strings(&mut self, strings: &[&[u8]]) -> Result<&mut Self, SiiError> {
        let len = 1 + strings.iter().map(|s| 1 + s.len().min(255)).sum::<usize>();
        self.category(CategoryType::Strings, len, |d| {
            d[0] = strings.len().min(255) as u8;
            let mut p = 1;
            for s in strings {
                let n = s.len().min(255);
                d[p] = n as u8;
                d[p + 1..p + 1 + n].copy_from_slice(&s[..n]);
                p += 1 + n;
            }
        })
    }

    /// Ends the image with the end marker and pads it with 0xFF to a whole KiB (as an
    /// erased EEPROM reads); returns its length in bytes.
    pub fn finish(self) -> usize {
        let o = self.len;
        self.buf[o..o + 2].copy_from_slice(&0xFFFFu16.to_le_bytes());
        self.buf[o + 2..o + 4].copy_from_slice(&0xFFFFu16.to_le_bytes());
        let end = (o + 4).next_multiple_of(1024).min(self.buf.len());
        self.buf[o + 4..end].fill(0xFF);
        end
    }
}

/// Encodes a PDO (header and entries) into `out` (at least `8 + 8 · entries.len()` bytes).
pub fn encode_pdo(out: &mut [u8], header: &PdoHeader, entries: &[PdoEntry]) -> usize {
    out[..2].copy_from_slice(&header.index.to_le_bytes());
    out[2] = entries.len() as u8;
    out[3] = header.sync_manager;
    out[4] = header.dc_sync;
    out[5] = header.name_index;
    out[6..8].copy_from_slice(&header.flags.to_le_bytes());
    for (k, e) in entries.iter().enumerate() {
        let d = &mut out[8 + 8 * k..16 + 8 * k];
        d[..2].copy_from_slice(&e.index.to_le_bytes());
        d[2] = e.sub;
        d[3] = e.name_index;
        d[4] = e.data_type;
        d[5] = e.bits;
        d[6] = 0;
        d[7] = 0;
    }
    8 + 8 * entries.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_checksum_is_crc8_poly_0x07_init_0xff() {
        // The check value of "123456789" by plain polynomial long division (poly 0x107, first
        // byte inverted for the initial value 0xFF), computed independently of this code.
        assert_eq!(crc8(b"123456789"), 0xFB);
        let mut w = [0u8; 14];
        w[..9].copy_from_slice(b"123456789");
        let c = checksum(&w);
        w[3] ^= 0x01;
        assert_ne!(checksum(&w), c);
    }

    #[test]
    fn an_image_written_reads_back() {
        let mut buf = [0u8; 2048];
        let header = SiiHeader {
            vendor_id: 0x0000_0A5A,
            product_code: 0x0402_0001,
            revision: 3,
            serial: 42,
            mailbox_out: MailboxWindow {
                offset: 0x1000,
                size: 128,
            },
            mailbox_in: MailboxWindow {
                offset: 0x1080,
                size: 128,
            },
            mailbox_protocols: 0x04,
            size: 1,
            version: 1,
            ..SiiHeader::default()
        };
        let mut w = SiiWriter::new(&mut buf, &header).unwrap();
        w.strings(&[b"Drives", b"rl-rs CiA 402 axis"]).unwrap();
        let g = General {
            group_index: 1,
            name_index: 2,
            coe_details: 0x23,
            ds402_channels: 1,
            ..General::default()
        };
        w.category(CategoryType::General, 32, |d| {
            d.copy_from_slice(&g.encode(1))
        })
        .unwrap();
        let sm = SiiSyncManager {
            start: 0x1100,
            length: 0,
            control: 0x64,
            enable: 1,
            usage: SmUsage::Outputs,
        };
        w.category(CategoryType::SyncManager, 8, |d| {
            d.copy_from_slice(&sm.encode())
        })
        .unwrap();
        let entries = [
            PdoEntry {
                index: 0x6040,
                sub: 0,
                name_index: 0,
                data_type: 6,
                bits: 16,
            },
            PdoEntry {
                index: 0x607A,
                sub: 0,
                name_index: 0,
                data_type: 4,
                bits: 32,
            },
        ];
        let ph = PdoHeader {
            index: 0x1600,
            entries: 2,
            sync_manager: 2,
            dc_sync: 0,
            name_index: 0,
            flags: 0,
        };
        w.category(CategoryType::RxPdo, 24, |d| {
            encode_pdo(d, &ph, &entries);
        })
        .unwrap();
        let n = w.finish();
        assert_eq!(n, 1024);
        let sii = Sii::new(&buf[..n]);
        assert!(sii.checksum_ok().unwrap());
        assert_eq!(sii.vendor_id(), Ok(0x0A5A));
        assert_eq!(sii.product_code(), Ok(0x0402_0001));
        assert_eq!(sii.mailbox_in().unwrap().offset, 0x1080);
        assert_eq!(sii.name(), Ok(&b"rl-rs CiA 402 axis"[..]));
        assert_eq!(sii.string(3), Err(SiiError::NoString { index: 3 }));
        assert!(sii.general().unwrap().unwrap().complete_access());
        assert_eq!(sii.sync_managers().unwrap().next(), Some(sm));
        let pdos: Vec<_> = sii.pdos(false).map(Result::unwrap).collect();
        assert_eq!(pdos.len(), 1);
        assert_eq!(pdos[0].header, ph);
        assert_eq!(pdos[0].bits(), 48);
        assert_eq!(pdos[0].entries().nth(1), Some(entries[1]));
        assert_eq!(sii.pdos(true).count(), 0);
        assert_eq!(sii.categories().count(), 4);
    }

    #[test]
    fn truncated_images_are_errors_not_panics() {
        let mut buf = [0u8; 256];
        let mut w = SiiWriter::new(&mut buf, &SiiHeader::default()).unwrap();
        w.strings(&[b"abc"]).unwrap();
        let n = w.finish();
        // Cut inside the strings category's data.
        let cut = Sii::new(&buf[..0x84]);
        assert!(matches!(
            cut.categories().next(),
            Some(Err(SiiError::Truncated { .. }))
        ));
        assert!(matches!(cut.string(1), Err(SiiError::Truncated { .. })));
        assert_eq!(Sii::new(&buf[..n]).string(1), Ok(&b"abc"[..]));
        assert!(matches!(
            Sii::new(&buf[..4]).vendor_id(),
            Err(SiiError::Truncated { .. })
        ));
    }
}
