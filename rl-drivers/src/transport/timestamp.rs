//! Kernel receive timestamps (`SO_TIMESTAMPNS`): the time a datagram or frame reached the
//! socket, as the kernel saw it, whatever the receiving thread was doing then. A real-time
//! receiver compares it with the time it took the message to tell how late it woke;
//! SocketCAN and cannelloni UDP both report it in [`Received`](super::can::Received).
//!
//! The clock is `CLOCK_REALTIME` (a [`Duration`] since the Unix epoch): compare it with
//! [`since_epoch`], not with an `Instant`.
//!
//! All the `unsafe` of the timestamped receive is here, each block with its argument.

use std::io;
use std::mem::{size_of, size_of_val, zeroed};
use std::net::{Ipv4Addr, Ipv6Addr, SocketAddr, SocketAddrV4, SocketAddrV6};
use std::os::fd::{AsRawFd, BorrowedFd};
use std::time::{Duration, SystemTime};

/// Now on the timestamps' clock.
pub fn since_epoch() -> Duration {
    SystemTime::now()
        .duration_since(SystemTime::UNIX_EPOCH)
        .unwrap_or(Duration::ZERO)
}

/// Turns kernel receive timestamps on for `fd`.
pub(crate) fn enable(fd: BorrowedFd<'_>) -> io::Result<()> {
    let on: libc::c_int = 1;
    // SAFETY: `on` is an initialised `c_int` that lives across the call; the kernel only reads
    // `size_of::<c_int>()` bytes of it.
    let r = unsafe {
        libc::setsockopt(
            fd.as_raw_fd(),
            libc::SOL_SOCKET,
            libc::SO_TIMESTAMPNS,
            (&raw const on).cast(),
            size_of::<libc::c_int>() as libc::socklen_t,
        )
    };
    if r < 0 {
        Err(io::Error::last_os_error())
    } else {
        Ok(())
    }
}

/// One message received without blocking: its length, the sender (for an IP socket) and the
/// kernel's receive timestamp (where [`enable`]d).
pub(crate) fn recv(
    fd: BorrowedFd<'_>,
    buf: &mut [u8],
) -> io::Result<(usize, Option<SocketAddr>, Option<Duration>)> {
    let mut iov = libc::iovec {
        iov_base: buf.as_mut_ptr().cast(),
        iov_len: buf.len(),
    };
    // Room for one `timespec` control message, aligned like the header it follows.
    let mut control = [0u64; 8];
    // SAFETY: an all-zero `sockaddr_storage` is a valid value (integers and padding).
    let mut name: libc::sockaddr_storage = unsafe { zeroed() };
    // SAFETY: an all-zero `msghdr` is valid (null pointers, zero lengths); the pointers set
    // below point to `name`, `iov` and `control`, which outlive the `recvmsg` call.
    let mut msg: libc::msghdr = unsafe { zeroed() };
    msg.msg_name = (&raw mut name).cast();
    msg.msg_namelen = size_of::<libc::sockaddr_storage>() as libc::socklen_t;
    msg.msg_iov = &raw mut iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control.as_mut_ptr().cast();
    msg.msg_controllen = size_of_val(&control) as _;
    // SAFETY: `msg` describes buffers valid for writes of their stated lengths.
    let n = unsafe { libc::recvmsg(fd.as_raw_fd(), &raw mut msg, libc::MSG_DONTWAIT) };
    if n < 0 {
        return Err(io::Error::last_os_error());
    }
    let mut timestamp = None;
    // SAFETY: the CMSG macros walk the control buffer the kernel filled, within
    // `msg_controllen`; a `SCM_TIMESTAMPNS` message carries one `timespec`, read unaligned.
    unsafe {
        let mut cmsg = libc::CMSG_FIRSTHDR(&raw const msg);
        while !cmsg.is_null() {
            if (*cmsg).cmsg_level == libc::SOL_SOCKET && (*cmsg).cmsg_type == libc::SCM_TIMESTAMPNS
            {
                let ts: libc::timespec = std::ptr::read_unaligned(libc::CMSG_DATA(cmsg).cast());
                timestamp = Some(Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32));
            }
            cmsg = libc::CMSG_NXTHDR(&raw const msg, cmsg);
        }
    }
    let from = match libc::c_int::from(name.ss_family) {
        libc::AF_INET if msg.msg_namelen as usize >= size_of::<libc::sockaddr_in>() => {
            // SAFETY: the kernel wrote a `sockaddr_in` (family AF_INET, length checked) into
            // `name`, which is large and aligned enough for any socket address.
            let a: libc::sockaddr_in = unsafe { std::ptr::read((&raw const name).cast()) };
            Some(SocketAddr::V4(SocketAddrV4::new(
                Ipv4Addr::from(u32::from_be(a.sin_addr.s_addr)),
                u16::from_be(a.sin_port),
            )))
        }
        libc::AF_INET6 if msg.msg_namelen as usize >= size_of::<libc::sockaddr_in6>() => {
            // SAFETY: as above, for a `sockaddr_in6` (family AF_INET6, length checked).
            let a: libc::sockaddr_in6 = unsafe { std::ptr::read((&raw const name).cast()) };
            Some(SocketAddr::V6(SocketAddrV6::new(
                Ipv6Addr::from(a.sin6_addr.s6_addr),
                u16::from_be(a.sin6_port),
                u32::from_be(a.sin6_flowinfo),
                a.sin6_scope_id,
            )))
        }
        _ => None,
    };
    Ok((n as usize, from, timestamp))
}
