//! One emulated EtherCAT slave controller (ESC): register memory with the real write masks and
//! side effects, SyncManagers (mailbox handshake with repeat, buffered process data), FMMUs with
//! bit granularity, the SII EEPROM interface, the AL state machine with the checks a slave makes,
//! the SM watchdog, and the DC unit.
//!
//! An [`Esc`] is the silicon; the firmware behind it is a [`Device`]. The [`Segment`]
//! (`super::segment`) routes datagrams to ESCs; tests may also drive an ESC directly through
//! [`Esc::ecat_read`], [`Esc::ecat_write`] and [`Esc::logical`].
//!
//! The ESC is one type over several files, one concern each: the register map (`regs`), the
//! SyncManagers (`sync_managers`), the FMMUs and logical addressing (`fmmu`), the mailbox
//! (`mailbox`), the SII EEPROM interface (`eeprom`), the AL state machine (`al`), the DC clock
//! (`dc`) and what its registers and SYNC signals do (`dc_sync`); this file holds the memory,
//! physical access and the end-of-frame work.
//!
//! [`Segment`]: super::segment::Segment

mod al;
mod dc;
mod dc_sync;
mod eeprom;
mod fmmu;
mod mailbox;
mod regs;
mod sync_managers;
mod timing;

pub use dc::{DcUnit, SyncGen};
pub use regs::{IMPLEMENTED, REG_SPACE, RegisterMap, TRIGGER};
pub use timing::TimingStats;

use super::device::{DcSyncStatus, Device, StateRequest, SyncEvent, SyncKind};
use super::quirks::Quirk;
use super::rec;
use super::sii::{self, DeviceDescription, SiiError, SiiImage, SmType};
use crate::ec::{AlState, AlStatusCode, Command};

/// Maximum number of SyncManagers an ESC can have.
pub const MAX_SM: usize = 16;
/// Maximum number of FMMUs an ESC can have.
pub const MAX_FMMU: usize = 16;

/// The ESC's digital output register, "Digital I/O Output Data" (0x0F00:0x0F03, ET1100): a
/// device without a microcontroller (digital I/O mode) has its output SyncManagers here, one
/// byte each, so that the FMMU writes straight into the output pins.
pub const DIGITAL_OUT: core::ops::Range<usize> = 0x0F00..0x0F04;

/// A set of SyncManager numbers (bit n: SM n): the process-data SMs of one direction. A
/// device may have several (four one-byte output SMs on the digital output register).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct SmSet(u16);

impl SmSet {
    /// Every SM of `kind` in the description.
    fn of(desc: &DeviceDescription, kind: SmType) -> Self {
        Self(
            desc.sync_managers
                .iter()
                .enumerate()
                .filter(|(i, s)| s.kind == kind && *i < MAX_SM)
                .fold(0, |m, (i, _)| m | 1 << i),
        )
    }

    fn contains(self, n: u8) -> bool {
        n < 16 && self.0 & (1 << n) != 0
    }

    fn iter(self) -> impl Iterator<Item = u8> {
        (0..16u8).filter(move |&n| self.contains(n))
    }
}

/// Distributed-clock support of an ESC (register 0x0008 bits 2 and 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DcSupport {
    /// No DC unit.
    None,
    /// 32-bit system time.
    Bits32,
    /// 64-bit system time.
    Bits64,
}

impl DcSupport {
    /// Whether the ESC has a DC unit.
    pub const fn supported(self) -> bool {
        !matches!(self, Self::None)
    }
}

