//! One fake device: its ESC and the firmware behind the PDI — the AL state machine with the
//! checks a device makes at each transition (mailbox configuration, process data sync managers
//! against the PDO mapping, DC SYNC0 for a drive that needs it, valid outputs before OP), the
//! mailbox server, the process data exchange with the CiA 402 axis, and the process data
//! watchdog that drops a device from OP to SAFE-OP when outputs stop coming.

use super::axis::Axis;
use super::coe_server::MailboxServer;
use super::description::{DeviceDescription, Profile};
use super::dictionary::Dictionary;
use super::esc::{Esc, PassTimes};
use crate::cia402::object as obj;
use crate::proto::canopen::pdo::Entry;
use crate::proto::ecat::al::{AlState, AlStatus, AlStatusCode};
use crate::proto::ecat::datagram::DatagramHeader;
use crate::proto::ecat::sync_manager::{self, SyncManager};

/// CiA 402 error code the fake drive reports when it loses its process data (CiA 301
/// "communication error").
pub const ERROR_COMMUNICATION: u16 = 0x8100;

/// How long a SAFE-OP → OP request waits for the first outputs before it is refused.
pub const OP_PENDING_NS: u64 = 1_000_000_000;

/// One device.
#[derive(Clone, Debug)]
pub struct Slave {
    esc: Esc,
    description: DeviceDescription,
    od: Dictionary,
    mailbox: MailboxServer,
    axis: Option<Axis>,
    state: AlState,
    error: Option<AlStatusCode>,
    rx: Vec<Entry>,
    tx: Vec<Entry>,
    outputs_valid: bool,
    last_outputs: u64,
    last_update: u64,
    sync0_done: u64,
    dc_mode: bool,
    answer: Option<Vec<u8>>,
    /// A SAFE-OP → OP request waiting for the first outputs (since this fake time).
    op_pending: Option<u64>,
    /// Transitions refused so far.
    pub refused_transitions: u64,
}

impl Slave {
    /// A powered-up device (INIT) with `open_ports` and its clock `clock_offset` ns ahead of
    /// the fake's time base, `drift_ppb` fast.
    pub fn new(
        description: DeviceDescription,
        open_ports: u8,
        clock_offset: i64,
        drift_ppb: i64,
    ) -> Self {
        let esc = Esc::new(
            description.esc,
            description.sii(),
            open_ports,
            clock_offset,
            drift_ppb,
        );
        let od = description.dictionary();
        let axis = match &description.profile {
            Profile::Cia402 {
                motor,
                initial_position,
                ..
            } => Some(Axis::new(*motor, *initial_position)),
            Profile::Plain => None,
        };
        let mut s = Self {
            esc,
            description,
            od,
            mailbox: MailboxServer::new(),
            axis,
            state: AlState::Init,
            error: None,
            rx: Vec::new(),
            tx: Vec::new(),
            outputs_valid: false,
            last_outputs: 0,
            last_update: 0,
            sync0_done: 0,
            dc_mode: false,
            answer: None,
            op_pending: None,
            refused_transitions: 0,
        };
        for n in 0..4 {
            s.esc.pdi_deactivate_sm(n, true);
        }
        if let Some(a) = &s.axis {
            a.write_measurements(&mut s.od, None, false, false);
        }
        s
    }

    /// The ESC.
    pub fn esc(&self) -> &Esc {
        &self.esc
    }

    /// The description.
    pub fn description(&self) -> &DeviceDescription {
        &self.description
    }

    /// The object dictionary.
    pub fn dictionary(&self) -> &Dictionary {
        &self.od
    }

    /// The axis of a drive.
    pub fn axis(&self) -> Option<&Axis> {
        self.axis.as_ref()
    }

    /// The AL state.
    pub fn al_state(&self) -> AlState {
        self.state
    }

    /// The error code shown in AL status, if the error flag is set.
    pub fn al_error(&self) -> Option<AlStatusCode> {
        self.error
    }

    /// Mailbox messages answered.
    pub fn mailbox_requests(&self) -> u64 {
        self.mailbox.requests
    }

    /// Whether the drive runs synchronised to SYNC0.
    pub fn dc_mode(&self) -> bool {
        self.dc_mode
    }

    /// Processes one datagram passing through (the ESC's part).
    pub fn process(
        &mut self,
        header: &mut DatagramHeader,
        data: &mut [u8],
        wkc: &mut u16,
        times: &PassTimes,
    ) {
        self.esc.process(header, data, wkc, times);
    }

    fn publish(&mut self) {
        let status = AlStatus::new(self.state, self.error.is_some()).0;
        self.esc
            .pdi_set_al_status(status, self.error.map_or(0, |c| c.0));
    }

    fn refuse(&mut self, code: AlStatusCode) {
        self.refused_transitions += 1;
        self.error = Some(code);
        self.publish();
    }

