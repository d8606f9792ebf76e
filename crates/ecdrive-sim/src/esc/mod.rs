//! One emulated EtherCAT slave controller (ESC): register memory with the real write masks and
//! side effects, SyncManagers (mailbox handshake with repeat, buffered process data), FMMUs with
//! bit granularity, the SII EEPROM interface, the AL state machine with the checks a slave makes,
//! the SM watchdog, and the DC unit.
//!
//! An [`Esc`] is the silicon; the firmware behind it is a [`Device`]. The [`Segment`]
//! (`super::segment`) routes datagrams to ESCs; tests may also drive an ESC directly through
//! [`Esc::ecat_read`], [`Esc::ecat_write`] and [`Esc::logical`].
//!
//! [`Segment`]: super::segment::Segment

mod dc;
mod regs;
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

#[derive(Debug, Clone, Copy, Default)]
struct Fmmu {
    log_start: u32,
    len: u16,
    start_bit: u8,
    stop_bit: u8,
    phys: u16,
    phys_bit: u8,
    read: bool,
    write: bool,
}

impl Fmmu {
    fn byte_aligned(&self) -> bool {
        self.start_bit == 0 && self.stop_bit == 7 && self.phys_bit == 0
    }
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
    sm_out_pd: Option<u8>,
    sm_in_pd: Option<u8>,
    sms: Vec<SmView>,
    fmmus: Vec<Fmmu>,
    mailbox: MailboxRt,
    pd: ProcessRt,
    dc: DcUnit,
    wd_deadline: Option<u64>,
    pending: u8,
    reset_step: u8,
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
            sm_out_pd: desc.sm_index(SmType::Outputs),
            sm_in_pd: desc.sm_index(SmType::Inputs),
            sms: Vec::with_capacity(MAX_SM),
            fmmus: Vec::with_capacity(MAX_FMMU),
            mailbox: MailboxRt::default(),
            pd: ProcessRt::default(),
            dc: DcUnit::new(cfg.clock_offset_ns, cfg.clock_drift_ppb),
            wd_deadline: None,
            pending: 0,
            reset_step: 0,
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

    /// The latched output image (SM2 content as last completed by the master).
    pub fn outputs(&self) -> &[u8] {
        &self.pd.outputs
    }

