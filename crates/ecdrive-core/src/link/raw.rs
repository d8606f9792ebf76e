//! An `AF_PACKET` raw socket for EtherCAT frames on one interface.

use super::ring::{RxRing, Taken};
use super::{FrameLink, LinkError};
use crate::ec::ETHERTYPE;
use crate::ec::frame::ETHERNET_HEADER_LEN;
use nix::errno::Errno;
use nix::poll::{PollFd, PollFlags, ppoll};
use nix::sys::time::TimeSpec;
use std::os::fd::{AsFd, AsRawFd, FromRawFd, OwnedFd};
use std::time::{Duration, Instant};

/// `SOL_PACKET` option that stops a packet socket from seeing the frames its host sends
/// (Linux ≥ 4.20). Not in the libc crate.
const PACKET_IGNORE_OUTGOING: libc::c_int = 23;

/// A raw socket bound to one interface and EtherType 0x88A4, non-blocking, with timed
/// receive. It never sees frames sent from this host (`PACKET_IGNORE_OUTGOING`), so one socket
/// serves both directions. Frames are received through a ring shared with the kernel
/// (`PACKET_RX_RING`) where the kernel offers one, so taking a frame that has arrived makes no
/// syscall; otherwise with `recv`. Buffers are the caller's: nothing is allocated per frame.
#[derive(Debug)]
pub struct RawSocket {
    /// Before `fd`: unmapped before the socket closes.
    ring: Option<RxRing>,
    fd: OwnedFd,
    interface: String,
    ifindex: i32,
    mtu: usize,
}

fn valid_name(name: &str) -> bool {
    !name.is_empty()
        && name.len() < libc::IFNAMSIZ
        && !name
            .bytes()
            .any(|b| b == b'/' || b == b':' || b == 0 || b.is_ascii_whitespace())
}

impl RawSocket {
    /// Open a raw socket on `interface`. Needs `CAP_NET_RAW`.
    pub fn open(interface: &str) -> Result<Self, LinkError> {
        if !valid_name(interface) {
            return Err(LinkError::InvalidName {
                interface: interface.to_owned(),
            });
        }
        let io = |op: &'static str, e: Errno| LinkError::Io {
            interface: interface.to_owned(),
            op,
            source: std::io::Error::from_raw_os_error(e as i32),
        };
        let ifindex = match nix::net::if_::if_nametoindex(interface) {
            Ok(i) => i32::try_from(i).map_err(|_| LinkError::NoSuchInterface {
                interface: interface.to_owned(),
            })?,
            Err(Errno::ENODEV) | Err(Errno::ENXIO) => {
                return Err(LinkError::NoSuchInterface {
                    interface: interface.to_owned(),
                });
            }
            Err(e) => return Err(io("looking up the interface index", e)),
        };
        let proto = ETHERTYPE.to_be();
        // SAFETY: plain socket(2) call with constant arguments; the result is checked below.
        let raw = unsafe {
            libc::socket(
                libc::AF_PACKET,
                libc::SOCK_RAW | libc::SOCK_NONBLOCK | libc::SOCK_CLOEXEC,
                libc::c_int::from(proto),
            )
        };
        if raw < 0 {
            let e = Errno::last();
            return Err(match e {
                Errno::EPERM | Errno::EACCES => LinkError::PermissionDenied {
                    interface: interface.to_owned(),
                },
                e => io("creating the raw socket", e),
            });
        }
        // SAFETY: `raw` is a freshly created, valid file descriptor that nothing else owns.
        let fd = unsafe { OwnedFd::from_raw_fd(raw) };

