//! The EtherCAT master's acyclic services: scanning the segment (count the devices with BRD,
//! reset their registers, assign station addresses with APWR, read every SII EEPROM), register
//! reads and writes by station address with working-counter checks, and the AL state machine
//! (request a state, wait for it bounded in time, name the AL status code when a device
//! refuses). These run in `open`, `start` and `stop`, never in `step`.

use std::time::{Duration, Instant};

use super::error::{DeviceRef, EcError};
use super::link::Link;
use crate::proto::ecat::al::{AlControl, AlState, AlStatus, AlStatusCode};
use crate::proto::ecat::command::Command;
use crate::proto::ecat::datagram::{DatagramHeader, physical, position};
use crate::proto::ecat::frame::MacAddr;
use crate::proto::ecat::register::{self as reg, DlStatus};
use crate::proto::ecat::sii::{MailboxWindow, Sii, SiiError, SiiSyncManager, SmUsage};

/// First station address assigned (device k gets `STATION_BASE + k`).
pub const STATION_BASE: u16 = 0x1001;
/// Most SII bytes read from one device.
pub const SII_MAX_BYTES: usize = 8192;

/// How the master talks to the segment.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MasterConfig {
    /// The network interface.
    pub interface: String,
    /// The source address of our frames.
    pub source: MacAddr,
    /// Bound on one setup datagram's round trip.
    pub frame_timeout: Duration,
    /// Retries of a setup datagram whose frame was lost.
    pub retries: u32,
    /// Bound on one AL state change.
    pub state_timeout: Duration,
    /// Bound on one mailbox exchange.
    pub mailbox_timeout: Duration,
    /// Most devices accepted.
    pub max_devices: usize,
    /// How long to poll for a reply without sleeping before waiting in the kernel
    /// ([`Link::set_spin`]).
    pub spin: Duration,
}

impl MasterConfig {
    /// Defaults for `interface`: 20 ms per setup frame with 3 retries, 5 s per AL state change,
    /// 1 s per mailbox exchange, 64 devices, replies polled for 50 µs before sleeping.
    pub fn new(interface: &str) -> Self {
        Self {
            interface: interface.into(),
            source: MacAddr::MASTER,
            frame_timeout: Duration::from_millis(20),
            retries: 3,
            state_timeout: Duration::from_secs(5),
            mailbox_timeout: Duration::from_secs(1),
            max_devices: 64,
            spin: Duration::from_micros(50),
        }
    }
}

/// A PDO as the SII lists it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SiiPdo {
    /// Its index.
    pub index: u16,
    /// Its sync manager.
    pub sync_manager: u8,
    /// Its entries: index, sub-index, bits.
    pub entries: Vec<(u16, u8, u8)>,
}

/// One device found on the segment, with what its SII says.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SubDevice {
    /// Position from the master.
    pub position: u16,
    /// Configured station address.
    pub station: u16,
    /// Station alias from the SII.
    pub alias: u16,
    /// Vendor id.
    pub vendor_id: u32,
    /// Product code.
    pub product_code: u32,
    /// Revision.
    pub revision: u32,
    /// Serial number.
    pub serial: u32,
    /// Name (SII general name string).
    pub name: String,
    /// ESC type register.
    pub esc_type: u8,
    /// ESC features (0x0008).
    pub features: u16,
    /// FMMUs the ESC has.
    pub fmmu_count: u8,
    /// Sync managers the ESC has.
    pub sm_count: u8,
    /// DL status after the scan (which ports lead on).
    pub dl_status: DlStatus,
    /// Mailbox out (size 0: none).
    pub mailbox_out: MailboxWindow,
    /// Mailbox in.
    pub mailbox_in: MailboxWindow,
    /// Supported mailbox protocols (SII word 0x1C).
    pub mailbox_protocols: u16,
    /// CoE details (SII general).
    pub coe_details: u8,
    /// Sync managers (SII category 41).
    pub sync_managers: Vec<SiiSyncManager>,
    /// FMMU usage bytes (SII category 40).
    pub fmmu_usage: Vec<u8>,
    /// Receive PDOs (SII category 51).
    pub rx_pdos: Vec<SiiPdo>,
    /// Transmit PDOs (SII category 50).
    pub tx_pdos: Vec<SiiPdo>,
    /// SII AssignActivate of its DC mode (0: no DC category).
    pub dc_assign_activate: u16,
    /// The mailbox counter of the next message (1..=7).
    pub mailbox_counter: u8,
}

