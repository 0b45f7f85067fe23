//! Serial lines for the Modbus RTU master: the [`SerialLine`] trait (embedded-io's `Read`,
//! `Write` and `ReadReady`, plus a bounded wait), and [`SerialPort`], a Linux tty (a Pi's UART
//! `/dev/ttyAMA0`, a USB adapter `/dev/ttyUSB0`, a pseudo-terminal) set to raw 8N1 at a baud
//! rate, non-blocking, whose waits use `ppoll`.
//!
//! Any embedded-io port works: `SerialLine`'s default wait polls `read_ready` (every 100 µs);
//! [`SerialPort`] waits on the file descriptor instead.

use std::fs::{File, OpenOptions};
use std::io::{self, Read, Write};
use std::os::fd::{AsFd, BorrowedFd, OwnedFd};
use std::os::unix::fs::OpenOptionsExt;
use std::path::Path;
use std::time::{Duration, Instant};

use nix::sys::termios::{self, BaudRate, SetArg};

use crate::transport::{Readiness, wait};

/// A serial line the RTU master can use: embedded-io's reads and writes, and a wait bounded by
/// a deadline.
pub trait SerialLine: embedded_io::Read + embedded_io::Write + embedded_io::ReadReady {
    /// Waits until a byte can be read or `deadline` passes (`Ok(false)`). The default polls
    /// [`read_ready`](embedded_io::ReadReady::read_ready) every 100 µs.
    fn wait_readable(&mut self, deadline: Instant) -> Result<bool, Self::Error> {
        loop {
            if self.read_ready()? {
                return Ok(true);
            }
            let now = Instant::now();
            if now >= deadline {
                return Ok(false);
            }
            std::thread::sleep((deadline - now).min(Duration::from_micros(100)));
        }
    }
}

/// A tty in raw mode, 8 data bits, no parity, one stop bit, no flow control, non-blocking.
#[derive(Debug)]
pub struct SerialPort {
    file: File,
}

/// The termios rate of a baud rate, if it is a standard one.
fn baud_rate(baud: u32) -> Option<BaudRate> {
    Some(match baud {
        1200 => BaudRate::B1200,
        2400 => BaudRate::B2400,
        4800 => BaudRate::B4800,
        9600 => BaudRate::B9600,
        19_200 => BaudRate::B19200,
        38_400 => BaudRate::B38400,
        57_600 => BaudRate::B57600,
        115_200 => BaudRate::B115200,
        230_400 => BaudRate::B230400,
        460_800 => BaudRate::B460800,
        921_600 => BaudRate::B921600,
        _ => return None,
    })
}

impl SerialPort {
    /// Opens the tty at `path` at `baud` (8N1, raw, no modem control).
    pub fn open(path: &Path, baud: u32) -> io::Result<Self> {
        let rate = baud_rate(baud).ok_or_else(|| {
            io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("{baud} baud is not a standard rate"),
            )
        })?;
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags(libc::O_NOCTTY | libc::O_NONBLOCK)
            .open(path)?;
        let mut t = termios::tcgetattr(&file)?;
        termios::cfmakeraw(&mut t);
        termios::cfsetspeed(&mut t, rate)?;
        // 8N1, receiver on, modem lines ignored, no hardware flow control.
        t.control_flags &= !(termios::ControlFlags::PARENB
            | termios::ControlFlags::CSTOPB
            | termios::ControlFlags::CSIZE
            | termios::ControlFlags::CRTSCTS);
        t.control_flags |= termios::ControlFlags::CS8
            | termios::ControlFlags::CREAD
            | termios::ControlFlags::CLOCAL;
        t.input_flags &= !(termios::InputFlags::IXON | termios::InputFlags::IXOFF);
        termios::tcsetattr(&file, SetArg::TCSANOW, &t)?;
        termios::tcflush(&file, termios::FlushArg::TCIOFLUSH)?;
        Ok(Self { file })
    }

    /// Wraps an open descriptor as it is (no termios settings): the master side of a
    /// pseudo-terminal, a socket pair in tests. It is made non-blocking.
    pub fn from_fd(fd: OwnedFd) -> io::Result<Self> {
        let file = File::from(fd);
        let flags = nix::fcntl::fcntl(&file, nix::fcntl::FcntlArg::F_GETFL)?;
        let flags = nix::fcntl::OFlag::from_bits_truncate(flags) | nix::fcntl::OFlag::O_NONBLOCK;
        nix::fcntl::fcntl(&file, nix::fcntl::FcntlArg::F_SETFL(flags))?;
        Ok(Self { file })
    }
}

impl AsFd for SerialPort {
    fn as_fd(&self) -> BorrowedFd<'_> {
        self.file.as_fd()
    }
}

/// An unplugged adapter or a closed pseudo-terminal reads as end of file or `EIO`: the line is
/// gone.
fn gone(e: &io::Error) -> bool {
    matches!(
        e.raw_os_error(),
        Some(libc::EIO | libc::ENXIO | libc::ENODEV)
    )
}

impl embedded_io::ErrorType for SerialPort {
    type Error = io::Error;
}

impl embedded_io::Read for SerialPort {
    /// Reads what is there; when nothing is, waits for it (embedded-io's blocking contract):
    /// the master calls it only after [`SerialLine::wait_readable`]. The end of the line (an
    /// unplugged adapter) is `BrokenPipe`.
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, io::Error> {
        if buf.is_empty() {
            return Ok(0);
        }
        loop {
            match self.file.read(buf) {
                Ok(0) => return Err(io::Error::from(io::ErrorKind::BrokenPipe)),
                Ok(n) => return Ok(n),
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    wait(self.file.as_fd(), Readiness::Readable, far_future())?;
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) if gone(&e) => return Err(io::Error::from(io::ErrorKind::BrokenPipe)),
                Err(e) => return Err(e),
            }
        }
    }
}

impl embedded_io::Write for SerialPort {
    fn write(&mut self, buf: &[u8]) -> Result<usize, io::Error> {
        loop {
            match self.file.write(buf) {
                Ok(n) => return Ok(n),
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    // The output queue is full: wait for room, at most the time a full
                    // frame takes at 1200 baud.
                    if !wait(
                        self.file.as_fd(),
                        Readiness::Writable,
                        Instant::now() + Duration::from_secs(3),
                    )? {
                        return Err(io::Error::from(io::ErrorKind::TimedOut));
                    }
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) if gone(&e) => return Err(io::Error::from(io::ErrorKind::BrokenPipe)),
                Err(e) => return Err(e),
            }
        }
    }

    fn flush(&mut self) -> Result<(), io::Error> {
        Ok(())
    }
}

impl embedded_io::ReadReady for SerialPort {
    /// Whether a read would return at once (with bytes, or with the end of the line).
    fn read_ready(&mut self) -> Result<bool, io::Error> {
        use nix::poll::{PollFd, PollFlags, PollTimeout, poll};
        let mut fds = [PollFd::new(self.file.as_fd(), PollFlags::POLLIN)];
        loop {
            match poll(&mut fds, PollTimeout::ZERO) {
                Ok(n) => return Ok(n > 0),
                Err(nix::errno::Errno::EINTR) => {}
                Err(e) => return Err(io::Error::from(e)),
            }
        }
    }
}

impl SerialLine for SerialPort {
    fn wait_readable(&mut self, deadline: Instant) -> Result<bool, io::Error> {
        wait(self.file.as_fd(), Readiness::Readable, deadline)
    }
}

/// A deadline no wait reaches in practice (a day).
fn far_future() -> Instant {
    Instant::now() + Duration::from_secs(86_400)
}
