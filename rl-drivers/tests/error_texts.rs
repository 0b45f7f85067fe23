//! A device's fault reason is never cut off: the generic error keeps the driver's reason in a
//! fixed buffer ([`DESCRIPTION_CAPACITY`] bytes, no allocation on the real-time path), and every
//! reason of the CiA 402 drivers is rendered here in its longest form — every EMCY code, every
//! SDO abort code CiA 301 names, every unit object, the largest numbers — and must fit whole.

use std::time::Duration;

use rl_drivers::canopen::CanopenError;
use rl_drivers::cia402::{Mode, PowerState, UnitsError, object as obj};
use rl_drivers::device::{DESCRIPTION_CAPACITY, Description};
use rl_drivers::ethercat::{DeviceRef, DriveFault, EcError, UnitsRefused};
use rl_drivers::proto::canopen::emcy::Emergency;
use rl_drivers::proto::canopen::nmt;
use rl_drivers::proto::canopen::sdo::{AbortCode, Address};
use rl_drivers::proto::canopen::sdo_client::SdoError;
use rl_drivers::proto::ecat::al::{AlState, AlStatus, AlStatusCode};
use rl_drivers::proto::ecat::mailbox::MailboxErrorCode;

const MODES: [Mode; 3] = [
    Mode::CyclicPosition,
    Mode::CyclicVelocity,
    Mode::CyclicTorque,
];
const STATES: [PowerState; 8] = [
    PowerState::NotReadyToSwitchOn,
    PowerState::SwitchOnDisabled,
    PowerState::ReadyToSwitchOn,
    PowerState::SwitchedOn,
    PowerState::OperationEnabled,
    PowerState::QuickStopActive,
    PowerState::FaultReactionActive,
    PowerState::Fault,
];
const UNIT_OBJECTS: [obj::Object; 7] = [
    obj::ENCODER_INCREMENTS,
    obj::ENCODER_MOTOR_REVOLUTIONS,
    obj::GEAR_MOTOR_REVOLUTIONS,
    obj::GEAR_SHAFT_REVOLUTIONS,
    obj::FEED,
    obj::FEED_SHAFT_REVOLUTIONS,
    obj::MOTOR_RATED_TORQUE,
];

/// Every abort code CiA 301 names (they all have low words below 0x100), and one it does not.
fn abort_codes() -> impl Iterator<Item = AbortCode> {
    (0x0500u32..0x0900)
        .flat_map(|high| (0u32..0x100).map(move |low| AbortCode(high << 16 | low)))
        .filter(|c| c.name().is_some())
        .chain([AbortCode(0xFFFF_FFFF)])
}

fn sdo_errors() -> impl Iterator<Item = SdoError> {
    let address = Address::new(0xFFFF, 0xFF);
    abort_codes()
        .flat_map(move |code| {
            [
                SdoError::Aborted { address, code },
                SdoError::Protocol {
                    address,
                    what: "toggle bit not alternated in a segment",
                    code,
                },
            ]
        })
        .chain([
            SdoError::Timeout { address },
            SdoError::TooLong {
                address,
                size: usize::MAX,
            },
            SdoError::Idle,
        ])
}

/// The longest text, and whether every one fits.
struct Longest {
    len: usize,
    text: String,
    checked: usize,
}

impl Longest {
    fn new() -> Self {
        Self {
            len: 0,
            text: String::new(),
            checked: 0,
        }
    }

    fn check(&mut self, reason: &dyn std::fmt::Display) {
        let d = Description::from_display(reason);
        let full = reason.to_string();
        assert!(
            !d.is_truncated() && d.as_str() == full,
            "cut off at {DESCRIPTION_CAPACITY} bytes ({} needed): {full}",
            full.len()
        );
        self.checked += 1;
        if full.len() > self.len {
            self.len = full.len();
            self.text = full;
        }
    }
}

