//! Fault injection into a running segment, from another thread, without locks.
//!
//! [`Segment::fault_handle`](super::Segment::fault_handle) returns a [`FaultHandle`]; faults
//! pushed into it travel through a wait-free ring buffer and are applied by the segment at the
//! start of the next frame it processes, on whatever thread runs it (the master's cycle thread
//! when the segment is in-process). Applying a fault allocates nothing, so the cycle stays
//! clean while a test injects faults.

/// A fault for one device.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DeviceFault {
    /// Raise the drive's alarm with this identifier (the drive's own name, e.g. `"AL.52"` for the
    /// MR-J4-TM, `"J3"` for the BDHDE).
    RaiseAlarm(&'static str),
    /// Force the following error the drive's model sees to this value, in position units
    /// (`None`: back to the model's own).
    ForceFollowingError(Option<i32>),
    /// Post an emergency message in the device's mailbox.
    Emergency {
        /// Error code.
        error_code: u16,
        /// Error register.
        error_register: u8,
        /// Manufacturer bytes.
        data: [u8; 5],
    },
}

/// A fault to inject.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fault {
    /// A fault for the device at `position`.
    Device {
        /// Position on the segment.
        position: u16,
        /// The fault.
        fault: DeviceFault,
    },
}

/// The injecting side. Send it to the thread that injects; the segment applies what it sends.
pub struct FaultHandle {
    pub(super) tx: rtrb::Producer<Fault>,
}

/// The queue is full (the segment is not processing frames).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("the fault queue is full: the segment is not processing frames")]
pub struct FaultQueueFull;

impl FaultHandle {
    /// Queue a fault for the next frame.
    pub fn inject(&mut self, fault: Fault) -> Result<(), FaultQueueFull> {
        self.tx.push(fault).map_err(|_| FaultQueueFull)
    }
}

impl core::fmt::Debug for FaultHandle {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("FaultHandle").finish_non_exhaustive()
    }
}

/// Capacity of the fault queue.
pub(super) const QUEUE: usize = 64;