        // SAFETY: sockaddr_ll is plain old data; all-zero is a valid value.
        let mut addr: libc::sockaddr_ll = unsafe { core::mem::zeroed() };
        addr.sll_family = libc::AF_PACKET as libc::c_ushort;
        addr.sll_protocol = proto;
        addr.sll_ifindex = ifindex;
        // SAFETY: `addr` is a valid sockaddr_ll and the length passed matches its size.
        let r = unsafe {
            libc::bind(
                fd.as_raw_fd(),
                (&addr as *const libc::sockaddr_ll).cast(),
                core::mem::size_of::<libc::sockaddr_ll>() as libc::socklen_t,
            )
        };
        if r < 0 {
            let e = Errno::last();
            return Err(match e {
                Errno::ENODEV => LinkError::NoSuchInterface {
                    interface: interface.to_owned(),
                },
                Errno::ENETDOWN => LinkError::InterfaceDown {
                    interface: interface.to_owned(),
                },
                e => io("binding the raw socket", e),
            });
        }
        let one: libc::c_int = 1;
        // SAFETY: the option value points to a live c_int and the length matches. Failure
        // (kernels before 4.20) is tolerated: a socket bound to 0x88A4 does not see outgoing
        // frames on veth or real NICs anyway.
        let _ = unsafe {
            libc::setsockopt(
                fd.as_raw_fd(),
                libc::SOL_PACKET,
                PACKET_IGNORE_OUTGOING,
                (&one as *const libc::c_int).cast(),
                core::mem::size_of::<libc::c_int>() as libc::socklen_t,
            )
        };
        let mtu = Self::query_mtu(&fd, interface).unwrap_or(1500);
        let ring = RxRing::new(&fd, mtu + ETHERNET_HEADER_LEN + 4).ok();
        Ok(Self {
            ring,
            fd,
            interface: interface.to_owned(),
            ifindex,
            mtu,
        })
    }

    fn query_mtu(fd: &OwnedFd, interface: &str) -> Option<usize> {
        // SAFETY: ifreq is plain old data; all-zero is a valid value.
        let mut req: libc::ifreq = unsafe { core::mem::zeroed() };
        for (d, s) in req.ifr_name.iter_mut().zip(interface.bytes()) {
            *d = s as libc::c_char;
        }
        // SAFETY: SIOCGIFMTU reads the NUL-terminated name (the name is shorter than IFNAMSIZ
        // and the rest is zero) and writes the MTU into the union of the ifreq we own.
        let r = unsafe { libc::ioctl(fd.as_raw_fd(), libc::SIOCGIFMTU, &mut req) };
        if r < 0 {
            return None;
        }
        // SAFETY: after a successful SIOCGIFMTU the union holds the MTU.
        let mtu = unsafe { req.ifr_ifru.ifru_mtu };
        usize::try_from(mtu).ok()
    }

    /// The interface name.
    pub fn interface(&self) -> &str {
        &self.interface
    }

    /// The interface index.
    pub fn ifindex(&self) -> i32 {
        self.ifindex
    }

    /// The interface MTU (payload bytes per frame).
    pub fn mtu(&self) -> usize {
        self.mtu
    }

    /// The largest frame this interface carries (MTU plus Ethernet header and one VLAN tag).
    pub fn max_frame_len(&self) -> usize {
        self.mtu + ETHERNET_HEADER_LEN + 4
    }

    fn io_err(&self, op: &'static str, e: Errno) -> LinkError {
        match e {
            Errno::ENETDOWN => LinkError::InterfaceDown {
                interface: self.interface.clone(),
            },
            Errno::ENODEV | Errno::ENXIO => LinkError::NoSuchInterface {
                interface: self.interface.clone(),
            },
            e => LinkError::Io {
                interface: self.interface.clone(),
                op,
                source: std::io::Error::from_raw_os_error(e as i32),
            },
        }
    }

    fn wait(&self, events: PollFlags, timeout: Option<Duration>) -> Result<bool, LinkError> {
        let mut fds = [PollFd::new(self.fd.as_fd(), events)];
        let ts = timeout.map(TimeSpec::from_duration);
        match ppoll(&mut fds, ts, None) {
            Ok(n) => Ok(n > 0),
            Err(Errno::EINTR) => Ok(false),
            Err(e) => Err(self.io_err("waiting for the socket", e)),
        }
    }

    /// Wait for a frame until `deadline` (`None`: forever); `false` once it has passed.
    fn wait_until(&self, deadline: Option<Instant>) -> Result<bool, LinkError> {
        let remaining = match deadline {
            None => None,
            Some(d) => {
                let now = Instant::now();
                if now >= d {
                    return Ok(false);
                }
                Some(d - now)
            }
        };
        self.wait(PollFlags::POLLIN, remaining)?;
        Ok(true)
    }

    /// Whether frames are received through the ring shared with the kernel (no syscall for a
    /// frame that has arrived) rather than with `recv`.
    pub fn has_rx_ring(&self) -> bool {
        self.ring.is_some()
    }

    /// Send one frame (a whole Ethernet frame without FCS).
    pub fn send(&self, frame: &[u8]) -> Result<(), LinkError> {
        if frame.len() > self.max_frame_len() {
            return Err(LinkError::FrameTooLarge {
                interface: self.interface.clone(),
                len: frame.len(),
                max: self.max_frame_len(),
            });
        }
        let mut spins = 0u32;
        loop {
            // SAFETY: the pointer and length describe the caller's live slice.
            let n = unsafe {
                libc::send(
                    self.fd.as_raw_fd(),
                    frame.as_ptr().cast(),
                    frame.len(),
                    libc::MSG_DONTWAIT,
                )
            };
            if n >= 0 {
                return Ok(());
            }
            match Errno::last() {
                Errno::EINTR => continue,
                Errno::EAGAIN | Errno::ENOBUFS if spins < 1000 => {
                    spins += 1;
                    self.wait(PollFlags::POLLOUT, Some(Duration::from_millis(1)))?;
                }
                Errno::EMSGSIZE => {
                    return Err(LinkError::FrameTooLarge {
                        interface: self.interface.clone(),
                        len: frame.len(),
                        max: self.max_frame_len(),
                    });
                }
                e => return Err(self.io_err("sending a frame", e)),
            }
        }
    }

    /// Receive one frame into `buf`, waiting at most `timeout` (`None`: forever). Returns the
    /// frame length, or `None` on timeout. A frame larger than `buf` is dropped and reported as
    /// [`LinkError::Truncated`].
    pub fn recv(
        &self,
        buf: &mut [u8],
        timeout: Option<Duration>,
    ) -> Result<Option<usize>, LinkError> {
        let deadline = timeout.map(|t| Instant::now() + t);
        loop {
            if let Some(ring) = &self.ring {
                match ring.take(buf) {
                    Taken::Frame(n) => return Ok(Some(n)),
                    Taken::TooLong(len) => {
                        return Err(LinkError::Truncated {
                            interface: self.interface.clone(),
                            len,
                            capacity: buf.len(),
                        });
                    }
                    // Too long for its slot: on the socket's queue, taken by recv below.
                    Taken::Queued => {}
                    Taken::Empty => {
                        if !self.wait_until(deadline)? {
                            return Ok(None);
                        }
                        continue;
                    }
                }
            }
            // SAFETY: the pointer and length describe the caller's live, writable slice.
            let n = unsafe {
                libc::recv(
                    self.fd.as_raw_fd(),
                    buf.as_mut_ptr().cast(),
                    buf.len(),
                    libc::MSG_DONTWAIT | libc::MSG_TRUNC,
                )
            };
            if n >= 0 {
                let n = n as usize;
                if n > buf.len() {
                    return Err(LinkError::Truncated {
                        interface: self.interface.clone(),
                        len: n,
                        capacity: buf.len(),
                    });
                }
                return Ok(Some(n));
            }
            match Errno::last() {
                Errno::EINTR => continue,
                Errno::EAGAIN => {
                    if !self.wait_until(deadline)? {
                        return Ok(None);
                    }
                }
                e => return Err(self.io_err("receiving a frame", e)),
            }
        }
    }
}

impl FrameLink for RawSocket {
    fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        RawSocket::send(self, frame)
    }

    fn describe(&self) -> String {
        format!("interface {}", self.interface())
    }

    fn recv(
        &mut self,
        buf: &mut [u8],
        timeout: Option<Duration>,
    ) -> Result<Option<usize>, LinkError> {
        RawSocket::recv(self, buf, timeout)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_checked_before_any_syscall() {
        for bad in ["", "a/b", "eth 0", "x:y", "0123456789abcdef"] {
            assert!(
                matches!(RawSocket::open(bad), Err(LinkError::InvalidName { .. })),
                "{bad:?}"
            );
        }
    }

    #[test]
    fn missing_interface_is_named() {
        let e = RawSocket::open("ecdnosuch0").unwrap_err();
        assert_eq!(e.to_string(), "interface ecdnosuch0 does not exist");
    }
}