impl SubDevice {
    /// Its reference for messages.
    pub fn reference(&self) -> DeviceRef {
        DeviceRef {
            position: self.position,
            station: self.station,
        }
    }

    /// Whether it has a CoE mailbox.
    pub fn has_coe(&self) -> bool {
        self.mailbox_out.size > 0 && self.mailbox_in.size > 0 && self.mailbox_protocols & 0x04 != 0
    }

    /// Whether its ESC has distributed clocks.
    pub fn has_dc(&self) -> bool {
        self.features & reg::FEATURE_DC != 0
    }

    /// Whether its ESC keeps 64-bit system time.
    pub fn has_dc64(&self) -> bool {
        self.features & reg::FEATURE_DC64 != 0
    }

    /// The sync manager (number, SII entry) used for `usage`.
    pub fn sync_manager(&self, usage: SmUsage) -> Option<(u8, SiiSyncManager)> {
        self.sync_managers
            .iter()
            .enumerate()
            .find(|(_, s)| s.usage == usage)
            .map(|(n, s)| (n as u8, *s))
    }

    fn from_sii(position: u16, sii: &Sii<'_>) -> Result<Self, SiiError> {
        let name = String::from_utf8_lossy(sii.name()?).into_owned();
        let general = sii.general()?.unwrap_or_default();
        let pdos = |transmit| -> Result<Vec<SiiPdo>, SiiError> {
            sii.pdos(transmit)
                .map(|p| {
                    p.map(|p| SiiPdo {
                        index: p.header.index,
                        sync_manager: p.header.sync_manager,
                        entries: p.entries().map(|e| (e.index, e.sub, e.bits)).collect(),
                    })
                })
                .collect()
        };
        Ok(Self {
            position,
            station: STATION_BASE + position,
            alias: sii.alias()?,
            vendor_id: sii.vendor_id()?,
            product_code: sii.product_code()?,
            revision: sii.revision()?,
            serial: sii.serial()?,
            name,
            esc_type: 0,
            features: 0,
            fmmu_count: 0,
            sm_count: 0,
            dl_status: DlStatus(0),
            mailbox_out: sii.mailbox_out()?,
            mailbox_in: sii.mailbox_in()?,
            mailbox_protocols: sii.mailbox_protocols()?,
            coe_details: general.coe_details,
            sync_managers: sii.sync_managers()?.collect(),
            fmmu_usage: sii.fmmu_usage()?.to_vec(),
            rx_pdos: pdos(false)?,
            tx_pdos: pdos(true)?,
            dc_assign_activate: sii.dc_modes()?.next().map_or(0, |m| m.assign_activate),
            mailbox_counter: 1,
        })
    }
}

/// The acyclic part of the master: the link and the devices found.
#[derive(Debug)]
pub struct Master {
    /// The wire.
    pub link: Link,
    /// The configuration.
    pub config: MasterConfig,
    /// The devices, in position order.
    pub devices: Vec<SubDevice>,
}

impl Master {
    /// Opens the raw socket.
    pub fn open(config: MasterConfig) -> Result<Self, EcError> {
        let mut link = Link::open(&config.interface, config.source)?;
        link.set_spin(config.spin);
        Ok(Self {
            link,
            config,
            devices: Vec::new(),
        })
    }

