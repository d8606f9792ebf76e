//! The device application behind an emulated ESC: the PDI side.
//!
//! On a real slave the slave controller (ESC) handles the wire and a microcontroller behind its
//! process data interface (PDI) runs the application: it answers state-change requests, serves
//! the mailbox, and exchanges process data at SYNC0 or when a frame arrives. The software slave
//! splits the same way: [`Esc`](super::esc::Esc) is the silicon, a [`Device`] is the firmware.
//!
//! The ESC calls the device:
//! - once at construction for its [`DeviceDescription`] (which becomes the SII EEPROM);
//! - for every state change the master requests that passed the ESC's own checks
//!   ([`Device::request_state`], which may refuse with an AL status code), and after every
//!   change ([`Device::state_changed`]), including the ones the ESC makes on its own (SM
//!   watchdog);
//! - at PRE-OP→SAFE-OP for the process data sizes of the current PDO mapping
//!   ([`Device::process_data_sizes`]), which SM2/SM3 must match;
//! - with every complete mailbox the master wrote ([`Device::mailbox_request`]), and for
//!   unsolicited messages when the read mailbox is free ([`Device::mailbox_poll`]);
//! - at every SYNC0 instant (DC mode), or after every frame that exchanged process data (no
//!   DC), with the output image, whether fresh outputs arrived for that cycle, and the input
//!   image to fill ([`Device::sync`]).
//!
//! Everything runs on the thread that processes frames; a device must not block.

use super::sii::DeviceDescription;
use crate::ec::{AlState, AlStatusCode};
use std::any::Any;

/// Access to the concrete type behind a `dyn Device` (implemented for every `'static` type).
pub trait AsAny: Any {
    /// `self` as `&dyn Any`.
    fn as_any(&self) -> &dyn Any;
    /// `self` as `&mut dyn Any`.
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

impl<T: Any> AsAny for T {
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// Sizes in bytes of the process data of the current PDO mapping: what SM2 (outputs) and SM3
/// (inputs) must be configured to at PRE-OP→SAFE-OP.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ProcessDataSizes {
    /// Output bytes (RxPDOs, master → device).
    pub outputs: usize,
    /// Input bytes (TxPDOs, device → master).
    pub inputs: usize,
}

/// The state of the SYNC unit, as the ESC registers say at the time of a request.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DcSyncStatus {
    /// The ESC supports DC.
    pub supported: bool,
    /// Cyclic operation and SYNC0 are activated (0x0981 bits 0 and 1).
    pub sync0_active: bool,
    /// SYNC1 is activated (0x0981 bit 2).
    pub sync1_active: bool,
    /// SYNC0 cycle time in ns (0x09A0).
    pub sync0_cycle_ns: u32,
    /// SYNC1 cycle time in ns (0x09A4).
    pub sync1_cycle_ns: u32,
    /// SYNC0 pulses generated since SYNC0 was activated (0 until its start time).
    pub sync0_pulses: u64,
}

/// A state change the master requested.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StateRequest {
    /// Current state.
    pub from: AlState,
    /// Requested state.
    pub to: AlState,
    /// The SYNC unit configuration at the time of the request.
    pub dc: DcSyncStatus,
}

/// What triggered a [`Device::sync`] call.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SyncKind {
    /// A SYNC0 pulse of the DC SYNC unit.
    Sync0,
    /// No DC synchronisation is active: a frame exchanged process data with this device
    /// (SM-synchronous or free-run operation).
    Frame,
}

/// One process-data cycle as the device application sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SyncEvent {
    /// What triggered it.
    pub kind: SyncKind,
    /// For [`SyncKind::Sync0`], the system time of the pulse; for [`SyncKind::Frame`], the
    /// device's system time (DC-capable ESC) or local time when the frame passed.
    pub time_ns: u64,
    /// Number of this event since SYNC0 was activated (or since power-up for frame events),
    /// starting at 0.
    pub cycle: u64,
    /// SYNC0 cycle time in ns (0 for frame events).
    pub cycle_time_ns: u32,
    /// The AL state.
    pub state: AlState,
    /// How many complete output buffers the master wrote since the previous event. 0 means
    /// the outputs for this cycle arrived late or not at all; more than 1 means an earlier
    /// cycle's outputs arrived late (after its SYNC0).
    pub outputs_received: u32,
    /// System (or local) time at which the latest output buffer was completed, if any has been
    /// since power-up.
    pub last_outputs_ns: Option<u64>,
    /// Whether outputs are enabled (OP): otherwise the output image holds the last values
    /// received in OP, or zeros, and must be treated as safe state.
    pub outputs_enabled: bool,
}

