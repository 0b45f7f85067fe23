//! A pseudo-terminal pair: the fake gripper holds the master side, a client opens the slave's
//! path (`/dev/pts/N`) as it would open `/dev/ttyUSB0`. The fake keeps its own handle on the
//! slave (in raw mode) so the line stays up between clients.

use std::io;
use std::os::fd::{AsFd, OwnedFd};
use std::path::{Path, PathBuf};

use nix::sys::termios::{self, SetArg};

/// An open pseudo-terminal.
#[derive(Debug)]
pub struct Pty {
    /// The master side (the device's end).
    pub master: OwnedFd,
    /// A handle on the slave side, kept open.
    pub slave: OwnedFd,
    path: PathBuf,
}

impl Pty {
    /// Opens a pair; the slave is set to raw mode (no echo, no line editing).
    pub fn open() -> io::Result<Self> {
        let pair = nix::pty::openpty(None, None)?;
        let mut t = termios::tcgetattr(&pair.slave)?;
        termios::cfmakeraw(&mut t);
        termios::tcsetattr(&pair.slave, SetArg::TCSANOW, &t)?;
        let path = nix::unistd::ttyname(pair.slave.as_fd())?;
        Ok(Self {
            master: pair.master,
            slave: pair.slave,
            path,
        })
    }

    /// The slave's path, to open as a serial port.
    pub fn path(&self) -> &Path {
        &self.path
    }
}