    /// One datagram with retries of lost frames; returns the working counter.
    pub fn datagram(
        &mut self,
        command: Command,
        address: u32,
        data: &mut [u8],
    ) -> Result<u16, EcError> {
        let header = DatagramHeader::new(command, address, data.len() as u16);
        let mut last = None;
        let keep = data.to_vec();
        for _ in 0..=self.config.retries {
            data.copy_from_slice(&keep);
            match self.link.transact(header, data, self.config.frame_timeout) {
                Ok(wkc) => return Ok(wkc),
                Err(e @ EcError::Timeout { .. }) => last = Some(e),
                Err(e) => return Err(e),
            }
        }
        Err(last.unwrap_or(EcError::Reply("no attempt")))
    }

    fn expect(command: Command, address: u32, wkc: u16, expected: u16) -> Result<(), EcError> {
        if wkc == expected {
            Ok(())
        } else {
            Err(EcError::WorkingCounter {
                command,
                address,
                expected,
                received: wkc,
            })
        }
    }

    /// Broadcast write; returns the working counter.
    pub fn bwr(&mut self, register: u16, data: &[u8]) -> Result<u16, EcError> {
        let mut d = data.to_vec();
        self.datagram(Command::Bwr, physical(0, register), &mut d)
    }

    /// Broadcast read (ORed); returns the working counter.
    pub fn brd(&mut self, register: u16, out: &mut [u8]) -> Result<u16, EcError> {
        out.fill(0);
        self.datagram(Command::Brd, physical(0, register), out)
    }

    /// Reads a register of device `k` by station address (working counter 1).
    pub fn fprd(&mut self, k: usize, register: u16, out: &mut [u8]) -> Result<(), EcError> {
        let station = self.devices[k].station;
        out.fill(0);
        let a = physical(station, register);
        let wkc = self.datagram(Command::Fprd, a, out)?;
        Self::expect(Command::Fprd, a, wkc, 1)
    }

    /// Writes a register of device `k` (working counter 1).
    pub fn fpwr(&mut self, k: usize, register: u16, data: &[u8]) -> Result<(), EcError> {
        let wkc = self.fpwr_wkc(k, register, data)?;
        let a = physical(self.devices[k].station, register);
        Self::expect(Command::Fpwr, a, wkc, 1)
    }

    /// Writes a register of device `k` and returns the working counter (0: refused).
    pub fn fpwr_wkc(&mut self, k: usize, register: u16, data: &[u8]) -> Result<u16, EcError> {
        let station = self.devices[k].station;
        let mut d = data.to_vec();
        self.datagram(Command::Fpwr, physical(station, register), &mut d)
    }

    /// Reads a little-endian u16 register of device `k`.
    pub fn fprd_u16(&mut self, k: usize, register: u16) -> Result<u16, EcError> {
        let mut b = [0u8; 2];
        self.fprd(k, register, &mut b)?;
        Ok(u16::from_le_bytes(b))
    }

