//! The dashboard server (TCP 29999; RL's `UniversalRobotsDashboard`): one text command per
//! line, one answer per line. [`Dashboard`] sends commands and checks their answers; it is for
//! the setup around a run (power, brakes, programs, protective stops), not the control loop
//! (it allocates).

use std::fmt;
use std::io;
use std::net::SocketAddr;
use std::time::{Duration, Instant};

use crate::transport::TcpLink;

/// The dashboard's port.
pub const PORT: u16 = 29999;

/// Why a dashboard command failed.
#[derive(Debug)]
pub enum DashboardError {
    /// The connection failed or timed out.
    Io(io::Error),
    /// The controller closed the connection.
    Closed,
    /// The answer is not the one the command succeeds with.
    Refused {
        /// The command.
        command: String,
        /// The controller's answer.
        answer: String,
    },
}

impl fmt::Display for DashboardError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Io(e) => write!(f, "dashboard: {e}"),
            Self::Closed => f.write_str("dashboard: the controller closed the connection"),
            Self::Refused { command, answer } => {
                write!(
                    f,
                    "dashboard `{command}`: the controller answered `{answer}`"
                )
            }
        }
    }
}

impl std::error::Error for DashboardError {}

/// A connection to the dashboard server.
#[derive(Debug)]
pub struct Dashboard {
    link: TcpLink,
    rx: Vec<u8>,
    timeout: Duration,
    greeting: String,
}

impl Dashboard {
    /// Connects and reads the greeting, within `timeout` (also the wait for each answer).
    pub fn connect(addr: SocketAddr, timeout: Duration) -> Result<Self, DashboardError> {
        let link = TcpLink::connect(addr, timeout).map_err(DashboardError::Io)?;
        let mut d = Self {
            link,
            rx: Vec::new(),
            timeout,
            greeting: String::new(),
        };
        d.greeting = d.line()?;
        Ok(d)
    }

    /// The greeting ("Connected: Universal Robots Dashboard Server").
    pub fn greeting(&self) -> &str {
        &self.greeting
    }

    fn line(&mut self) -> Result<String, DashboardError> {
        let deadline = Instant::now() + self.timeout;
        loop {
            if let Some(end) = self.rx.iter().position(|b| *b == b'\n') {
                let line: Vec<u8> = self.rx.drain(..=end).collect();
                return Ok(String::from_utf8_lossy(&line).trim_end().to_owned());
            }
            let mut buf = [0u8; 512];
            match self.link.recv(&mut buf, deadline) {
                Ok(0) => return Err(DashboardError::Closed),
                Ok(n) => self.rx.extend_from_slice(&buf[..n]),
                Err(e) => return Err(DashboardError::Io(e)),
            }
        }
    }

    /// Sends `command` and returns the answer.
    pub fn command(&mut self, command: &str) -> Result<String, DashboardError> {
        let deadline = Instant::now() + self.timeout;
        self.link
            .send_all(format!("{command}\n").as_bytes(), deadline)
            .map_err(DashboardError::Io)?;
        self.line()
    }

    /// Sends `command`; its answer must start with `success`.
    fn expect(&mut self, command: &str, success: &str) -> Result<String, DashboardError> {
        let answer = self.command(command)?;
        if answer.starts_with(success) {
            Ok(answer)
        } else {
            Err(DashboardError::Refused {
                command: command.into(),
                answer,
            })
        }
    }

    /// Powers the arm on ("Powering on").
    pub fn power_on(&mut self) -> Result<(), DashboardError> {
        self.expect("power on", "Powering on").map(drop)
    }

    /// Powers the arm off.
    pub fn power_off(&mut self) -> Result<(), DashboardError> {
        self.expect("power off", "Powering off").map(drop)
    }

    /// Releases the brakes.
    pub fn brake_release(&mut self) -> Result<(), DashboardError> {
        self.expect("brake release", "Brake releasing").map(drop)
    }

    /// Stops the running program.
    pub fn stop(&mut self) -> Result<(), DashboardError> {
        self.expect("stop", "Stopped").map(drop)
    }

    /// Pauses the running program.
    pub fn pause(&mut self) -> Result<(), DashboardError> {
        self.expect("pause", "Pausing program").map(drop)
    }

    /// Plays the loaded program.
    pub fn play(&mut self) -> Result<(), DashboardError> {
        self.expect("play", "Starting program").map(drop)
    }

    /// Loads a program (`.urp`) by its path on the controller.
    pub fn load(&mut self, program: &str) -> Result<(), DashboardError> {
        self.expect(&format!("load {program}"), "Loading program")
            .map(drop)
    }

    /// Unlocks a protective stop (the controller refuses within 5 s of it).
    pub fn unlock_protective_stop(&mut self) -> Result<(), DashboardError> {
        self.expect("unlock protective stop", "Protective stop releasing")
            .map(drop)
    }

    /// Closes a safety popup.
    pub fn close_safety_popup(&mut self) -> Result<(), DashboardError> {
        self.expect("close safety popup", "closing safety popup")
            .map(drop)
    }

    /// The robot mode's name (`RUNNING`, `IDLE`, `POWER_OFF`…).
    pub fn robot_mode(&mut self) -> Result<String, DashboardError> {
        let a = self.expect("robotmode", "Robotmode: ")?;
        Ok(a["Robotmode: ".len()..].to_owned())
    }

    /// The safety mode's name (`NORMAL`, `PROTECTIVE_STOP`…).
    pub fn safety_mode(&mut self) -> Result<String, DashboardError> {
        let a = self.expect("safetymode", "Safetymode: ")?;
        Ok(a["Safetymode: ".len()..].to_owned())
    }

    /// Whether a program runs.
    pub fn running(&mut self) -> Result<bool, DashboardError> {
        let a = self.expect("running", "Program running: ")?;
        Ok(a.ends_with("true"))
    }

    /// The program state (`PLAYING name.urp`, `STOPPED name.urp`…).
    pub fn program_state(&mut self) -> Result<String, DashboardError> {
        self.command("programState")
    }

    /// PolyScope's version.
    pub fn polyscope_version(&mut self) -> Result<String, DashboardError> {
        self.command("PolyscopeVersion")
    }

    /// Whether the controller is in remote control (e-Series: needed for `power on` and
    /// `play` from outside).
    pub fn is_in_remote_control(&mut self) -> Result<bool, DashboardError> {
        Ok(self.command("is in remote control")?.trim() == "true")
    }

    /// Ends the session ("Disconnected").
    pub fn quit(mut self) -> Result<(), DashboardError> {
        self.expect("quit", "Disconnected").map(drop)
    }
}
