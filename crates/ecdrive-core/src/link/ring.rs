//! The receive ring of a raw socket (`PACKET_RX_RING`, `TPACKET_V2`): the kernel writes each
//! frame into a slot of memory shared with the process and marks it ready, so taking a frame
//! that has arrived is reading memory, not a `recv` syscall. Only waiting for one that has not
//! arrived yet is a syscall (`ppoll`, by the socket).

use nix::errno::Errno;
use std::os::fd::{AsRawFd, OwnedFd};
use std::sync::atomic::{AtomicU32, AtomicUsize, Ordering};

/// Slots in the ring: the frames that may wait unread (the socket's receive queue held about
/// a hundred full-size frames before).
const SLOTS: usize = 256;

/// `TPACKET_V2` of the kernel's `enum tpacket_versions` (not in the libc crate).
const TPACKET_V2: libc::c_int = 1;

/// A frame taken from the ring.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Taken {
    /// Nothing has arrived.
    Empty,
    /// A frame of this length was copied into the buffer.
    Frame(usize),
    /// A frame of this length arrived, longer than the buffer: dropped.
    TooLong(usize),
    /// The frame was too long for its slot; the kernel queued it on the socket instead, where
    /// a `recv` takes it.
    Queued,
}

/// The mapped ring. Owns the mapping; the socket it belongs to outlives it (both are fields of
/// the same [`super::raw::RawSocket`], the ring first, so it is unmapped first).
pub struct RxRing {
    base: *mut u8,
    len: usize,
    slot_size: usize,
    slots: usize,
    /// The next slot to read; a reader claims a ready slot by advancing it.
    next: AtomicUsize,
}

// SAFETY: the mapping is owned by this value alone; moving it to another thread moves the only
// handle to it (the kernel's side is synchronised through each slot's status word).
unsafe impl Send for RxRing {}
// SAFETY: readers on several threads claim a slot by a compare-exchange of `next` before they
// read it, so no slot is read by two of them; each slot's status word is atomic.
unsafe impl Sync for RxRing {}

impl std::fmt::Debug for RxRing {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RxRing")
            .field("slot_size", &self.slot_size)
            .field("slots", &self.slots)
            .field("next", &self.next.load(Ordering::Relaxed))
            .finish()
    }
}

fn setsockopt<T>(fd: &OwnedFd, name: libc::c_int, value: &T) -> Result<(), Errno> {
    // SAFETY: `value` points to a live T for the duration of the call and the length passed is
    // its size.
    let r = unsafe {
        libc::setsockopt(
            fd.as_raw_fd(),
            libc::SOL_PACKET,
            name,
            (value as *const T).cast(),
            core::mem::size_of::<T>() as libc::socklen_t,
        )
    };
    if r < 0 { Err(Errno::last()) } else { Ok(()) }
}

impl RxRing {
    /// Set up a ring on `fd` (a bound packet socket that has no ring yet) for frames of up to
    /// `max_frame` bytes. `Err` when the kernel refuses (the caller then receives with
    /// `recv`).
    pub fn new(fd: &OwnedFd, max_frame: usize) -> Result<Self, Errno> {
        setsockopt(fd, libc::PACKET_VERSION, &TPACKET_V2)?;
        // Header, the link-layer address the kernel puts after it, the frame, alignment.
        let need = libc::TPACKET2_HDRLEN + 32 + max_frame + 16;
        let slot_size = need.next_power_of_two().max(2048);
        // SAFETY: sysconf has no preconditions.
        let page = usize::try_from(unsafe { libc::sysconf(libc::_SC_PAGESIZE) })
            .ok()
            .filter(|p| p.is_power_of_two())
            .unwrap_or(4096);
        let block = slot_size.max(page);
        let blocks = (SLOTS * slot_size).div_ceil(block);
        let slots = blocks * (block / slot_size);
        let req = libc::tpacket_req {
            tp_block_size: u32::try_from(block).map_err(|_| Errno::EINVAL)?,
            tp_block_nr: u32::try_from(blocks).map_err(|_| Errno::EINVAL)?,
            tp_frame_size: u32::try_from(slot_size).map_err(|_| Errno::EINVAL)?,
            tp_frame_nr: u32::try_from(slots).map_err(|_| Errno::EINVAL)?,
        };
        setsockopt(fd, libc::PACKET_RX_RING, &req)?;
        let len = block * blocks;
        // SAFETY: mmap of the socket's ring, whose size is exactly the one just requested; the
        // result is checked before use and unmapped in Drop.
        let base = unsafe {
            libc::mmap(
                core::ptr::null_mut(),
                len,
                libc::PROT_READ | libc::PROT_WRITE,
                libc::MAP_SHARED,
                fd.as_raw_fd(),
                0,
            )
        };
        if base == libc::MAP_FAILED {
            return Err(Errno::last());
        }
        Ok(Self {
            base: base.cast(),
            len,
            slot_size,
            slots,
            next: AtomicUsize::new(0),
        })
    }

    fn status(&self, slot: usize) -> &AtomicU32 {
        // SAFETY: every slot starts within the mapping (slot < slots, slots * slot_size ≤ len)
        // with a tpacket2_hdr whose first field is the 4-byte-aligned status word; the kernel
        // and this process synchronise on it atomically (release by the writer, acquire by the
        // reader), as the packet(7) ring protocol prescribes.
        unsafe { &*self.base.add(slot * self.slot_size).cast::<AtomicU32>() }
    }

    /// Take the next frame, if one has arrived, copying it into `buf`.
    pub fn take(&self, buf: &mut [u8]) -> Taken {
        let (slot, status) = loop {
            let slot = self.next.load(Ordering::Acquire);
            let status = self.status(slot).load(Ordering::Acquire);
            if status & libc::TP_STATUS_USER == 0 {
                return Taken::Empty;
            }
            let next = (slot + 1) % self.slots;
            if self
                .next
                .compare_exchange(slot, next, Ordering::AcqRel, Ordering::Acquire)
                .is_ok()
            {
                break (slot, status);
            }
        };
        // SAFETY: the slot is ours until its status goes back to the kernel: its header lies
        // within the mapping (see `status`), read unaligned-safe by value.
        let hdr: libc::tpacket2_hdr = unsafe {
            self.base
                .add(slot * self.slot_size)
                .cast::<libc::tpacket2_hdr>()
                .read_unaligned()
        };
        let (mac, snap, len) = (
            usize::from(hdr.tp_mac),
            hdr.tp_snaplen as usize,
            hdr.tp_len as usize,
        );
        let taken = if status & libc::TP_STATUS_COPY != 0 {
            Taken::Queued
        } else if len > buf.len() || snap < len || mac + snap > self.slot_size {
            Taken::TooLong(len)
        } else {
            // SAFETY: `mac + snap` lies within the slot (checked above), the slot within the
            // mapping; the kernel does not write the slot until its status is handed back below.
            let data = unsafe {
                std::slice::from_raw_parts(self.base.add(slot * self.slot_size + mac), snap)
            };
            buf[..snap].copy_from_slice(data);
            Taken::Frame(snap)
        };
        self.status(slot)
            .store(libc::TP_STATUS_KERNEL, Ordering::Release);
        taken
    }
}

impl Drop for RxRing {
    fn drop(&mut self) {
        // SAFETY: base and len are those of the mapping made in `new`, unmapped only here.
        unsafe {
            libc::munmap(self.base.cast(), self.len);
        }
    }
}