    /// Counts the devices, resets their registers, assigns station addresses, reads every
    /// SII. Leaves every device in INIT.
    pub fn scan(&mut self) -> Result<usize, EcError> {
        self.link.drain()?;
        // INIT with error acknowledge, twice: the AL control handshake may refuse the first.
        let init = AlControl::acknowledge(AlState::Init).to_u16().to_le_bytes();
        // A segment returns every frame, devices or not; a frame that never comes back means
        // nothing is there.
        self.bwr(reg::AL_CONTROL, &init).map_err(|e| match e {
            EcError::Timeout { .. } => EcError::NoDevices,
            e => e,
        })?;
        let mut type_reg = [0u8; 1];
        let count = self.brd(reg::TYPE, &mut type_reg)?;
        if count == 0 {
            return Err(EcError::NoDevices);
        }
        if usize::from(count) > self.config.max_devices {
            return Err(EcError::TooManyDevices {
                found: count,
                limit: self.config.max_devices,
            });
        }
        // Reset what a previous master may have left: loop control, event mask, error
        // counters, FMMUs, sync managers, DC activation and filters; the EEPROM to ECAT.
        self.bwr(0x0101, &[0])?;
        self.bwr(reg::ECAT_EVENT_MASK, &0x0004u16.to_le_bytes())?;
        self.bwr(reg::RX_ERROR_COUNTERS, &[0; 8])?;
        self.bwr(reg::FMMU0, &[0; 16 * 3])?;
        self.bwr(reg::SM0, &[0; 8 * 4])?;
        self.bwr(reg::DC_ACTIVATION, &[0])?;
        self.bwr(reg::DC_SPEED_COUNTER_START, &0x1000u16.to_le_bytes())?;
        self.bwr(reg::DC_FILTER_DEPTH, &0x0C00u16.to_le_bytes())?;
        self.bwr(reg::SII_CONFIG, &[0x02])?;
        self.bwr(reg::SII_CONFIG, &[0x00])?;
        self.bwr(reg::AL_CONTROL, &init)?;
        self.devices.clear();
        for p in 0..count {
            let station = STATION_BASE + p;
            let mut d = station.to_le_bytes();
            let a = position(p, reg::STATION_ADDRESS);
            let wkc = self.datagram(Command::Apwr, a, &mut d)?;
            Self::expect(Command::Apwr, a, wkc, 1)?;
        }
        for p in 0..count {
            let image = self.read_sii(STATION_BASE + p, p)?;
            let sii = Sii::new(&image);
            let reference = DeviceRef {
                position: p,
                station: STATION_BASE + p,
            };
            let mut dev = SubDevice::from_sii(p, &sii).map_err(|error| EcError::Sii {
                device: reference,
                error,
            })?;
            self.devices.push(dev.clone());
            let k = self.devices.len() - 1;
            let mut id = [0u8; 10];
            self.fprd(k, reg::TYPE, &mut id)?;
            dev.esc_type = id[0];
            dev.fmmu_count = id[4];
            dev.sm_count = id[5];
            dev.features = u16::from_le_bytes([id[8], id[9]]);
            dev.dl_status = DlStatus(self.fprd_u16(k, reg::DL_STATUS)?);
            self.devices[k] = dev;
        }
        Ok(self.devices.len())
    }

    fn sii_wait(&mut self, station: u16, reference: DeviceRef) -> Result<u16, EcError> {
        let deadline = Instant::now() + Duration::from_millis(100);
        loop {
            let mut b = [0u8; 2];
            let a = physical(station, reg::SII_CONTROL);
            let wkc = self.datagram(Command::Fprd, a, &mut b)?;
            Self::expect(Command::Fprd, a, wkc, 1)?;
            let s = u16::from_le_bytes(b);
            if s & reg::SII_BUSY == 0 {
                if s & (reg::SII_ERROR_COMMAND | reg::SII_ERROR_WRITE_ENABLE) != 0 {
                    return Err(EcError::SiiAccess {
                        device: reference,
                        status: s,
                    });
                }
                return Ok(s);
            }
            if Instant::now() >= deadline {
                return Err(EcError::SiiAccess {
                    device: reference,
                    status: s,
                });
            }
        }
    }