#[test]
fn every_canopen_reason_fits_whole() {
    let mut l = Longest::new();
    let node = 127;
    for code in 0..=u16::MAX {
        let emcy = Emergency {
            code,
            register: 0xFF,
            vendor: [0xFF; 5],
        };
        for state in STATES {
            l.check(&CanopenError::DriveFault {
                node,
                state,
                emcy: Some(emcy),
            });
        }
        l.check(&CanopenError::Emergency { node, emcy });
    }
    for error in sdo_errors() {
        l.check(&CanopenError::Sdo { node, error });
        for object in UNIT_OBJECTS {
            l.check(&CanopenError::Units {
                node,
                error: UnitsError::Unreadable { object, error },
            });
        }
    }
    for object in UNIT_OBJECTS {
        l.check(&CanopenError::Units {
            node,
            error: UnitsError::Zero { object },
        });
    }
    l.check(&CanopenError::Units {
        node,
        error: UnitsError::Given {
            what: "counts per revolution",
            value: -f64::MAX,
        },
    });
    for mode in MODES {
        l.check(&CanopenError::ModeUnsupported {
            node,
            mode,
            supported: u32::MAX,
        });
        l.check(&CanopenError::ModeNotTaken {
            node,
            mode,
            display: i8::MIN,
        });
    }
    for state in STATES {
        for goal in ["operation enabled", "switch on disabled", "quick stop"] {
            l.check(&CanopenError::Stuck {
                node,
                state: Some(state),
                waited: Duration::from_secs(u64::MAX / 1000),
                goal,
            });
        }
        l.check(&CanopenError::DriveFault {
            node,
            state,
            emcy: None,
        });
        l.check(&CanopenError::Disabled { node, state });
    }
    for state in [
        nmt::State::BootUp,
        nmt::State::Stopped,
        nmt::State::Operational,
        nmt::State::PreOperational,
    ] {
        l.check(&CanopenError::NmtState { node, state });
    }
    l.check(&CanopenError::NotADrive {
        node,
        device_type: u32::MAX,
    });
    l.check(&CanopenError::HeartbeatLost {
        node,
        timeout: Duration::from_secs(u64::MAX / 1000),
    });
    l.check(&CanopenError::TpdoLost {
        count: u32::MAX,
        node,
    });
    l.check(&CanopenError::TpdoLength {
        node,
        len: usize::MAX,
        expected: usize::MAX,
    });
    println!(
        "{} CANopen reasons fit {DESCRIPTION_CAPACITY} bytes; the longest ({} bytes): {}",
        l.checked, l.len, l.text
    );
}

#[test]
fn every_ethercat_reason_fits_whole() {
    let mut l = Longest::new();
    let device = DeviceRef {
        position: u16::MAX,
        station: u16::MAX,
    };
    for code in 0..=u16::MAX {
        let status = AlStatus::new(AlState::SafeOp, true);
        l.check(&EcError::AlStatus {
            device,
            status,
            code: AlStatusCode(code),
        });
        l.check(&EcError::AlTransition {
            device,
            target: AlState::Op,
            status,
            code: AlStatusCode(code),
        });
        l.check(&EcError::MailboxError {
            device,
            code: MailboxErrorCode(code),
        });
        l.check(&DriveFault {
            axis: 65_535,
            device,
            statusword: code,
            error_code: 0xFFFF,
        });
    }
    for error in sdo_errors() {
        let sdo = EcError::Sdo { device, error };
        l.check(&sdo);
        for object in UNIT_OBJECTS {
            l.check(&UnitsRefused {
                axis: 65_535,
                device,
                error: UnitsError::Unreadable { object, error: sdo },
            });
        }
    }
    for object in UNIT_OBJECTS {
        l.check(&UnitsRefused {
            axis: 65_535,
            device,
            error: UnitsError::Zero { object },
        });
        l.check(&UnitsRefused {
            axis: 65_535,
            device,
            error: UnitsError::Unreadable {
                object,
                error: EcError::Timeout {
                    what: "a CoE mailbox answer",
                    waited_us: u64::MAX,
                },
            },
        });
    }
    println!(
        "{} EtherCAT reasons fit {DESCRIPTION_CAPACITY} bytes; the longest ({} bytes): {}",
        l.checked, l.len, l.text
    );
}
