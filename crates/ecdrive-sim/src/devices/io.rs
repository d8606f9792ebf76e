//! A simple digital-I/O-like device without mailbox.

use crate::device::{Device, ProcessDataSizes, StateRequest, SyncEvent, SyncKind};
use crate::ec::{AlState, AlStatusCode};
use crate::quirks::{Capabilities, Quirks};
use crate::sii::{
    DcOpMode, DeviceDescription, FmmuUsage, Identity, PdoDesc, PdoEntryDesc, SmDesc, SmEnable,
    SmType,
};

pub use crate::rec::TEST_VENDOR_ID;

/// What an [`IoDevice`] has seen, for tests.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct IoObservations {
    /// Number of `sync` calls.
    pub cycles: u64,
    /// Number of SYNC0 events.
    pub sync0_events: u64,
    /// SYNC0 events (in any state) at which no fresh outputs had arrived.
    pub cycles_without_outputs: u64,
    /// SYNC0 events in OP at which no fresh outputs had arrived.
    pub missed_in_op: u64,
    /// SYNC0 events at which more than one output buffer had arrived since the previous one
    /// (an earlier cycle's outputs came late).
    pub late_outputs: u64,
    /// Outputs as of the last cycle in OP.
    pub last_outputs: Vec<u8>,
    /// System time of the last SYNC0 event.
    pub last_sync0_ns: Option<u64>,
    /// SYNC0 cycle time seen.
    pub sync0_cycle_ns: u32,
    /// State changes `(from, to, error)` in order.
    pub transitions: Vec<(AlState, AlState, Option<AlStatusCode>)>,
}

/// A digital-I/O-like device: `outputs` bytes of RxPDO at SM0, `inputs` bytes of TxPDO at SM1,
/// no mailbox, DC capable. Inputs: bytes 0–1 a cycle counter (little-endian), then the outputs
/// as last received in OP, then zeros.
#[derive(Debug, Clone)]
pub struct IoDevice {
    outputs: usize,
    inputs: usize,
    serial: u32,
    refuse: Option<(AlState, AlStatusCode)>,
    counter: u16,
    quirks: Quirks,
    /// What the device has seen.
    pub seen: IoObservations,
}

impl IoDevice {
    /// A device with `outputs` output bytes and `inputs` input bytes (each 0..=1024).
    pub fn new(outputs: usize, inputs: usize) -> Self {
        Self {
            outputs: outputs.min(1024),
            inputs: inputs.min(1024),
            serial: 0,
            refuse: None,
            counter: 0,
            quirks: Quirks::NONE,
            seen: IoObservations::default(),
        }
    }

    /// The same device behaving like one ecdrive did not write ([`crate::quirks`]):
    /// only the process-data quirks apply (it has no mailbox and no CiA 402).
    pub fn with_quirks(mut self, quirks: Quirks) -> Result<Self, String> {
        quirks.check_for("generic-io", Capabilities::default())?;
        self.quirks = quirks;
        Ok(self)
    }

    /// With a serial number.
    pub fn with_serial(mut self, serial: u32) -> Self {
        self.serial = serial;
        self
    }

    /// Refuse requests into state `to` with `code` (to test masters' error paths).
    pub fn refusing(mut self, to: AlState, code: AlStatusCode) -> Self {
        self.refuse = Some((to, code));
        self
    }

    fn entries(prefix: &str, index: u16, bytes: usize) -> Vec<PdoEntryDesc> {
        (0..bytes)
            .map(|i| PdoEntryDesc {
                index,
                sub: (i + 1) as u8,
                name: format!("{prefix} {}", i + 1),
                data_type: 0x05, // UNSIGNED8
                bits: 8,
                flags: 0,
            })
            .collect()
    }
}

impl Device for IoDevice {
    fn quirks(&self) -> Quirks {
        self.quirks
    }