    /// Reads the SII image of the device at `station`: the header words and the categories up
    /// to the end marker.
    pub fn read_sii(&mut self, station: u16, position: u16) -> Result<Vec<u8>, EcError> {
        let reference = DeviceRef { position, station };
        let status = self.sii_wait(station, reference)?;
        let chunk = if status & reg::SII_READ_8 != 0 { 8 } else { 4 };
        let mut image = Vec::with_capacity(1024);
        let read_to = |master: &mut Self, image: &mut Vec<u8>, end: usize| -> Result<(), EcError> {
            while image.len() < end {
                let word = (image.len() / 2) as u32;
                let mut cmd = [0u8; 6];
                cmd[..2].copy_from_slice(&reg::SII_CMD_READ.to_le_bytes());
                cmd[2..].copy_from_slice(&word.to_le_bytes());
                let a = physical(station, reg::SII_CONTROL);
                let wkc = master.datagram(Command::Fpwr, a, &mut cmd)?;
                Self::expect(Command::Fpwr, a, wkc, 1)?;
                master.sii_wait(station, reference)?;
                let mut data = vec![0u8; chunk];
                let a = physical(station, reg::SII_DATA);
                let wkc = master.datagram(Command::Fprd, a, &mut data)?;
                Self::expect(Command::Fprd, a, wkc, 1)?;
                image.extend_from_slice(&data);
            }
            Ok(())
        };
        read_to(self, &mut image, 0x80)?;
        // Walk the categories: read each header, then skip to the next.
        let mut word = 0x40usize;
        loop {
            read_to(self, &mut image, word * 2 + 4)?;
            let kind = u16::from_le_bytes([image[word * 2], image[word * 2 + 1]]);
            let size = usize::from(u16::from_le_bytes([
                image[word * 2 + 2],
                image[word * 2 + 3],
            ]));
            if kind == 0xFFFF || kind == 0 && size == 0 {
                break;
            }
            let next = word + 2 + size;
            if next * 2 > SII_MAX_BYTES {
                return Err(EcError::Sii {
                    device: reference,
                    error: SiiError::Truncated {
                        offset: word * 2,
                        need: 4 + 2 * size,
                    },
                });
            }
            read_to(self, &mut image, next * 2)?;
            word = next;
        }
        Ok(image)
    }

    /// Reads device `k`'s AL status and code.
    pub fn al_status(&mut self, k: usize) -> Result<(AlStatus, AlStatusCode), EcError> {
        let mut b = [0u8; 6];
        self.fprd(k, reg::AL_STATUS, &mut b)?;
        Ok((
            AlStatus(u16::from_le_bytes([b[0], b[1]])),
            AlStatusCode(u16::from_le_bytes([b[4], b[5]])),
        ))
    }

    /// Writes AL control of device `k`, retrying while the device has not taken the previous
    /// request (the handshake of ESCs without device emulation).
    pub fn al_control(
        &mut self,
        k: usize,
        control: AlControl,
        deadline: Instant,
    ) -> Result<(), EcError> {
        let v = control.to_u16().to_le_bytes();
        loop {
            if self.fpwr_wkc(k, reg::AL_CONTROL, &v)? == 1 {
                return Ok(());
            }
            if Instant::now() >= deadline {
                let a = physical(self.devices[k].station, reg::AL_CONTROL);
                return Err(EcError::WorkingCounter {
                    command: Command::Fpwr,
                    address: a,
                    expected: 1,
                    received: 0,
                });
            }
            std::thread::sleep(Duration::from_micros(200));
        }
    }

    /// Brings devices `ks` to `target`, bounded by the configured state timeout; `between`
    /// runs once per poll (to keep process data flowing). A device whose error flag is set is
    /// acknowledged first; a device that refuses is named with its AL status code.
    pub fn request_state(
        &mut self,
        ks: &[usize],
        target: AlState,
        mut between: impl FnMut(&mut Self) -> Result<(), EcError>,
    ) -> Result<(), EcError> {
        let deadline = Instant::now() + self.config.state_timeout;
        for &k in ks {
            let (status, _) = self.al_status(k)?;
            let control = if status.error() {
                AlControl::acknowledge(target)
            } else {
                AlControl::request(target)
            };
            self.al_control(k, control, deadline)?;
        }
        let mut pending: Vec<usize> = ks.to_vec();
        loop {
            between(self)?;
            let mut still = Vec::new();
            for &k in &pending {
                let (status, code) = self.al_status(k)?;
                if status.state() == Some(target) && !status.error() {
                    continue;
                }
                if status.error() {
                    return Err(EcError::AlTransition {
                        device: self.devices[k].reference(),
                        target,
                        status,
                        code,
                    });
                }
                if Instant::now() >= deadline {
                    return Err(EcError::AlTransition {
                        device: self.devices[k].reference(),
                        target,
                        status,
                        code,
                    });
                }
                still.push(k);
            }
            if still.is_empty() {
                return Ok(());
            }
            pending = still;
            std::thread::sleep(Duration::from_micros(500));
        }
    }
}