impl SyncEvent {
    /// Whether fresh outputs arrived for this cycle.
    pub fn outputs_fresh(&self) -> bool {
        self.outputs_received > 0
    }
}

/// The device application behind one emulated ESC.
pub trait Device: AsAny + Send {
    /// What the SII says about the device. Called once, when the slave is created.
    fn description(&self) -> DeviceDescription;

    /// Process data sizes of the current PDO mapping. The ESC compares SM2/SM3 against these at
    /// PRE-OP→SAFE-OP (and when the master changes them in SAFE-OP/OP).
    fn process_data_sizes(&self) -> ProcessDataSizes;

    /// The master requested a state change that passed the ESC's checks (mailbox and process
    /// data SyncManager configuration). Return an AL status code to refuse; the ESC then stays
    /// in `from` with the error flag set. Refusals of downward transitions (towards INIT) are
    /// ignored, as on a real slave.
    fn request_state(&mut self, request: &StateRequest) -> Result<(), AlStatusCode> {
        let _ = request;
        Ok(())
    }

    /// The AL state changed (after a request, or on the ESC's own initiative with `error`).
    fn state_changed(&mut self, from: AlState, to: AlState, error: Option<AlStatusCode>) {
        let _ = (from, to, error);
    }

    /// The master wrote a complete mailbox into SM0; `request` is the whole SM0 buffer. If a
    /// reply is due, write the whole reply mailbox (6-byte header + data) into `reply` (sized
    /// as SM1) and return its length.
    fn mailbox_request(
        &mut self,
        state: AlState,
        request: &[u8],
        reply: &mut [u8],
    ) -> Option<usize> {
        let _ = (state, request, reply);
        None
    }

    /// SM1 is empty and no request is pending: post an unsolicited message (e.g. a CoE
    /// emergency) if one is queued.
    fn mailbox_poll(&mut self, reply: &mut [u8]) -> Option<usize> {
        let _ = reply;
        None
    }

    /// The mailbox was (re)configured or the device went to INIT: forget the duplicate counter
    /// and abort segmented transfers.
    fn mailbox_reset(&mut self) {}

    /// The device was switched off and on ([`crate::esc::Esc::power_cycle`]): back to its
    /// power-on state, keeping only what it keeps in non-volatile memory.
    fn power_cycle(&mut self) {}

    /// The foreign-device behaviour this device shows ([`super::quirks`]). The ESC applies the
    /// process-data ones itself ([`Quirk::StaleInputsUntilOp`](super::quirks::Quirk::StaleInputsUntilOp),
    /// [`Quirk::OutputsInSafeOp`](super::quirks::Quirk::OutputsInSafeOp)); the device applies
    /// the rest.
    fn quirks(&self) -> super::quirks::Quirks {
        super::quirks::Quirks::NONE
    }

    /// Apply an injected fault ([`super::faults`]); `false` if the device does not support it.
    /// Must not allocate: it runs on the thread that processes frames.
    fn inject(&mut self, fault: &super::faults::DeviceFault) -> bool {
        let _ = fault;
        false
    }

    /// One process-data cycle: read `outputs` (SM2 image), fill `inputs` (SM3 image). Return an
    /// AL status code to leave OP for SAFE-OP with the error flag (e.g. 0x001A synchronisation
    /// error after too many missed cycles).
    fn sync(
        &mut self,
        event: &SyncEvent,
        outputs: &[u8],
        inputs: &mut [u8],
    ) -> Result<(), AlStatusCode> {
        let _ = (event, outputs, inputs);
        Ok(())
    }
}

/// Why a device cannot be created by name ([`crate::devices::by_name`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DeviceError {
    /// No device has that name.
    #[error("unknown device {name:?}; known devices: {known}")]
    Unknown {
        /// The name asked for.
        name: String,
        /// The names accepted.
        known: String,
    },
    /// A quirk is unknown or does not apply to the device.
    #[error("device {name:?}: {reason}")]
    Quirk {
        /// The device name as given.
        name: String,
        /// Why.
        reason: String,
    },
    /// The device's built-in data is inconsistent.
    #[error("device {name:?} cannot be built: {reason}")]
    Build {
        /// The device.
        name: String,
        /// Why.
        reason: String,
    },
}