/// Hardware properties of an emulated ESC: what the silicon is, not what the device does.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EscConfig {
    /// ESC type (0x0000).
    pub esc_type: u8,
    /// ESC revision (0x0001).
    pub revision: u8,
    /// ESC build (0x0002).
    pub build: u16,
    /// Number of FMMUs (0x0004), at most 16.
    pub fmmu_count: u8,
    /// Number of SyncManagers (0x0005), at most 16.
    pub sm_count: u8,
    /// Process RAM in KiB (0x0006); RAM starts at 0x1000.
    pub ram_kib: u8,
    /// Port descriptor (0x0007): two bits per port.
    pub port_descriptor: u8,
    /// DC support.
    pub dc: DcSupport,
    /// Reset value of the watchdog divider (0x0400). 0x09C2 gives 100 µs watchdog units.
    pub watchdog_divider: u16,
    /// Reset value of the process-data (SM) watchdog time (0x0420), in watchdog units. The ESC
    /// reset value is 1000 (100 ms). 0 disables the SM watchdog; tests that must not depend on
    /// scheduling set 0 or a large value.
    pub sm_watchdog: u16,
    /// Reset value of the PDI watchdog time (0x0410).
    pub pdi_watchdog: u16,
    /// Local clock offset against the host clock in ns.
    pub clock_offset_ns: i64,
    /// Local clock drift against the host clock in ppb.
    pub clock_drift_ppb: i64,
    /// The EEPROM's write protection is on (its WP pin tied high): a write command is not
    /// acknowledged (0x0502 bit 13, "acknowledge/command error") and the word keeps its value.
    pub eeprom_write_protected: bool,
    /// Frames an EEPROM command keeps the interface busy (0x0502 bit 15) before it is done:
    /// 0, done as the frame passes (an ESC emulating its EEPROM from the PDI's memory); a real
    /// I²C EEPROM takes some hundred µs per read, several frames at start-up's rates. While
    /// busy, writes to 0x0502–0x050F are ignored and the data registers keep the previous
    /// command's data (ESC datasheets, SII EEPROM interface).
    pub eeprom_busy_frames: u8,
    /// The EEPROM interface reads 4 bytes per command (0x0502 bit 6 clear), as ESCs with a
    /// 32-bit data register do; else 8.
    pub eeprom_reads_4_bytes: bool,
}

impl Default for EscConfig {
    fn default() -> Self {
        Self {
            esc_type: rec::ESC_TYPE,
            revision: rec::ESC_REVISION,
            build: rec::ESC_BUILD,
            fmmu_count: rec::FMMU_COUNT,
            sm_count: rec::SM_COUNT,
            ram_kib: rec::RAM_KIB,
            port_descriptor: 0x0F,
            dc: DcSupport::Bits64,
            watchdog_divider: 0x09C2,
            sm_watchdog: 1000,
            pdi_watchdog: 1000,
            clock_offset_ns: 0,
            clock_drift_ppb: 0,
            eeprom_write_protected: false,
            eeprom_busy_frames: 0,
            eeprom_reads_4_bytes: false,
        }
    }
}

impl EscConfig {
    /// The ESC features register value (0x0008).
    pub fn features(&self) -> u16 {
        // b6 enhanced link detection MII, b7 separate FCS error handling.
        let base = 0x00C0;
        match self.dc {
            DcSupport::None => base,
            DcSupport::Bits32 => base | 0x0004 | 0x0100,
            DcSupport::Bits64 => base | 0x0004 | 0x0008 | 0x0100,
        }
    }
}

/// Timing of the frame that carries a datagram, at one slave.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Hop {
    /// Host time at which the frame passes this slave's processing unit (forward direction,
    /// port 0).
    pub forward_ns: u64,
    /// Host time at which the frame comes back through port 1, if port 1 is open.
    pub return_ns: Option<u64>,
}

impl Hop {
    /// A hop at `t` with port 1 closed (last slave, or tests).
    pub const fn at(t: u64) -> Self {
        Self {
            forward_ns: t,
            return_ns: None,
        }
    }
}

/// Work the ESC has to do at the end of the frame (the PDI reacting).
mod pending {
    pub const MBX_WRITTEN: u8 = 0x01;
    pub const MBX_READ: u8 = 0x02;
    pub const MBX_REPEAT: u8 = 0x04;
    pub const PD_ACCESS: u8 = 0x08;
    pub const SM_CHANGED: u8 = 0x10;
    pub const MBX_POLL: u8 = 0x20;
    pub const DEADLINE: u8 = 0x40;
    pub const SII_BUSY: u8 = 0x80;
}

#[derive(Debug, Clone, Copy, Default)]
struct SmView {
    idx: u8,
    start: usize,
    end: usize,
    mailbox: bool,
    ecat_writes: bool,
    /// Enabled by ECAT and not deactivated by the PDI.
    usable: bool,
}

/// Mailbox layout from the SII.
#[derive(Debug, Clone, Copy)]
struct MbxLayout {
    sm_out: u8,
    sm_in: u8,
    out_start: u16,
    out_len: u16,
    in_start: u16,
    in_len: u16,
}

/// Firmware-side mailbox state.
#[derive(Debug, Default)]
struct MailboxRt {
    running: bool,
    request: Vec<u8>,
    reply: Vec<u8>,
    backup: Vec<u8>,
    backup_valid: bool,
}

/// Firmware-side process data state.
#[derive(Debug, Default)]
struct ProcessRt {
    outputs: Vec<u8>,
    outputs_received: u32,
    last_outputs_ns: Option<u64>,
    frame_cycles: u64,
    /// Where a device with [`Quirk::StaleInputsUntilOp`] writes its inputs below OP.
    scratch: Vec<u8>,
    /// The inputs of a device with several input SMs, gathered: the device writes them here
    /// and they are scattered into the SMs (sized once).
    in_image: Vec<u8>,
}