    /// A local fault (injected, or the watchdog): OP → SAFE-OP with the error flag and `code`.
    /// The outputs sync manager is deactivated until the master acknowledges, as ETG's slave
    /// stack does, and a drive's axis faults.
    pub fn fall_back(&mut self, code: AlStatusCode) {
        if self.state == AlState::Op {
            self.state = AlState::SafeOp;
        }
        self.esc.pdi_deactivate_sm(2, true);
        if let Some(a) = &mut self.axis {
            if a.state().is_powered() {
                a.fault(ERROR_COMMUNICATION);
            }
        }
        self.error = Some(code);
        self.publish();
    }

    fn mailbox_ok(&self) -> bool {
        let d = &self.description;
        if !d.has_mailbox() {
            return true;
        }
        let ok = |s: SyncManager, start: u16, len: u16, write: bool| {
            s.start == start
                && s.length == len
                && s.is_mailbox()
                && s.is_write() == write
                && s.activate & sync_manager::ACTIVATE_ENABLE != 0
        };
        ok(
            self.esc.sm(0),
            d.mailbox_out.offset,
            d.mailbox_out.size,
            true,
        ) && ok(
            self.esc.sm(1),
            d.mailbox_in.offset,
            d.mailbox_in.size,
            false,
        )
    }

    fn process_data_check(&self) -> Result<(), AlStatusCode> {
        let (o, i) = if self.description.has_mailbox() {
            (2, 3)
        } else {
            (0, 1)
        };
        let check = |n: usize, bits: usize, write: bool, code| {
            let bytes = bits.div_ceil(8);
            if bytes == 0 {
                return Ok(());
            }
            let s = self.esc.sm(n);
            if usize::from(s.length) != bytes
                || s.is_mailbox()
                || s.is_write() != write
                || s.activate & sync_manager::ACTIVATE_ENABLE == 0
            {
                return Err(code);
            }
            Ok(())
        };
        check(
            o,
            Dictionary::bits(&self.rx),
            true,
            AlStatusCode::INVALID_OUTPUT_CONFIG,
        )?;
        check(
            i,
            Dictionary::bits(&self.tx),
            false,
            AlStatusCode::INVALID_INPUT_CONFIG,
        )
    }

    fn sm_numbers(&self) -> (usize, usize) {
        if self.description.has_mailbox() {
            (2, 3)
        } else {
            (0, 1)
        }
    }

    fn handle_al_control(&mut self, control: u16, t: u64) {
        self.op_pending = None;
        let acknowledge = control & 0x10 != 0;
        let Some(requested) = AlState::from_code(control as u8) else {
            self.refuse(AlStatusCode::UNKNOWN_STATE);
            return;
        };
        if self.error.is_some() {
            if !acknowledge {
                return; // The error stays until the master acknowledges it.
            }
            self.error = None;
            if self.state == AlState::SafeOp {
                let (o, _) = self.sm_numbers();
                self.esc.pdi_deactivate_sm(o, false);
            }
        }
        let (o, i) = self.sm_numbers();
        use AlState::*;
        match (self.state, requested) {
            (s, r) if s == r => {}
            (_, Init) => {
                for n in 0..4 {
                    self.esc.pdi_deactivate_sm(n, true);
                }
                self.mailbox = MailboxServer::new();
                self.answer = None;
                self.od.pre_op = false;
                self.disable_axis();
                self.state = Init;
            }
            (Init, PreOp) => {
                if !self.mailbox_ok() {
                    self.refuse(AlStatusCode::INVALID_MAILBOX_CONFIG);
                    return;
                }
                if self.description.has_mailbox() {
                    self.esc.pdi_deactivate_sm(0, false);
                    self.esc.pdi_deactivate_sm(1, false);
                }
                self.od.pre_op = true;
                self.state = PreOp;
            }
            (PreOp, SafeOp) => {
                self.rx = self.od.assigned(false);
                self.tx = self.od.assigned(true);
                if let Err(code) = self.process_data_check() {
                    self.refuse(code);
                    return;
                }
                let sync0 = self.esc.sync0();
                if let Profile::Cia402 {
                    requires_dc: true, ..
                } = self.description.profile
                {
                    if sync0.is_none_or(|s| s.cycle == 0) {
                        self.refuse(AlStatusCode::INVALID_DC_SYNC);
                        return;
                    }
                }
                self.dc_mode = sync0.is_some_and(|s| s.cycle > 0) && self.description.dc.is_some();
                if let Some(s) = sync0 {
                    for index in [0x1C32, 0x1C33] {
                        self.od.set_int(index, 1, if self.dc_mode { 2 } else { 0 });
                        self.od.set_int(index, 2, i64::from(s.cycle));
                    }
                }
                self.sync0_done = self.esc.sync0_pulses(t);
                self.esc.pdi_deactivate_sm(o, false);
                self.esc.pdi_deactivate_sm(i, false);
                self.od.pre_op = false;
                self.outputs_valid = false;
                self.last_update = t;
                self.state = SafeOp;
                self.exchange_inputs();
            }
            (SafeOp, Op) => {
                if !self.outputs_valid && !self.rx.is_empty() {
                    // As ETG's slave stack does: the transition stays "in work" until the first
                    // outputs arrive (refused with "no valid outputs" after OP_PENDING_NS).
                    self.op_pending = Some(t);
                    return;
                }
                self.last_outputs = t;
                self.state = Op;
            }
            (Op, SafeOp) => {
                self.disable_axis();
                self.state = SafeOp;
            }
            (Op | SafeOp, PreOp) => {
                self.esc.pdi_deactivate_sm(o, true);
                self.esc.pdi_deactivate_sm(i, true);
                self.disable_axis();
                self.od.pre_op = true;
                self.state = PreOp;
            }
            (_, Bootstrap) => {
                self.refuse(AlStatusCode::BOOTSTRAP_NOT_SUPPORTED);
                return;
            }
            _ => {
                self.refuse(AlStatusCode::INVALID_STATE_CHANGE);
                return;
            }
        }
        self.publish();
    }