    fn description(&self) -> DeviceDescription {
        let mut sync_managers = Vec::new();
        let mut fmmus = Vec::new();
        let mut rx_pdos = Vec::new();
        let mut tx_pdos = Vec::new();
        if self.outputs > 0 {
            rx_pdos.push(PdoDesc {
                index: 0x1600,
                sm: sync_managers.len() as u8,
                dc_sync: 0,
                name: "Outputs".into(),
                flags: 0x0011, // mandatory, fixed content
                entries: Self::entries("Output", 0x7000, self.outputs),
            });
            sync_managers.push(SmDesc {
                start: 0x1000,
                length: self.outputs as u16,
                control: 0x64,
                enable: SmEnable::ENABLE,
                kind: SmType::Outputs,
            });
            fmmus.push(FmmuUsage::Outputs);
        }
        if self.inputs > 0 {
            tx_pdos.push(PdoDesc {
                index: 0x1A00,
                sm: sync_managers.len() as u8,
                dc_sync: 0,
                name: "Inputs".into(),
                flags: 0x0011,
                entries: Self::entries("Input", 0x6000, self.inputs),
            });
            sync_managers.push(SmDesc {
                start: 0x1800,
                length: self.inputs as u16,
                control: 0x20,
                enable: SmEnable::ENABLE,
                kind: SmType::Inputs,
            });
            fmmus.push(FmmuUsage::Inputs);
        }
        DeviceDescription {
            identity: Identity {
                vendor_id: TEST_VENDOR_ID,
                product_code: 0x0000_0101,
                revision: 0x0001_0000,
                serial: self.serial,
            },
            order: "ECD-IO".into(),
            name: format!("ecdrive generic I/O {}/{}", self.outputs, self.inputs),
            group: "ecdrive test devices".into(),
            sync_managers,
            fmmus,
            rx_pdos,
            tx_pdos,
            dc_modes: vec![
                DcOpMode {
                    name: "FreeRun".into(),
                    description: "SM-synchronous / free run".into(),
                    assign_activate: 0x0000,
                    cycle_time0: 0,
                    shift_time0: 0,
                    shift_time1: 0,
                    sync0_cycle_factor: 0,
                    sync1_cycle_factor: 0,
                },
                DcOpMode {
                    name: "DC".into(),
                    description: "DC SYNC0".into(),
                    assign_activate: 0x0300,
                    cycle_time0: 0,
                    shift_time0: 0,
                    shift_time1: 0,
                    sync0_cycle_factor: 1,
                    sync1_cycle_factor: 0,
                },
            ],
            ..Default::default()
        }
    }

    fn process_data_sizes(&self) -> ProcessDataSizes {
        ProcessDataSizes {
            outputs: self.outputs,
            inputs: self.inputs,
        }
    }

    fn request_state(&mut self, request: &StateRequest) -> Result<(), AlStatusCode> {
        match self.refuse {
            Some((to, code)) if to == request.to => Err(code),
            _ => Ok(()),
        }
    }

    fn state_changed(&mut self, from: AlState, to: AlState, error: Option<AlStatusCode>) {
        self.seen.transitions.push((from, to, error));
    }

    fn sync(
        &mut self,
        event: &SyncEvent,
        outputs: &[u8],
        inputs: &mut [u8],
    ) -> Result<(), AlStatusCode> {
        self.seen.cycles += 1;
        if event.kind == SyncKind::Sync0 {
            self.seen.sync0_events += 1;
            self.seen.last_sync0_ns = Some(event.time_ns);
            self.seen.sync0_cycle_ns = event.cycle_time_ns;
            if event.outputs_received > 1 {
                self.seen.late_outputs += 1;
            }
            if !event.outputs_fresh() {
                self.seen.cycles_without_outputs += 1;
                if event.state == AlState::Op {
                    self.seen.missed_in_op += 1;
                }
            }
        }
        if event.outputs_enabled {
            self.seen.last_outputs.clear();
            self.seen.last_outputs.extend_from_slice(outputs);
        }
        self.counter = self.counter.wrapping_add(1);
        let c = self.counter.to_le_bytes();
        for (i, b) in inputs.iter_mut().enumerate() {
            *b = match i {
                0 | 1 => c.get(i).copied().unwrap_or(0),
                _ => self.seen.last_outputs.get(i - 2).copied().unwrap_or(0),
            };
        }
        Ok(())
    }
}