/// One emulated ESC.
#[derive(Debug)]
pub struct Esc {
    cfg: EscConfig,
    map: RegisterMap,
    mem: Box<[u8]>,
    sii: SiiImage,
    state: AlState,
    mbx: Option<MbxLayout>,
    boot_mbx: Option<MbxLayout>,
    sm_out_pd: SmSet,
    sm_in_pd: SmSet,
    /// The device's stack enables its output SM with OP only
    /// ([`crate::quirks::Quirk::OutputsOnlyInOp`]).
    outputs_only_in_op: bool,
    sms: Vec<SmView>,
    fmmus: Vec<crate::ec::register::FmmuConfig>,
    mailbox: MailboxRt,
    pd: ProcessRt,
    dc: DcUnit,
    wd_deadline: Option<u64>,
    pending: u8,
    reset_step: u8,
    /// Frame ends left before the running EEPROM command is done
    /// ([`EscConfig::eeprom_busy_frames`]).
    sii_busy: u8,
    scratch: Vec<u8>,
    station_address_changed: bool,
    /// Opt-in timing statistics (boxed: most ESCs never enable them).
    timing: Option<Box<TimingStats>>,
}

fn overlaps(a: usize, b: usize, lo: usize, hi: usize) -> bool {
    a < hi && b > lo
}

impl Esc {
    /// An ESC fronting a device with this description, in its power-on state.
    pub fn new(desc: &DeviceDescription, cfg: EscConfig) -> Result<Self, SiiError> {
        let sii = sii::build(desc)?;
        Ok(Self::with_sii(desc, sii, cfg))
    }

    /// An ESC with an explicit SII image (e.g. a dump), using `desc` for the firmware's own
    /// view of its mailbox and process data SyncManagers.
    pub fn with_sii(desc: &DeviceDescription, sii: SiiImage, mut cfg: EscConfig) -> Self {
        cfg.fmmu_count = cfg.fmmu_count.min(MAX_FMMU as u8);
        cfg.sm_count = cfg.sm_count.min(MAX_SM as u8);
        let ram = usize::from(cfg.ram_kib) * 1024;
        let mbx = desc.mailbox.as_ref().and_then(|m| {
            Some(MbxLayout {
                sm_out: desc.sm_index(SmType::MailboxOut).unwrap_or(0),
                sm_in: desc.sm_index(SmType::MailboxIn).unwrap_or(1),
                out_start: m.rx_offset,
                out_len: m.rx_size,
                in_start: m.tx_offset,
                in_len: m.tx_size,
            })
            .filter(|l| l.out_len > 0 || l.in_len > 0)
        });
        let boot_mbx = desc.mailbox.as_ref().and_then(|m| {
            m.bootstrap.map(|b| MbxLayout {
                sm_out: desc.sm_index(SmType::MailboxOut).unwrap_or(0),
                sm_in: desc.sm_index(SmType::MailboxIn).unwrap_or(1),
                out_start: b[0],
                out_len: b[1],
                in_start: b[2],
                in_len: b[3],
            })
        });
        let mut esc = Self {
            map: RegisterMap::new(&cfg),
            mem: vec![0u8; REG_SPACE + ram].into_boxed_slice(),
            sii,
            state: AlState::Init,
            mbx,
            boot_mbx,
            sm_out_pd: SmSet::of(desc, SmType::Outputs),
            sm_in_pd: SmSet::of(desc, SmType::Inputs),
            outputs_only_in_op: false,
            sms: Vec::with_capacity(MAX_SM),
            fmmus: Vec::with_capacity(MAX_FMMU),
            mailbox: MailboxRt::default(),
            pd: ProcessRt::default(),
            dc: DcUnit::new(cfg.clock_offset_ns, cfg.clock_drift_ppb),
            wd_deadline: None,
            pending: 0,
            reset_step: 0,
            sii_busy: 0,
            scratch: Vec::new(),
            station_address_changed: false,
            timing: None,
            cfg,
        };
        let req = usize::from(mbx.map(|m| m.out_len).unwrap_or(0));
        let rep = usize::from(mbx.map(|m| m.in_len).unwrap_or(0));
        esc.mailbox.request = vec![0; req];
        esc.mailbox.reply = vec![0; rep];
        esc.mailbox.backup = vec![0; rep];
        esc.power_on();
        esc
    }