    fn disable_axis(&mut self) {
        if let Some(a) = &mut self.axis {
            if a.state() != crate::cia402::PowerState::Fault {
                // Without process data the drive switches its power stage off.
                self.od.set_int(obj::CONTROLWORD.index, 0, 0);
                a.apply_controlword(&self.od);
            }
            a.write_measurements(&mut self.od, None, false, false);
        }
    }

    fn exchange_inputs(&mut self) {
        if self.tx.is_empty() {
            return;
        }
        let mut buf = vec![0u8; Dictionary::bits(&self.tx).div_ceil(8)];
        self.od.pack(&self.tx, &mut buf);
        let (_, i) = self.sm_numbers();
        self.esc.pdi_write_inputs(i, &buf);
    }

    /// Runs the firmware at fake time `t`: AL control, mailbox, process data, watchdog.
    pub fn pdi_step(&mut self, t: u64) {
        let latency = self.description.firmware_latency_ns;
        if self
            .esc
            .al_control_pending_since()
            .is_some_and(|since| t >= since + latency)
        {
            if let Some(control) = self.esc.pdi_take_al_control() {
                self.handle_al_control(control, t);
            }
        }
        if self.state != AlState::Init && self.description.has_mailbox() {
            if let Some(a) = self.answer.take() {
                if !self.esc.pdi_mailbox_put(1, &a) {
                    self.answer = Some(a);
                }
            }
            if self.answer.is_none()
                && self
                    .esc
                    .mailbox_pending_since(0)
                    .is_some_and(|since| t >= since + latency)
            {
                if let Some(message) = self.esc.pdi_mailbox_take(0) {
                    let capacity = usize::from(self.description.mailbox_in.size);
                    if let Some(a) = self.mailbox.handle(&message, &mut self.od, capacity) {
                        if !self.esc.pdi_mailbox_put(1, &a) {
                            self.answer = Some(a);
                        }
                    }
                    if let Some(axis) = &mut self.axis {
                        // An SDO write of the controlword acts at once, as on a real drive.
                        axis.apply_controlword(&self.od);
                    }
                }
            }
        }
        if matches!(self.state, AlState::SafeOp | AlState::Op) {
            self.process_data(t);
        }
    }

    fn process_data(&mut self, t: u64) {
        let (o, _) = self.sm_numbers();
        let mut fresh = false;
        if let Some(outputs) = self.esc.pdi_take_outputs(o) {
            let outputs = outputs.to_vec();
            self.outputs_valid = true;
            self.last_outputs = t;
            if self.op_pending.take().is_some() {
                self.state = AlState::Op;
                self.publish();
            }
            if self.state == AlState::Op {
                self.od.unpack(&self.rx, &outputs);
                if let Some(a) = &mut self.axis {
                    a.apply_controlword(&self.od);
                }
                fresh = true;
            }
        }
        if let Some(axis) = &mut self.axis {
            if self.dc_mode {
                let pulses = self.esc.sync0_pulses(t);
                let cycle = self.esc.sync0().map_or(0, |s| s.cycle);
                let dt = f64::from(cycle) * 1e-9;
                // A drive in DC mode moves on SYNC0 only (bounded catch-up after a pause).
                let due = pulses.saturating_sub(self.sync0_done).min(1000);
                for _ in 0..due {
                    axis.update(&mut self.od, dt);
                }
                self.sync0_done = pulses;
            } else if fresh {
                let dt = (t.saturating_sub(self.last_update)) as f64 * 1e-9;
                axis.update(&mut self.od, dt.min(0.1));
                self.last_update = t;
            } else {
                let mode = crate::cia402::Mode::from_code(
                    self.od.int(obj::MODES_OF_OPERATION.index, 0) as i8,
                );
                axis.write_measurements(&mut self.od, mode, false, false);
            }
        }
        self.exchange_inputs();
        if self
            .op_pending
            .is_some_and(|since| t.saturating_sub(since) > OP_PENDING_NS)
        {
            self.op_pending = None;
            self.refuse(AlStatusCode::NO_VALID_OUTPUTS);
        }
        // The process data watchdog (SM2 control bit 6): outputs must keep coming in OP.
        let s = self.esc.sm(o);
        if self.state == AlState::Op
            && s.control & sync_manager::WATCHDOG != 0
            && self.esc.watchdog_ns() > 0
            && t.saturating_sub(self.last_outputs) > self.esc.watchdog_ns()
        {
            self.fall_back(AlStatusCode::SM_WATCHDOG);
        }
    }
}