    /// The input image (SM3 buffer), if SM3 is enabled.
    pub fn inputs(&self) -> &[u8] {
        match self.pd_sm_range(self.sm_in_pd) {
            Some((s, e)) => self.mem.get(s..e).unwrap_or(&[]),
            None => &[],
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
        if let Some(b) = self.mem.get_mut(0x0300) {
            *b = b.saturating_add(1);
        }
    }

    // ---------------------------------------------------------------- SyncManager views

    fn rebuild_sms(&mut self) {
        self.sms.clear();
        let ram_end = self.mem.len();
        for n in 0..self.cfg.sm_count {
            let b = 0x0800 + 8 * usize::from(n);
            if self.byte(b + 6) & 0x01 == 0 {
                continue;
            }
            let start = usize::from(self.get_u16(b));
            let len = usize::from(self.get_u16(b + 2));
            if len == 0 {
                continue;
            }
            let ctl = self.byte(b + 4);
            self.sms.push(SmView {
                idx: n,
                start,
                end: (start + len).min(ram_end.max(start)),
                mailbox: ctl & 0x03 == 0x02,
                ecat_writes: (ctl >> 2) & 0x03 == 0x01,
                usable: self.byte(b + 7) & 0x01 == 0,
            });
        }
    }

    fn sm_base(n: u8) -> usize {
        0x0800 + 8 * usize::from(n)
    }

    fn sm_enabled(&self, n: u8) -> bool {
        self.byte(Self::sm_base(n) + 6) & 0x01 != 0
    }

    fn sm_full(&self, n: u8) -> bool {
        self.byte(Self::sm_base(n) + 5) & 0x08 != 0
    }

    fn set_sm_full(&mut self, n: u8, full: bool) {
        self.set_bits(Self::sm_base(n) + 5, 0x08, full);
    }

    /// (start, end) of an enabled process-data SM.
    fn pd_sm_range(&self, sm: Option<u8>) -> Option<(usize, usize)> {
        let n = sm?;
        if !self.sm_enabled(n) {
            return None;
        }
        let b = Self::sm_base(n);
        let start = usize::from(self.get_u16(b));
        let len = usize::from(self.get_u16(b + 2));
        let end = start.checked_add(len)?;
        if end > self.mem.len() || start < REG_SPACE {
            return None;
        }
        Some((start, end))
    }

    /// Set PDI-deactivate bits of the device's SMs according to the AL state: mailbox SMs are
    /// usable from PRE-OP (or BOOT), the input SM from SAFE-OP and the output SM in OP only.
    fn update_pdi_deactivation(&mut self) {
        let st = self.state;
        let mbx_on = self.mailbox.running;
        let set = |esc: &mut Self, n: u8, on: bool| {
            if n < esc.cfg.sm_count {
                esc.set_bits(Self::sm_base(n) + 7, 0x01, !on);
            }
        };
        let layout = if st == AlState::Bootstrap {
            self.boot_mbx
        } else {
            self.mbx
        };
        if let Some(m) = layout.or(self.mbx) {
            set(self, m.sm_out, mbx_on);
            set(self, m.sm_in, mbx_on);
        }
        if let Some(n) = self.sm_in_pd {
            set(self, n, matches!(st, AlState::SafeOp | AlState::Op));
        }
        if let Some(n) = self.sm_out_pd {
            set(self, n, st == AlState::Op);
        }
        self.rebuild_sms();
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
            ok |= self.reg_read(a, reg_part, or, hop);
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
            ok |= self.reg_write(a, reg_part, hop, dev);
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

    /// The run of RAM starting at `pos` (before `b`) that is covered by one SM, or by none:
    /// returns its end and the SM.
    fn next_run(&self, pos: usize, b: usize) -> (usize, Option<SmView>) {
        let mut next_start = b;
        for sm in &self.sms {
            if sm.start <= pos && pos < sm.end {
                return (sm.end.min(b), Some(*sm));
            }
            if sm.start > pos && sm.start < next_start {
                next_start = sm.start;
            }
        }
        (next_start, None)
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
                                if Some(sm.idx) == self.sm_out_pd {
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

    /// A buffered-mode buffer was completed (written or read including its last byte).
    fn buffer_done(&mut self, n: u8) {
        let st = Self::sm_base(n) + 5;
        let cur = (self.byte(st) >> 4) & 0x03;
        let next = if cur >= 2 { 0 } else { cur + 1 };
        if let Some(b) = self.mem.get_mut(st) {
            *b = (*b & !0x30) | (next << 4);
        }
    }

    fn outputs_completed(&mut self, sm: SmView, hop: Hop) {
        let len = sm.end - sm.start;
        if self.pd.outputs.len() != len {
            self.pd.outputs.resize(len, 0);
        }
        if let Some(src) = self.mem.get(sm.start..sm.end) {
            self.pd.outputs.copy_from_slice(src);
        }
        self.pd.outputs_received = self.pd.outputs_received.saturating_add(1);
        let t = if self.cfg.dc.supported() {
            self.system_time(hop.forward_ns)
        } else {
            self.local_time(hop.forward_ns)
        };
        self.pd.last_outputs_ns = Some(t);
        if self.state == AlState::Op
            && self.dc.sync.active
            && self.dc.sync.count > 0
            && let Some(stats) = self.timing.as_deref_mut()
        {
            // Pulses up to now were delivered before this frame: the latest one was a cycle
            // before the next.
            let cycle = i128::from(self.dc.sync.cycle.max(1));
            let last = i128::from(self.dc.sync.next) - cycle;
            let since = (i128::from(t) - last).rem_euclid(cycle);
            stats.record_arrival(since as u64);
        }
        // Re-trigger the SM watchdog.
        if self.byte(Self::sm_base(sm.idx) + 4) & 0x40 != 0 {
            self.wd_deadline = self.watchdog_ns().map(|w| hop.forward_ns.saturating_add(w));
            self.set_bits(0x0440, 0x01, true);
        }
    }

    /// The mailbox layout in use: the bootstrap mailbox in BOOT, the standard one otherwise.
    fn active_mbx(&self) -> Option<MbxLayout> {
        if self.state == AlState::Bootstrap {
            self.boot_mbx
        } else {
            self.mbx
        }
    }

    fn mailbox_read_done(&mut self, n: u8) {
        if let Some(m) = self.active_mbx() {
            if n == m.sm_in {
                let (s, e) = (
                    usize::from(m.in_start),
                    usize::from(m.in_start) + usize::from(m.in_len),
                );
                if let Some(src) = self.mem.get(s..e) {
                    if self.mailbox.backup.len() == src.len() {
                        self.mailbox.backup.copy_from_slice(src);
                        self.mailbox.backup_valid = true;
                    }
                }
            }
        }
        self.set_sm_full(n, false);
        self.set_bits(Self::sm_base(n) + 5, 0x02, true);
        self.pending |= pending::MBX_READ;
    }

    // ---------------------------------------------------------------- FMMUs / logical

    fn rebuild_fmmus(&mut self) {
        self.fmmus.clear();
        for n in 0..usize::from(self.cfg.fmmu_count) {
            let b = 0x0600 + 16 * n;
            if self.byte(b + 12) & 0x01 == 0 {
                continue;
            }
            let ty = self.byte(b + 11);
            let f = Fmmu {
                log_start: self.get_u32(b),
                len: self.get_u16(b + 4),
                start_bit: self.byte(b + 6) & 0x07,
                stop_bit: self.byte(b + 7) & 0x07,
                phys: self.get_u16(b + 8),
                phys_bit: self.byte(b + 10) & 0x07,
                read: ty & 0x01 != 0,
                write: ty & 0x02 != 0,
            };
            if f.len > 0 && (f.read || f.write) {
                self.fmmus.push(f);
            }
        }
    }

    /// A logical command (LRD/LWR/LRW) at logical address `laddr`: map through the active
    /// FMMUs. Writes use the data as it arrived, then reads overwrite it. Returns the working
    /// counter increment: +1 if a read FMMU access succeeded, +2 (LRW) or +1 (LWR) if a write
    /// succeeded.
    pub fn logical(
        &mut self,
        cmd: Command,
        laddr: u32,
        data: &mut [u8],
        hop: Hop,
        dev: &mut dyn Device,
    ) -> u16 {
        let (do_read, do_write) = match cmd {
            Command::Lrd => (true, false),
            Command::Lwr => (false, true),
            Command::Lrw => (true, true),
            _ => return 0,
        };
        if self.fmmus.is_empty() || data.is_empty() {
            return 0;
        }
        let d0 = u64::from(laddr) * 8;
        let d1 = d0 + data.len() as u64 * 8;
        let mut wrote = false;
        let mut read = false;
        if do_write {
            for i in 0..self.fmmus.len() {
                let Some(f) = self.fmmus.get(i).copied() else {
                    break;
                };
                if f.write {
                    wrote |= self.fmmu_access(f, d0, d1, data, true, hop, dev);
                }
            }
        }
        if do_read {
            for i in 0..self.fmmus.len() {
                let Some(f) = self.fmmus.get(i).copied() else {
                    break;
                };
                if f.read {
                    read |= self.fmmu_access(f, d0, d1, data, false, hop, dev);
                }
            }
        }
        match cmd {
            Command::Lrw => u16::from(read) + 2 * u16::from(wrote),
            _ => u16::from(read || wrote),
        }
    }

    /// One FMMU's part of a logical access; `[d0, d1)` is the datagram in logical bits.
    #[allow(clippy::too_many_arguments)]
    fn fmmu_access(
        &mut self,
        f: Fmmu,
        d0: u64,
        d1: u64,
        data: &mut [u8],
        write: bool,
        hop: Hop,
        dev: &mut dyn Device,
    ) -> bool {
        let l0 = u64::from(f.log_start) * 8 + u64::from(f.start_bit);
        let l1 = (u64::from(f.log_start) + u64::from(f.len) - 1) * 8 + u64::from(f.stop_bit) + 1;
        if l1 <= l0 {
            return false;
        }
        let lo = l0.max(d0);
        let hi = l1.min(d1);
        if lo >= hi {
            return false;
        }
        let p0 = u64::from(f.phys) * 8 + u64::from(f.phys_bit) + (lo - l0);
        if f.byte_aligned() {
            let (dl, dh) = (((lo - d0) / 8) as usize, ((hi - d0) / 8) as usize);
            let phys = p0 / 8;
            let Ok(phys) = u16::try_from(phys) else {
                return false;
            };
            let Some(slice) = data.get_mut(dl..dh) else {
                return false;
            };
            if phys as usize + slice.len() > 0x1_0000 {
                return false;
            }
            return if write {
                self.ecat_write(phys, slice, hop, dev)
            } else {
                self.ecat_read(phys, slice, false, hop)
            };
        }
        // Bit-granular path: operate on the physical bytes spanned.
        let nbits = hi - lo;
        let pb0 = p0 / 8;
        let pb1 = (p0 + nbits - 1) / 8;
        let Ok(phys) = u16::try_from(pb0) else {
            return false;
        };
        let span = (pb1 - pb0 + 1) as usize;
        if phys as usize + span > 0x1_0000 {
            return false;
        }
        let mut buf = core::mem::take(&mut self.scratch);
        buf.clear();
        buf.resize(span, 0);
        let ok = if write {
            self.peek(phys, &mut buf);
            for k in 0..nbits {
                let src_bit = lo - d0 + k;
                let dst_bit = p0 - pb0 * 8 + k;
                let v = data
                    .get((src_bit / 8) as usize)
                    .map(|b| (b >> (src_bit % 8)) & 1)
                    .unwrap_or(0);
                if let Some(d) = buf.get_mut((dst_bit / 8) as usize) {
                    let m = 1u8 << (dst_bit % 8);
                    *d = if v != 0 { *d | m } else { *d & !m };
                }
            }
            self.ecat_write(phys, &buf, hop, dev)
        } else {
            let ok = self.ecat_read(phys, &mut buf, false, hop);
            if ok {
                for k in 0..nbits {
                    let src_bit = p0 - pb0 * 8 + k;
                    let dst_bit = lo - d0 + k;
                    let v = buf
                        .get((src_bit / 8) as usize)
                        .map(|b| (b >> (src_bit % 8)) & 1)
                        .unwrap_or(0);
                    if let Some(d) = data.get_mut((dst_bit / 8) as usize) {
                        let m = 1u8 << (dst_bit % 8);
                        *d = if v != 0 { *d | m } else { *d & !m };
                    }
                }
            }
            ok
        };
        self.scratch = buf;
        ok
    }

    // ---------------------------------------------------------------- SM register side effects

    fn sm_registers_written(&mut self, old_act: &[u8; MAX_SM], dev: &mut dyn Device) {
        let mut changed = false;
        for n in 0..self.cfg.sm_count {
            let base = Self::sm_base(n);
            let old = old_act.get(usize::from(n)).copied().unwrap_or(0);
            let new = self.byte(base + 6);
            if old & 0x01 != new & 0x01 {
                changed = true;
                // Enabling or disabling resets the buffer state.
                let ctl = self.byte(base + 4);
                let status = if ctl & 0x03 == 0x02 { 0x00 } else { 0x30 };
                self.put(base + 5, &[status]);
                let is_mbx = self.mbx.is_some_and(|m| m.sm_out == n || m.sm_in == n);
                if is_mbx {
                    if n == self.mbx.map(|m| m.sm_in).unwrap_or(u8::MAX) {
                        self.mailbox.backup_valid = false;
                        // Repeat request/ack restart in sync.
                        self.set_bits(base + 7, 0x02, new & 0x02 != 0);
                    }
                    dev.mailbox_reset();
                }
                if Some(n) == self.sm_out_pd && new & 0x01 != 0 {
                    let len = usize::from(self.get_u16(base + 2));
                    self.pd.outputs.clear();
                    self.pd.outputs.resize(len, 0);
                }
            }
            if old & 0x02 != new & 0x02 && self.mbx.is_some_and(|m| m.sm_in == n) {
                self.pending |= pending::MBX_REPEAT;
            }
            if old != new {
                changed = true;
            }
        }
        self.rebuild_sms();
        if changed {
            self.pending |= pending::SM_CHANGED;
        }
    }

    // ---------------------------------------------------------------- SII interface

    fn sii_reload(&mut self) {
        let ok = self.sii.checksum_ok();
        self.set_bits(0x0503, 0x08, !ok);
        // b6: 8-byte reads; b7: 2-byte addressing for EEPROMs above 16 Kbit.
        let big = self.sii.bytes().len() > 2048;
        self.set_bits(0x0502, 0x40, true);
        self.set_bits(0x0502, 0x80, big);
        if ok {
            let w0 = self.sii.word(0);
            let w1 = self.sii.word(1);
            let w2 = self.sii.word(2);
            let w3 = self.sii.word(3);
            let w4 = self.sii.word(4);
            self.put_u16(0x0140, w0);
            self.put_u16(0x0150, w1);
            self.put_u16(0x0152, w3);
            if self.cfg.dc.supported() {
                self.put_u16(0x0982, w2);
            }
            self.put_u16(0x0012, w4);
            self.station_address_changed = true;
        }
        let dl = self.get_u16(0x0110);
        self.put_u16(0x0110, if ok { dl | 1 } else { dl & !1 });
    }

    fn sii_command(&mut self) {
        let ctl = self.get_u16(0x0502);
        let cmd = (ctl >> 8) & 0x07;
        // Command field reads back as 0 (done); busy never set: commands complete at once.
        // A new command clears the error bits.
        let mut status = self.byte(0x0503) & 0x08; // keep checksum error
        match cmd {
            0 => {}
            1 => {
                let addr = self.get_u32(0x0504);
                let mut data = [0u8; 8];
                for (i, chunk) in data.chunks_exact_mut(2).enumerate() {
                    let w = self.sii.word(addr.wrapping_add(i as u32));
                    chunk.copy_from_slice(&w.to_le_bytes());
                }
                self.put(0x0508, &data);
            }
            2 => {
                if ctl & 0x0001 == 0 {
                    status |= 0x40; // write enable error
                } else {
                    let addr = self.get_u32(0x0504) as usize;
                    let v = [self.byte(0x0508), self.byte(0x0509)];
                    match self.sii.bytes_mut().get_mut(addr * 2..addr * 2 + 2) {
                        Some(d) => d.copy_from_slice(&v),
                        None => status |= 0x20,
                    }
                }
            }
            4 => {
                self.sii_reload();
                status = self.byte(0x0503) & 0x08;
            }
            _ => status |= 0x20, // command error
        }
        self.put(0x0503, &[status]);
        // Write enable is self-clearing.
        self.set_bits(0x0502, 0x01, false);
    }

    // ---------------------------------------------------------------- DC

    fn dc_written(
        &mut self,
        a: usize,
        b: usize,
        data: &[u8],
        old_sys: Option<u64>,
        old_activation: u8,
        hop: Hop,
    ) {
        if overlaps(a, b, 0x0900, 0x0904) {
            self.latch_receive_times(hop);
        }
        if let Some(own) = old_sys {
            if overlaps(a, b, 0x0910, 0x0918) {
                // Merge the written bytes over the own time to get the received value; compare
                // in the width that was written.
                let mut v = own.to_le_bytes();
                let mut hi_byte = 0usize;
                for (i, &d) in data.iter().enumerate() {
                    let at = a + i;
                    if (0x0910..0x0918).contains(&at) {
                        if let Some(x) = v.get_mut(at - 0x0910) {
                            *x = d;
                        }
                        hi_byte = hi_byte.max(at - 0x0910 + 1);
                    }
                }
                let received = u64::from_le_bytes(v);
                let delay = u64::from(self.get_u32(0x0928));
                let own_cmp = own.wrapping_sub(delay);
                let e = if hi_byte <= 4 {
                    i64::from((own_cmp as u32).wrapping_sub(received as u32) as i32)
                } else {
                    own_cmp.wrapping_sub(received) as i64
                };
                let depth = self.byte(0x0934);
                let f = self.dc.loop_input(hop.forward_ns, e, depth);
                self.put_u32(0x092C, DcUnit::encode_difference(f));
                if self.state == AlState::Op
                    && let Some(t) = self.timing.as_deref_mut()
                {
                    t.record_dc_difference(f);
                }
            }
        }
        if overlaps(a, b, 0x0930, 0x0932) || overlaps(a, b, 0x0934, 0x0936) {
            self.dc.reset_loop();
            self.put_u32(0x092C, 0);
        }
        if overlaps(a, b, 0x0981, 0x0982) {
            let new = self.byte(0x0981);
            let was = old_activation & 0x03 == 0x03;
            let now_on = new & 0x03 == 0x03;
            if now_on && !was {
                self.start_sync(hop);
            } else if !now_on {
                self.dc.sync.active = false;
                self.put(0x0984, &[0]);
            }
        }
    }

    fn latch_receive_times(&mut self, hop: Hop) {
        let p0 = self.local_time(hop.forward_ns);
        self.put_u32(0x0900, p0 as u32);
        if let Some(r) = hop.return_ns {
            let p1 = self.local_time(r);
            self.put_u32(0x0904, p1 as u32);
        }
        self.put_u64(0x0918, p0);
    }

    fn start_sync(&mut self, hop: Hop) {
        let start = self.get_u64(0x0990);
        let cycle = self.get_u32(0x09A0);
        let now = self.system_time(hop.forward_ns);
        let mut status = 0x01; // SYNC0 activation pending until the first pulse
        let next = if start > now {
            start
        } else if cycle == 0 {
            status |= 0x04;
            now
        } else {
            // Start time already passed: start at the next whole cycle and flag it.
            status |= 0x04;
            let c = u64::from(cycle);
            let k = (now - start) / c + 1;
            start.saturating_add(k.saturating_mul(c))
        };
        self.dc.sync = SyncGen {
            active: true,
            next,
            cycle,
            count: 0,
        };
        self.pending |= pending::DEADLINE;
        self.put(0x0984, &[status]);
    }

    fn watchdog_ns(&self) -> Option<u64> {
        let t = u64::from(self.get_u16(0x0420));
        if t == 0 {
            return None;
        }
        let unit = (u64::from(self.get_u16(0x0400)) + 2) * 40;
        Some(t * unit)
    }

    // ---------------------------------------------------------------- AL state machine

    fn dc_status(&self) -> DcSyncStatus {
        let act = self.byte(0x0981);
        DcSyncStatus {
            supported: self.cfg.dc.supported(),
            sync0_active: self.dc.sync.active && act & 0x03 == 0x03,
            sync1_active: self.dc.sync.active && act & 0x04 != 0,
            sync0_cycle_ns: self.get_u32(0x09A0),
            sync1_cycle_ns: self.get_u32(0x09A4),
        }
    }

    fn set_al_status(&mut self, state: AlState, error: Option<AlStatusCode>) {
        self.state = state;
        let v = state as u16 | if error.is_some() { 0x10 } else { 0 };
        self.put_u16(0x0130, v);
        self.put_u16(0x0134, error.map(|c| c.0).unwrap_or(0));
    }

    fn mailbox_config_ok(&self, layout: &MbxLayout) -> bool {
        let check = |n: u8, start: u16, len: u16, dir: u8| {
            if n >= self.cfg.sm_count {
                return false;
            }
            let b = Self::sm_base(n);
            self.get_u16(b) == start
                && self.get_u16(b + 2) == len
                && self.byte(b + 4) & 0x0F == (0x02 | dir << 2)
                && self.byte(b + 6) & 0x01 != 0
        };
        check(layout.sm_out, layout.out_start, layout.out_len, 1)
            && check(layout.sm_in, layout.in_start, layout.in_len, 0)
    }

    /// Check a process-data SM against the expected size. `None` if fine.
    fn pd_config_ok(&self, sm: Option<u8>, expected: usize, ecat_writes: bool) -> bool {
        let Some(n) = sm else {
            return expected == 0;
        };
        if n >= self.cfg.sm_count {
            return expected == 0;
        }
        let b = Self::sm_base(n);
        let enabled = self.byte(b + 6) & 0x01 != 0;
        if expected == 0 {
            return !enabled || self.get_u16(b + 2) == 0;
        }
        let start = usize::from(self.get_u16(b));
        let len = usize::from(self.get_u16(b + 2));
        let ctl = self.byte(b + 4);
        let dir_ok = (ctl >> 2) & 0x03 == if ecat_writes { 1 } else { 0 };
        enabled
            && len == expected
            && ctl & 0x03 == 0x00
            && dir_ok
            && start >= REG_SPACE
            && start + len <= self.mem.len()
    }

    fn check_process_data(&self, dev: &dyn Device) -> Result<(), AlStatusCode> {
        let sizes = dev.process_data_sizes();
        if !self.pd_config_ok(self.sm_out_pd, sizes.outputs, true) {
            return Err(AlStatusCode::INVALID_OUTPUT_CONFIG);
        }
        if !self.pd_config_ok(self.sm_in_pd, sizes.inputs, false) {
            return Err(AlStatusCode::INVALID_INPUT_CONFIG);
        }
        Ok(())
    }

    fn start_mailbox(&mut self, layout: Option<MbxLayout>, dev: &mut dyn Device) {
        self.mailbox.running = true;
        self.mailbox.backup_valid = false;
        if let Some(m) = layout {
            // Buffers sized for this mailbox (allocates only when the size changes, at a state
            // transition).
            self.mailbox.request.resize(usize::from(m.out_len), 0);
            self.mailbox.reply.resize(usize::from(m.in_len), 0);
            self.mailbox.backup.resize(usize::from(m.in_len), 0);
            // The repeat toggle starts in sync with what the master has.
            let act = self.byte(Self::sm_base(m.sm_in) + 6);
            self.set_bits(Self::sm_base(m.sm_in) + 7, 0x02, act & 0x02 != 0);
        }
        dev.mailbox_reset();
    }

    fn stop_mailbox(&mut self, dev: &mut dyn Device) {
        if self.mailbox.running {
            dev.mailbox_reset();
        }
        self.mailbox.running = false;
        self.mailbox.backup_valid = false;
    }

    fn al_control(&mut self, hop: Hop, dev: &mut dyn Device) {
        let ctl = self.byte(0x0120);
        let ack = ctl & 0x10 != 0;
        let req_bits = ctl & 0x0F;
        let from = self.state;
        let has_error = self.al_error();
        // An error must be acknowledged (or INIT requested) before anything else happens.
        if has_error && !ack && req_bits != AlState::Init as u8 {
            return;
        }
        let Some(to) = AlState::from_bits(req_bits) else {
            let state = if from == AlState::Op {
                self.leave_op();
                AlState::SafeOp
            } else {
                from
            };
            self.finish_transition(from, state, Some(AlStatusCode::UNKNOWN_STATE), dev);
            return;
        };
        use AlState::*;
        let result: Result<AlState, (AlState, AlStatusCode)> = match (from, to) {
            (a, b) if a == b => Ok(a),
            (Init, PreOp) => match self.mbx {
                Some(m) if !self.mailbox_config_ok(&m) => {
                    Err((Init, AlStatusCode::INVALID_MAILBOX_CONFIG))
                }
                _ => self
                    .ask(dev, from, to)
                    .map(|_| PreOp)
                    .map_err(|c| (Init, c)),
            },
            (Init, Bootstrap) => match self.boot_mbx {
                None => Err((Init, AlStatusCode::BOOTSTRAP_NOT_SUPPORTED)),
                Some(m) if !self.mailbox_config_ok(&m) => {
                    Err((Init, AlStatusCode::INVALID_MAILBOX_CONFIG_BOOT))
                }
                Some(_) => self
                    .ask(dev, from, to)
                    .map(|_| Bootstrap)
                    .map_err(|c| (Init, c)),
            },
            (PreOp, SafeOp) => match self.check_process_data(dev) {
                Err(c) => Err((PreOp, c)),
                Ok(()) => self
                    .ask(dev, from, to)
                    .map(|_| SafeOp)
                    .map_err(|c| (PreOp, c)),
            },
            (SafeOp, Op) => self.ask(dev, from, to).map(|_| Op).map_err(|c| (SafeOp, c)),
            (_, Init) => Ok(Init),
            (Op, SafeOp) | (Op, PreOp) | (SafeOp, PreOp) => Ok(to),
            (Op, Bootstrap) => Err((SafeOp, AlStatusCode::INVALID_STATE_CHANGE)),
            (Bootstrap, _) => Err((Bootstrap, AlStatusCode::INVALID_STATE_CHANGE)),
            (s, _) => Err((s, AlStatusCode::INVALID_STATE_CHANGE)),
        };
        let (new_state, error) = match result {
            Ok(s) => (s, None),
            Err((s, c)) => (s, Some(c)),
        };
        // Leave states as needed.
        if from == Op && new_state != Op {
            self.leave_op();
        }
        if matches!(new_state, Init | Bootstrap) && from != new_state {
            self.stop_mailbox(dev);
        }
        if matches!(from, Init | Bootstrap)
            && matches!(new_state, PreOp | Bootstrap)
            && from != new_state
        {
            let layout = if new_state == Bootstrap {
                self.boot_mbx
            } else {
                self.mbx
            };
            self.start_mailbox(layout, dev);
        }
        if new_state == Op && from != Op {
            self.wd_deadline = self.watchdog_ns().map(|w| hop.forward_ns.saturating_add(w));
            self.set_bits(0x0440, 0x01, true);
            self.pending |= pending::DEADLINE;
        }
        self.finish_transition(from, new_state, error, dev);
    }

    fn ask(&self, dev: &mut dyn Device, from: AlState, to: AlState) -> Result<(), AlStatusCode> {
        dev.request_state(&StateRequest {
            from,
            to,
            dc: self.dc_status(),
        })
    }

    fn leave_op(&mut self) {
        self.wd_deadline = None;
    }

    fn finish_transition(
        &mut self,
        from: AlState,
        to: AlState,
        error: Option<AlStatusCode>,
        dev: &mut dyn Device,
    ) {
        self.set_al_status(to, error);
        self.update_pdi_deactivation();
        if from != to || error.is_some() {
            dev.state_changed(from, to, error);
        }
    }

    /// Drop to a lower state with an error on the slave's own initiative (watchdog, sync
    /// error, SM change).
    fn local_error(&mut self, to: AlState, code: AlStatusCode, dev: &mut dyn Device) {
        let from = self.state;
        if from == AlState::Op {
            self.leave_op();
        }
        if matches!(to, AlState::Init) {
            self.stop_mailbox(dev);
        }
        self.finish_transition(from, to, Some(code), dev);
    }

    /// A local restart of the application controller (an injected
    /// [`SlaveFault::ResetToInit`](crate::faults::SlaveFault::ResetToInit)): INIT with the
    /// error bit and AL status code 0x0060 "Slave restarted locally"; the mailbox stops, the
    /// device sees the change as a local error. ESC registers (station address, SyncManager
    /// and FMMU configuration) are kept.
    pub fn local_reset(&mut self, dev: &mut dyn Device) {
        self.local_error(AlState::Init, AlStatusCode::RESTARTED_LOCALLY, dev);
    }

    /// Change the local clock's drift against the host clock from host time `host_ns` on (an
    /// injected [`SlaveFault::ClockDrift`](crate::faults::SlaveFault::ClockDrift)). The
    /// local time does not jump; a later ESC reset keeps the new drift (it is the oscillator's).
    pub fn set_clock_drift(&mut self, host_ns: u64, drift_ppb: i64) {
        self.dc.set_drift(host_ns, drift_ppb);
        self.cfg.clock_drift_ppb = drift_ppb;
        self.cfg.clock_offset_ns = self.dc.offset_ns;
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

    fn check_sm_change(&mut self, dev: &mut dyn Device) {
        let st = self.state;
        if matches!(st, AlState::PreOp | AlState::SafeOp | AlState::Op) {
            if let Some(m) = self.mbx {
                if !self.mailbox_config_ok(&m) {
                    self.local_error(AlState::Init, AlStatusCode::INVALID_MAILBOX_CONFIG, dev);
                    return;
                }
            }
        }
        if matches!(st, AlState::SafeOp | AlState::Op) {
            if let Err(c) = self.check_process_data(dev) {
                self.local_error(AlState::PreOp, c, dev);
            }
        }
    }

    fn mailbox_repeat(&mut self) {
        let Some(m) = self.active_mbx() else { return };
        let base = Self::sm_base(m.sm_in);
        let req = self.byte(base + 6) & 0x02;
        if self.mailbox.running && !self.sm_full(m.sm_in) && self.mailbox.backup_valid {
            let s = usize::from(m.in_start);
            let backup = core::mem::take(&mut self.mailbox.backup);
            self.put(s, &backup);
            self.mailbox.backup = backup;
            self.set_sm_full(m.sm_in, true);
        }
        self.set_bits(base + 7, 0x02, req != 0);
    }

    fn service_mailbox(&mut self, dev: &mut dyn Device) {
        let Some(m) = self.active_mbx() else { return };
        let state = self.state;
        if self.sm_full(m.sm_in) || !self.sm_enabled(m.sm_in) {
            return;
        }
        let out_start = usize::from(m.in_start);
        let out_len = usize::from(m.in_len);
        if self.sm_full(m.sm_out) {
            let s = usize::from(m.out_start);
            let e = s + usize::from(m.out_len);
            let mut req = core::mem::take(&mut self.mailbox.request);
            let mut rep = core::mem::take(&mut self.mailbox.reply);
            if let Some(src) = self.mem.get(s..e) {
                if req.len() == src.len() {
                    req.copy_from_slice(src);
                }
            }
            self.set_sm_full(m.sm_out, false);
            self.set_bits(Self::sm_base(m.sm_out) + 5, 0x01, false);
            rep.fill(0);
            let n = dev.mailbox_request(state, &req, &mut rep);
            if let Some(n) = n {
                self.post_mailbox(out_start, out_len, &rep, n, m.sm_in);
            }
            self.mailbox.request = req;
            self.mailbox.reply = rep;
            return;
        }
        let mut rep = core::mem::take(&mut self.mailbox.reply);
        rep.fill(0);
        if let Some(n) = dev.mailbox_poll(&mut rep) {
            self.post_mailbox(out_start, out_len, &rep, n, m.sm_in);
        }
        self.mailbox.reply = rep;
    }

    fn post_mailbox(&mut self, start: usize, len: usize, rep: &[u8], n: usize, sm: u8) {
        if n == 0 || n > len {
            return;
        }
        if let Some(dst) = self.mem.get_mut(start..start + len) {
            dst.fill(0);
            if let (Some(d), Some(s)) = (dst.get_mut(..n), rep.get(..n)) {
                d.copy_from_slice(s);
            }
        }
        self.set_sm_full(sm, true);
        self.set_bits(Self::sm_base(sm) + 5, 0x02, false);
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

    /// Host time at which [`run_due`](Self::run_due) has something to do (next SYNC0 pulse or
    /// watchdog expiry), conservatively early.
    pub fn next_deadline(&self, host_now: u64) -> Option<u64> {
        let mut d = self.wd_deadline;
        if self.dc.sync.active {
            let sys_now = self.system_time(host_now);
            let ahead = self.dc.sync.next.saturating_sub(sys_now);
            // System time may run up to 0.2 % faster than the host clock (drift + loop); aim
            // early by that much plus a microsecond.
            let margin = ahead / 500 + 1_000;
            let t = host_now.saturating_add(ahead.saturating_sub(margin));
            d = Some(d.map_or(t, |x| x.min(t)));
        }
        d
    }

    /// Deliver every SYNC0 pulse that has passed by host time `host_ns`, in order, and apply
    /// an expired SM watchdog.
    pub fn run_due(&mut self, host_ns: u64, dev: &mut dyn Device) {
        if self.dc.sync.active {
            let now = self.system_time(host_ns);
            let mut guard = 0u32;
            while self.dc.sync.active && self.dc.sync.next <= now {
                let t = self.dc.sync.next;
                let cycle = self.dc.sync.cycle;
                self.put(0x098E, &[0x01]);
                self.set_bits(0x0984, 0x01, false);
                let count = self.dc.sync.count;
                self.deliver_sync(SyncKind::Sync0, t, cycle, dev);
                self.dc.sync.count = count + 1;
                if cycle == 0 {
                    self.dc.sync.active = false;
                } else {
                    self.dc.sync.next = t.saturating_add(u64::from(cycle));
                }
                guard += 1;
                if guard >= 10_000_000 {
                    // More than ten million missed pulses (hours of a fast cycle): skip
                    // ahead instead of spinning.
                    let c = u64::from(cycle.max(1));
                    let k = (now - self.dc.sync.next) / c + 1;
                    self.dc.sync.next = self.dc.sync.next.saturating_add(k * c);
                    self.dc.sync.count = self.dc.sync.count.saturating_add(k);
                    break;
                }
            }
        }
        if let Some(d) = self.wd_deadline {
            if host_ns >= d {
                self.wd_deadline = None;
                self.set_bits(0x0440, 0x01, false);
                if let Some(c) = self.mem.get_mut(0x0442) {
                    *c = c.saturating_add(1);
                }
                if self.state == AlState::Op {
                    self.local_error(AlState::SafeOp, AlStatusCode::SM_WATCHDOG, dev);
                }
            }
        }
    }

    fn deliver_sync(&mut self, kind: SyncKind, t: u64, cycle_time: u32, dev: &mut dyn Device) {
        let cycle = match kind {
            SyncKind::Sync0 => self.dc.sync.count,
            SyncKind::Frame => {
                let c = self.pd.frame_cycles;
                self.pd.frame_cycles += 1;
                c
            }
        };
        if kind == SyncKind::Sync0
            && self.state == AlState::Op
            && let Some(stats) = self.timing.as_deref_mut()
        {
            stats.sync0_pulses += 1;
            if self.pd.outputs_received == 0 {
                stats.sync0_without_outputs += 1;
            }
        }
        let quirks = dev.quirks();
        let ev = SyncEvent {
            kind,
            time_ns: t,
            cycle,
            cycle_time_ns: cycle_time,
            state: self.state,
            outputs_received: core::mem::take(&mut self.pd.outputs_received),
            last_outputs_ns: self.pd.last_outputs_ns,
            outputs_enabled: self.state == AlState::Op
                || (self.state == AlState::SafeOp && quirks.has(Quirk::OutputsInSafeOp)),
        };
        let range = self.pd_sm_range(self.sm_in_pd);
        let outputs = core::mem::take(&mut self.pd.outputs);
        let r = if self.state != AlState::Op && quirks.has(Quirk::StaleInputsUntilOp) {
            // The device runs, but its inputs do not reach the image before OP.
            let mut scratch = core::mem::take(&mut self.pd.scratch);
            let len = range.map_or(0, |(s, e)| e - s);
            if scratch.len() < len {
                // Sized once, at the first cycle below OP.
                scratch.resize(len, 0);
            }
            let r = dev.sync(&ev, &outputs, scratch.get_mut(..len).unwrap_or(&mut []));
            self.pd.scratch = scratch;
            r
        } else {
            let inputs: &mut [u8] = match range {
                Some((s, e)) => self.mem.get_mut(s..e).unwrap_or(&mut []),
                None => &mut [],
            };
            dev.sync(&ev, &outputs, inputs)
        };
        self.pd.outputs = outputs;
        if self.mailbox.running {
            // The application may have queued a mailbox message.
            self.pending |= pending::MBX_POLL;
        }
        if let Err(code) = r {
            if self.state == AlState::Op {
                self.local_error(AlState::SafeOp, code, dev);
            }
        }
    }
}