    /// Put every register into its power-on state and load the ESC configuration area from the
    /// SII (as after a power cycle or an ECAT reset).
    fn power_on(&mut self) {
        self.mem.fill(0);
        self.sii_busy = 0;
        let c = self.cfg.clone();
        self.put(0x0000, &[c.esc_type, c.revision]);
        self.put_u16(0x0002, c.build);
        self.put(
            0x0004,
            &[c.fmmu_count, c.sm_count, c.ram_kib, c.port_descriptor],
        );
        self.put_u16(0x0008, c.features());
        self.put(0x0100, &[0x01, 0x00, 0x07, 0x00]);
        self.put_u16(0x0120, AlState::Init as u16);
        self.put_u16(0x0130, AlState::Init as u16);
        self.put_u16(0x0400, c.watchdog_divider);
        self.put_u16(0x0410, c.pdi_watchdog);
        self.put_u16(0x0420, c.sm_watchdog);
        self.put_u16(0x0440, 0x0001);
        if c.dc.supported() {
            self.put_u16(0x0930, 0x1000);
            self.put(0x0934, &[0x04, 0x0C]);
        }
        self.state = AlState::Init;
        self.sms.clear();
        self.fmmus.clear();
        self.mailbox.running = false;
        self.mailbox.backup_valid = false;
        self.pd = ProcessRt::default();
        self.dc = DcUnit::new(c.clock_offset_ns, c.clock_drift_ppb);
        self.wd_deadline = None;
        self.pending = 0;
        self.reset_step = 0;
        self.station_address_changed = true;
        self.sii_reload();
        self.update_pdi_deactivation();
    }

    // ---------------------------------------------------------------- small memory helpers

    fn put(&mut self, at: usize, bytes: &[u8]) {
        if let Some(d) = self.mem.get_mut(at..at + bytes.len()) {
            d.copy_from_slice(bytes);
        }
    }

    fn put_u16(&mut self, at: usize, v: u16) {
        self.put(at, &v.to_le_bytes());
    }

    fn put_u32(&mut self, at: usize, v: u32) {
        self.put(at, &v.to_le_bytes());
    }

    fn put_u64(&mut self, at: usize, v: u64) {
        self.put(at, &v.to_le_bytes());
    }

    fn byte(&self, at: usize) -> u8 {
        self.mem.get(at).copied().unwrap_or(0)
    }

    fn get_u16(&self, at: usize) -> u16 {
        u16::from_le_bytes([self.byte(at), self.byte(at + 1)])
    }

    fn get_u32(&self, at: usize) -> u32 {
        u32::from_le_bytes([
            self.byte(at),
            self.byte(at + 1),
            self.byte(at + 2),
            self.byte(at + 3),
        ])
    }

    fn get_u64(&self, at: usize) -> u64 {
        u64::from(self.get_u32(at)) | u64::from(self.get_u32(at + 4)) << 32
    }

    fn set_bits(&mut self, at: usize, bits: u8, on: bool) {
        if let Some(b) = self.mem.get_mut(at) {
            if on {
                *b |= bits;
            } else {
                *b &= !bits;
            }
        }
    }

    // ---------------------------------------------------------------- public inspection

    /// The hardware configuration.
    pub fn config(&self) -> &EscConfig {
        &self.cfg
    }

    /// The SII EEPROM content.
    pub fn sii(&self) -> &SiiImage {
        &self.sii
    }

    /// Turn the EEPROM's write protection on or off ([`EscConfig::eeprom_write_protected`]).
    pub fn set_eeprom_write_protected(&mut self, on: bool) {
        self.cfg.eeprom_write_protected = on;
    }

    /// Replace the EEPROM's content (as saved from an earlier run: an EEPROM keeps what was
    /// written to it) and load the ESC configuration area from it. The size must be the
    /// EEPROM's.
    pub fn load_eeprom(&mut self, bytes: &[u8]) -> Result<(), String> {
        let size = self.sii.bytes().len();
        if bytes.len() != size {
            return Err(format!(
                "{} bytes, but this device's EEPROM has {size}",
                bytes.len()
            ));
        }
        self.sii.bytes_mut().copy_from_slice(bytes);
        self.sii_reload();
        Ok(())
    }

    /// Switch the slave off and on: every register to its power-on state, the configuration
    /// area loaded from the EEPROM (which keeps its content), the device told it is in INIT
    /// and its mailbox reset. A device with power-on behaviour of its own (the emulated
    /// drives) gets [`Device::power_cycle`] as well.
    pub fn power_cycle(&mut self, dev: &mut dyn Device) {
        let from = self.state;
        self.power_on();
        dev.mailbox_reset();
        if from != AlState::Init {
            dev.state_changed(from, AlState::Init, None);
        }
        dev.power_cycle();
    }

    /// Configured station address (0x0010).
    pub fn station_address(&self) -> u16 {
        self.get_u16(0x0010)
    }

    /// Configured station alias (0x0012).
    pub fn station_alias(&self) -> u16 {
        self.get_u16(0x0012)
    }

    /// Whether FP commands also match the alias (DL control 0x0103 bit 0).
    pub fn alias_enabled(&self) -> bool {
        self.byte(0x0103) & 0x01 != 0
    }

    /// Whether the station address or alias settings changed since the last call (the segment
    /// keeps an address index).
    pub fn take_address_changed(&mut self) -> bool {
        core::mem::take(&mut self.station_address_changed)
    }

    /// Current AL state.
    pub fn al_state(&self) -> AlState {
        self.state
    }

    /// AL status error flag (0x0130 bit 4).
    pub fn al_error(&self) -> bool {
        self.byte(0x0130) & 0x10 != 0
    }

    /// AL status code (0x0134).
    pub fn al_status_code(&self) -> AlStatusCode {
        AlStatusCode(self.get_u16(0x0134))
    }

    /// Copy register or RAM content without any side effect (PDI-side view, tests). Bytes
    /// beyond the memory read as 0.
    pub fn peek(&self, addr: u16, out: &mut [u8]) {
        let a = usize::from(addr);
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.byte(a + i);
        }
    }

    /// Read a little-endian u16 register without side effects.
    pub fn peek_u16(&self, addr: u16) -> u16 {
        self.get_u16(usize::from(addr))
    }

    /// Read a little-endian u32 register without side effects.
    pub fn peek_u32(&self, addr: u16) -> u32 {
        self.get_u32(usize::from(addr))
    }

    /// Local time at host time `host_ns`.
    pub fn local_time(&self, host_ns: u64) -> u64 {
        self.dc.local(host_ns)
    }

    /// DC system time at host time `host_ns`.
    pub fn system_time(&self, host_ns: u64) -> u64 {
        self.dc.system(host_ns, self.get_u64(0x0920))
    }

    /// The SYNC0 generator state.
    pub fn sync_state(&self) -> SyncGen {
        self.dc.sync
    }

    /// The latched output image (the output SMs' content as last completed by the master,
    /// in SM order).
    pub fn outputs(&self) -> &[u8] {
        &self.pd.outputs
    }

    /// The input image (the input SM's buffer, or the input SMs' in SM order), empty while no
    /// input SM is enabled.
    pub fn inputs(&self) -> &[u8] {
        let mut ranges = self.pd_ranges(self.sm_in_pd);
        match (ranges.next(), ranges.next()) {
            (Some((s, e)), None) => self.mem.get(s..e).unwrap_or(&[]),
            (Some(_), Some(_)) => &self.pd.in_image,
            _ => &[],
        }
    }

    /// Set DL status (0x0110) for the slave's position: port 0 is always connected; port 1
    /// is open unless this is the last slave; ports 2 and 3 are closed.
    pub fn set_topology(&mut self, port1_open: bool) {
        // b0 PDI operational (EEPROM loaded), b1 PDI watchdog not expired, b4 link port 0,
        // b9 communication on port 0, b12/b14 loop closed on ports 2/3.
        let mut v: u16 = 0x0002 | 0x0010 | 0x0200 | 0x1000 | 0x4000;
        if self.sii.checksum_ok() {
            v |= 0x0001;
        }
        if port1_open {
            v |= 0x0020 | 0x0800;
        } else {
            v |= 0x0400;
        }
        self.put_u16(0x0110, v);
    }

    /// Whether port 1 is open (DL status).
    pub fn port1_open(&self) -> bool {
        self.get_u16(0x0110) & 0x0020 != 0
    }

    /// Increment the invalid-frame counter of port 0 (0x0300), saturating.
    pub fn count_invalid_frame(&mut self) {
        self.count(0x0300);
    }

    /// Increment the RX error counter of `port` (0x0301 + 2 × port), saturating: a frame
    /// received with a bit error (CRC, symbol error) on that port.
    pub fn count_rx_error(&mut self, port: u8) {
        self.count(0x0301 + 2 * usize::from(port.min(3)));
    }

    /// Increment the forwarded RX error counter of `port` (0x0308 + port), saturating: a frame
    /// received on that port already marked as erroneous by a device before this one.
    pub fn count_forwarded_error(&mut self, port: u8) {
        self.count(0x0308 + usize::from(port.min(3)));
    }

    /// Increment the lost link counter of `port` (0x0310 + port), saturating.
    pub fn count_lost_link(&mut self, port: u8) {
        self.count(0x0310 + usize::from(port.min(3)));
    }

    /// The 8-bit error counter at `at`: saturates at 0xFF as the ESC's do.
    fn count(&mut self, at: usize) {
        if let Some(b) = self.mem.get_mut(at) {
            *b = b.saturating_add(1);
        }
    }

    // ---------------------------------------------------------------- ECAT physical access

    /// An ECAT read of `out.len()` bytes at physical address `addr` (register or RAM).
    /// `or`: OR the content into `out` (BRD/BRW) instead of replacing it. Returns whether the
    /// access counts in the working counter.
    pub fn ecat_read(&mut self, addr: u16, out: &mut [u8], or: bool, hop: Hop) -> bool {
        let a = usize::from(addr);
        let b = a + out.len();
        let mut ok = false;
        if a < REG_SPACE {
            let end = b.min(REG_SPACE);
            let (reg_part, rest) = out.split_at_mut(end - a);
            let mut lo = a;
            while lo < end {
                let (hi, sm) = self.next_register_run(lo, end);
                let part = reg_part.get_mut(lo - a..hi - a).unwrap_or(&mut []);
                ok |= match sm {
                    Some(_) => self.ram_read(lo, part, or),
                    None => self.reg_read(lo, part, or, hop),
                };
                lo = hi;
            }
            if !rest.is_empty() {
                ok |= self.ram_read(REG_SPACE, rest, or);
            }
        } else {
            ok |= self.ram_read(a, out, or);
        }
        ok
    }

    /// An ECAT write of `data` at physical address `addr` (register or RAM). Returns whether
    /// the access counts in the working counter.
    pub fn ecat_write(&mut self, addr: u16, data: &[u8], hop: Hop, dev: &mut dyn Device) -> bool {
        let a = usize::from(addr);
        let b = a + data.len();
        let mut ok = false;
        if a < REG_SPACE {
            let end = b.min(REG_SPACE);
            let (reg_part, rest) = data.split_at(end - a);
            let mut lo = a;
            while lo < end {
                let (hi, sm) = self.next_register_run(lo, end);
                let part = reg_part.get(lo - a..hi - a).unwrap_or(&[]);
                ok |= match sm {
                    Some(_) => self.ram_write(lo, part, hop),
                    None => self.reg_write(lo, part, hop, dev),
                };
                lo = hi;
            }
            if !rest.is_empty() {
                ok |= self.ram_write(REG_SPACE, rest, hop);
            }
        } else {
            ok |= self.ram_write(a, data, hop);
        }
        ok
    }

    fn refresh_dynamic(&mut self, a: usize, b: usize, hop: Hop) {
        if !self.cfg.dc.supported() || !overlaps(a, b, 0x0910, 0x09A0) {
            return;
        }
        if overlaps(a, b, 0x0910, 0x0918) {
            let t = self.system_time(hop.forward_ns);
            self.put_u64(0x0910, t);
        }
        if overlaps(a, b, 0x0984, 0x0985) {
            // Nothing dynamic beyond what activation stored.
        }
        if self.dc.sync.active && overlaps(a, b, 0x0990, 0x09A0) {
            let next = self.dc.sync.next;
            self.put_u64(0x0990, next);
            let s1 = u64::from(self.get_u32(0x09A4));
            if self.byte(0x0981) & 0x04 != 0 {
                self.put_u64(0x0998, next.wrapping_add(s1));
            }
        }
    }

    fn reg_read(&mut self, a: usize, out: &mut [u8], or: bool, hop: Hop) -> bool {
        let b = a + out.len();
        self.refresh_dynamic(a, b, hop);
        let mut ok = false;
        let (Some(mem), Some(flags)) = (self.mem.get(a..b), self.map.flags.get(a..b)) else {
            return false;
        };
        for ((o, &m), &f) in out.iter_mut().zip(mem).zip(flags) {
            if f & IMPLEMENTED != 0 {
                ok = true;
                if or {
                    *o |= m;
                } else {
                    *o = m;
                }
            }
        }
        // The master polls the read mailbox's status: let the firmware post queued messages.
        if let Some(m) = self.active_mbx() {
            let st = Self::sm_base(m.sm_in) + 5;
            if overlaps(a, b, st, st + 1) {
                self.pending |= pending::MBX_POLL;
            }
        }
        // SYNC0/SYNC1 status bits clear on read.
        if self.cfg.dc.supported() && overlaps(a, b, 0x098E, 0x0990) {
            if overlaps(a, b, 0x098E, 0x098F) {
                self.put(0x098E, &[0]);
            }
            if overlaps(a, b, 0x098F, 0x0990) {
                self.put(0x098F, &[0]);
            }
        }
        ok
    }

    fn reg_write(&mut self, a: usize, data: &[u8], hop: Hop, dev: &mut dyn Device) -> bool {
        let b = a + data.len();
        if self.sii_busy > 0 && overlaps(a, b, 0x0502, 0x0510) {
            // The EEPROM interface takes no command, address or data while busy.
            return true;
        }
        let sm_hi = 0x0800 + 8 * usize::from(self.cfg.sm_count);
        let sm_touched = overlaps(a, b, 0x0800, sm_hi);
        // Old SM activate bytes, to see enable/disable and repeat edges.
        let mut old_act = [0u8; MAX_SM];
        if sm_touched {
            for (n, o) in old_act
                .iter_mut()
                .enumerate()
                .take(usize::from(self.cfg.sm_count))
            {
                *o = self.byte(0x0800 + 8 * n + 6);
            }
        }
        let old_sys = if overlaps(a, b, 0x0910, 0x0918) && self.cfg.dc.supported() {
            Some(self.system_time(hop.forward_ns))
        } else {
            None
        };
        let old_activation = self.byte(0x0981);

        let mut ok = false;
        for (i, &v) in data.iter().enumerate() {
            let at = a + i;
            let (Some(&mask), Some(&flags)) = (self.map.wmask.get(at), self.map.flags.get(at))
            else {
                continue;
            };
            if flags & IMPLEMENTED == 0 || (mask == 0 && flags & TRIGGER == 0) {
                continue;
            }
            ok = true;
            if mask == 0 {
                continue;
            }
            // SM start/length/control can only be changed while the SM is disabled.
            if (0x0800..sm_hi).contains(&at) && (at - 0x0800) % 8 < 5 {
                let act = self.byte(0x0800 + (at - 0x0800) / 8 * 8 + 6);
                if act & 0x01 != 0 {
                    continue;
                }
            }
            // The start time is writable only while the Sync Out Unit is not activated
            // (0x0981 bit 0; datasheet section II, 0x0990).
            if (0x0990..0x0998).contains(&at) && self.byte(0x0981) & 0x01 != 0 {
                continue;
            }
            if let Some(m) = self.mem.get_mut(at) {
                *m = (*m & !mask) | (v & mask);
            }
        }
        if !ok {
            return false;
        }

        if overlaps(a, b, 0x0010, 0x0014) || overlaps(a, b, 0x0103, 0x0104) {
            self.station_address_changed = true;
        }
        if overlaps(a, b, 0x0040, 0x0041) {
            self.ecat_reset_step(data.first().copied().unwrap_or(0), dev);
            return true;
        }
        if overlaps(a, b, 0x0300, 0x030C) {
            self.put(0x0300, &[0; 12]);
        }
        for r in [
            0x030C, 0x030D, 0x0310, 0x0311, 0x0312, 0x0313, 0x0442, 0x0443,
        ] {
            if overlaps(a, b, r, r + 1) {
                self.put(r, &[0]);
            }
        }
        if overlaps(a, b, 0x0503, 0x0504) {
            self.sii_command();
        }
        let fmmu_hi = 0x0600 + 16 * usize::from(self.cfg.fmmu_count);
        if overlaps(a, b, 0x0600, fmmu_hi) {
            self.rebuild_fmmus();
        }
        if sm_touched {
            self.sm_registers_written(&old_act, dev);
        }
        if self.cfg.dc.supported() && overlaps(a, b, 0x0900, 0x09B0) {
            self.dc_written(a, b, data, old_sys, old_activation, hop);
        }
        if overlaps(a, b, 0x0120, 0x0121) {
            self.al_control(hop, dev);
        }
        true
    }

    fn ecat_reset_step(&mut self, v: u8, dev: &mut dyn Device) {
        const SEQ: [u8; 3] = [b'R', b'E', b'S'];
        self.reset_step = match (self.reset_step, v) {
            (s, v) if SEQ.get(usize::from(s)) == Some(&v) => s + 1,
            (_, b'R') => 1,
            _ => 0,
        };
        if self.reset_step == 3 {
            let from = self.state;
            self.power_on();
            dev.mailbox_reset();
            if from != AlState::Init {
                dev.state_changed(from, AlState::Init, None);
            }
            self.reset_step = 0;
        }
        self.put(0x0040, &[self.reset_step]);
    }

    fn ram_read(&mut self, a: usize, out: &mut [u8], or: bool) -> bool {
        let b = (a + out.len()).min(self.mem.len());
        let mut ok = false;
        let mut lo = a;
        while lo < b {
            let (hi, sm) = self.next_run(lo, b);
            let allowed = match sm {
                None => true,
                Some(sm) => {
                    if !sm.usable || sm.ecat_writes {
                        false
                    } else if sm.mailbox {
                        self.sm_full(sm.idx)
                    } else {
                        true
                    }
                }
            };
            if allowed {
                if let (Some(src), Some(dst)) = (self.mem.get(lo..hi), out.get_mut(lo - a..hi - a))
                {
                    if or {
                        for (d, s) in dst.iter_mut().zip(src) {
                            *d |= *s;
                        }
                    } else {
                        dst.copy_from_slice(src);
                    }
                    ok = true;
                    if let Some(sm) = sm {
                        if hi == sm.end {
                            if sm.mailbox {
                                self.mailbox_read_done(sm.idx);
                            } else {
                                self.buffer_done(sm.idx);
                                self.pending |= pending::PD_ACCESS;
                            }
                        }
                    }
                }
            }
            lo = hi;
        }
        ok
    }

    fn ram_write(&mut self, a: usize, data: &[u8], hop: Hop) -> bool {
        let b = (a + data.len()).min(self.mem.len());
        let mut ok = false;
        let mut lo = a;
        while lo < b {
            let (hi, sm) = self.next_run(lo, b);
            let allowed = match sm {
                None => true,
                Some(sm) => {
                    if !sm.usable || !sm.ecat_writes {
                        false
                    } else if sm.mailbox {
                        !self.sm_full(sm.idx)
                    } else {
                        true
                    }
                }
            };
            if allowed {
                if let (Some(dst), Some(src)) = (self.mem.get_mut(lo..hi), data.get(lo - a..hi - a))
                {
                    dst.copy_from_slice(src);
                    ok = true;
                    if let Some(sm) = sm {
                        if hi == sm.end {
                            if sm.mailbox {
                                self.set_sm_full(sm.idx, true);
                                self.set_bits(Self::sm_base(sm.idx) + 5, 0x01, true);
                                self.pending |= pending::MBX_WRITTEN;
                            } else {
                                self.buffer_done(sm.idx);
                                if self.sm_out_pd.contains(sm.idx) {
                                    self.outputs_completed(sm, hop);
                                }
                                self.pending |= pending::PD_ACCESS;
                            }
                        }
                    }
                }
            }
            lo = hi;
        }
        ok
    }

    // ---------------------------------------------------------------- end of frame / time

    /// Whether there is work for [`end_of_frame`](Self::end_of_frame).
    pub fn has_pending(&self) -> bool {
        self.pending != 0
    }

    /// The PDI reacts to what the frame did: mailbox requests and repeats, SM changes, and
    /// (without DC sync) a process-data cycle. Returns whether
    /// [`next_deadline`](Self::next_deadline) may have moved earlier (SYNC0 activated, OP
    /// entered).
    pub fn end_of_frame(&mut self, hop: Hop, dev: &mut dyn Device) -> bool {
        let p = core::mem::take(&mut self.pending);
        if p & pending::SII_BUSY != 0 {
            self.sii_frame_end();
        }
        if p & pending::SM_CHANGED != 0 {
            self.check_sm_change(dev);
        }
        if p & pending::MBX_REPEAT != 0 {
            self.mailbox_repeat();
        }
        if p & pending::PD_ACCESS != 0
            && !self.dc.sync.active
            && matches!(self.state, AlState::SafeOp | AlState::Op)
        {
            let t = if self.cfg.dc.supported() {
                self.system_time(hop.forward_ns)
            } else {
                self.local_time(hop.forward_ns)
            };
            self.deliver_sync(SyncKind::Frame, t, 0, dev);
        }
        // Mailbox service below covers any message the application queued meanwhile.
        self.pending &= !pending::MBX_POLL;
        if self.mailbox.running {
            self.service_mailbox(dev);
        }
        let moved = (p | self.pending) & pending::DEADLINE != 0;
        self.pending &= !pending::DEADLINE;
        moved
    }

    /// Start recording [`TimingStats`] (allocates the histograms once; recording never
    /// allocates). Calling it again resets them.
    pub fn enable_timing_stats(&mut self) {
        match self.timing.as_deref_mut() {
            Some(t) => t.reset(),
            None => self.timing = Some(Box::new(TimingStats::new())),
        }
    }

    /// The timing statistics, if enabled.
    pub fn timing_stats(&self) -> Option<&TimingStats> {
        self.timing.as_deref()
    }
}
