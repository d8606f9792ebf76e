//! A configured CANopen drive on the master side: its process images, the fields resolved from
//! its PDO plan, and the [`Axis`] engine that runs it — the same engine as the EtherCAT drives.
//!
//! Once per cycle the master copies each received TPDO into the input image; the application
//! (or a profile-mode helper of [`crate::cia402`]) reads [`CanDrive::feedback`] and gives
//! requests and set-points to [`CanDrive::axis_mut`]; [`CanDrive::step`] runs the axis and writes
//! the outputs into the output image, which the master sends as RPDOs before the next SYNC.
//! Reading and writing the images allocates nothing.

use super::pdo_plan::PdoPlan;
use super::profile::CanDriveProfile;
use crate::cia402::{Axis, Feedback, Output, StatusWord};
use crate::od::{Dictionary, ObjectAddress};
use crate::pdo::{AxisBinding, Direction, FieldError, Layout};

/// Bytes of an image: four PDOs of eight bytes.
pub const IMAGE_BYTES: usize = 64;

/// One PDO's place in an image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PdoSlot {
    /// PDO number 1–4.
    pub number: u8,
    /// COB-ID.
    pub cob: u16,
    /// Byte offset in the image.
    pub offset: usize,
    /// Length in bytes.
    pub len: usize,
}

/// A drive the master runs. See the [module documentation](self).
#[derive(Debug, Clone)]
pub struct CanDrive {
    node: u8,
    profile: &'static CanDriveProfile,
    axis: Axis,
    plan: PdoPlan,
    rx: [u8; IMAGE_BYTES],
    tx: [u8; IMAGE_BYTES],
    rpdos: Vec<PdoSlot>,
    tpdos: Vec<PdoSlot>,
    tpdo_seen_us: [Option<u64>; 4],
    binding: AxisBinding,
    layout: Layout,
    last_output: Option<Output>,
    rpdo_sent_us: Option<u64>,
    /// Outputs carried by SDO ([`PdoPlan::sdo_out`]): object, byte range in the output
    /// image, and the bytes last written (`None`: not yet).
    sdo_out: Vec<(ObjectAddress, core::ops::Range<usize>, Option<[u8; 4]>)>,
    /// Inputs carried by SDO ([`PdoPlan::sdo_in`]): object and byte range in the input image.
    sdo_in: Vec<(ObjectAddress, core::ops::Range<usize>)>,
    /// Whether the inputs carried by SDO have been read once.
    sdo_in_seen: bool,
}

impl CanDrive {
    /// A drive on `node` with the (validated) `plan` and an `axis`; an error names a mapped
    /// CiA 402 object that cannot be read as its type.
    pub fn new(
        node: u8,
        profile: &'static CanDriveProfile,
        plan: PdoPlan,
        axis: Axis,
    ) -> Result<Self, FieldError> {
        let mapping = plan.image_mapping();
        let layout = Layout::new(&mapping);
        let bytes_of = |dir: Direction, e: &crate::pdo::PdoEntry| {
            layout.find(dir, e.address()).map(|m| {
                let at = m.byte_offset();
                (e.address(), at..at + usize::from(m.bits()).div_ceil(8))
            })
        };
        let sdo_out: Vec<_> = plan
            .sdo_out
            .iter()
            .filter_map(|e| bytes_of(Direction::Rx, e))
            .map(|(a, r)| (a, r, None))
            .collect();
        let sdo_in: Vec<_> = plan
            .sdo_in
            .iter()
            .filter_map(|e| bytes_of(Direction::Tx, e))
            .collect();
        let binding = AxisBinding::resolve(&layout, &Dictionary::new(profile.dictionary))?;
        let slots = |dir: Direction| {
            let mut v: Vec<&super::pdo_plan::CanPdo> = plan.pdos(dir).iter().collect();
            v.sort_by_key(|p| p.number);
            let mut offset = 0usize;
            v.into_iter()
                .map(|p| {
                    let s = PdoSlot {
                        number: p.number,
                        cob: p.cob_for(dir, node),
                        offset,
                        len: p.bytes(),
                    };
                    offset += p.bytes();
                    s
                })
                .collect::<Vec<_>>()
        };
        let rpdos = slots(Direction::Rx);
        let tpdos = slots(Direction::Tx);
        Ok(Self {
            node,
            profile,
            axis,
            plan,
            rx: [0; IMAGE_BYTES],
            tx: [0; IMAGE_BYTES],
            rpdos,
            tpdos,
            tpdo_seen_us: [None; 4],
            binding,
            layout,
            last_output: None,
            rpdo_sent_us: None,
            sdo_out,
            sdo_in,
            sdo_in_seen: false,
        })
    }

    /// The next output carried by SDO whose value changed since it was last written (slot,
    /// object, bytes), in the plan's order — the controlword last, so a new target is in
    /// place before the edge that starts it. Allocation-free.
    pub fn next_sdo_output(&self) -> Option<(usize, ObjectAddress, [u8; 4], usize)> {
        self.sdo_out
            .iter()
            .enumerate()
            .find_map(|(k, (addr, range, sent))| {
                let now = self.rx.get(range.clone())?;
                let mut b = [0u8; 4];
                b.get_mut(..now.len())?.copy_from_slice(now);
                (*sent != Some(b)).then_some((k, *addr, b, now.len()))
            })
    }

    /// Record that SDO output slot `k` was written with `bytes`.
    pub fn sdo_output_written(&mut self, k: usize, bytes: [u8; 4]) {
        if let Some(s) = self.sdo_out.get_mut(k) {
            s.2 = Some(bytes);
        }
    }

    /// The inputs carried by SDO (object, byte range in the input image).
    pub fn sdo_inputs(&self) -> &[(ObjectAddress, core::ops::Range<usize>)] {
        &self.sdo_in
    }

    /// Store an input read by SDO (slot `k`).
    pub(crate) fn store_sdo_input(&mut self, k: usize, data: &[u8]) {
        let Some((_, range)) = self.sdo_in.get(k) else {
            return;
        };
        let n = range.len().min(data.len());
        if let (Some(dst), Some(src)) =
            (self.tx.get_mut(range.start..range.start + n), data.get(..n))
        {
            dst.copy_from_slice(src);
        }
        self.sdo_in_seen = true;
    }

    /// The node-ID.
    pub const fn node(&self) -> u8 {
        self.node
    }

    /// The profile.
    pub const fn profile(&self) -> &'static CanDriveProfile {
        self.profile
    }

    /// The PDO plan installed on the drive.
    pub const fn pdo_plan(&self) -> &PdoPlan {
        &self.plan
    }

    /// The axis engine.
    pub const fn axis(&self) -> &Axis {
        &self.axis
    }

    /// The axis engine, for requests and set-points.
    pub fn axis_mut(&mut self) -> &mut Axis {
        &mut self.axis
    }

    /// The RPDOs and where they sit in the output image.
    pub fn rpdos(&self) -> &[PdoSlot] {
        &self.rpdos
    }

    /// The TPDOs and where they sit in the input image.
    pub fn tpdos(&self) -> &[PdoSlot] {
        &self.tpdos
    }

    /// The output image (RPDO data).
    pub fn rx_image(&self) -> &[u8] {
        &self.rx
    }

    /// The input image (TPDO data).
    pub fn tx_image(&self) -> &[u8] {
        &self.tx
    }

    /// Whether every TPDO has been received at least once (and the inputs carried by SDO
    /// read).
    pub fn has_feedback(&self) -> bool {
        (self.sdo_in.is_empty() || self.sdo_in_seen)
            && (0..self.tpdos.len()).all(|i| self.tpdo_seen_us.get(i).is_some_and(Option::is_some))
    }

    /// When TPDO slot `i` last arrived.
    pub fn tpdo_seen_us(&self, i: usize) -> Option<u64> {
        self.tpdo_seen_us.get(i).copied().flatten()
    }

    /// Copy a received TPDO (slot `i`) into the input image. Short frames fill what they carry.
    pub(crate) fn store_tpdo(&mut self, i: usize, data: &[u8], now_us: u64) {
        let Some(s) = self.tpdos.get(i).copied() else {
            return;
        };
        let n = s.len.min(data.len());
        if let (Some(dst), Some(src)) = (self.tx.get_mut(s.offset..s.offset + n), data.get(..n)) {
            dst.copy_from_slice(src);
        }
        if let Some(t) = self.tpdo_seen_us.get_mut(i) {
            *t = Some(now_us);
        }
    }

    /// The bytes of RPDO slot `i` to send.
    pub(crate) fn rpdo_bytes(&self, i: usize) -> Option<(u16, &[u8])> {
        let s = self.rpdos.get(i)?;
        Some((s.cob, self.rx.get(s.offset..s.offset + s.len)?))
    }

    /// Where the CiA 402 objects sit in the images (the binding the EtherCAT master uses too).
    pub const fn binding(&self) -> &AxisBinding {
        &self.binding
    }

    /// The statusword from the input image (0 before the first TPDO).
    pub fn statusword(&self) -> StatusWord {
        self.binding.statusword(&self.tx)
    }

    /// The feedback for [`Axis::step`] from the input image.
    pub fn feedback(&self) -> Feedback {
        self.binding.feedback(&self.tx)
    }

    /// Run the axis on this cycle's feedback and write its outputs into the output image (the
    /// target position also into 60C1h:01 when the ip data record is mapped). Allocation-free.
    pub fn step(&mut self) -> Output {
        let out = self.axis.step(&self.feedback());
        self.binding.write(&out, &mut self.rx);
        self.last_output = Some(out);
        out
    }

    /// Write outputs computed elsewhere (the motion runtime's step,
    /// [`crate::motion::MotionSession`]) into the output image, as [`CanDrive::step`] writes
    /// its own. Allocation-free.
    pub fn write_output(&mut self, out: &Output) {
        self.binding.write(out, &mut self.rx);
        self.last_output = Some(*out);
    }

    /// The images' layout: the RPDOs one after another in the output image, the TPDOs in
    /// the input image, in PDO-number order.
    pub const fn layout(&self) -> &Layout {
        &self.layout
    }

    /// Write `raw` into `field` of the output image (an application's write to a mapped
    /// output, [`crate::motion::MotionSession::cycle_app`]); sent with the next RPDOs.
    pub fn write_raw(&mut self, field: crate::pdo::Field, raw: u64) {
        let _ = field.write_raw(&mut self.rx, raw);
    }

    /// When the master last sent this drive's RPDOs (the transport's clock).
    pub const fn rpdo_sent_us(&self) -> Option<u64> {
        self.rpdo_sent_us
    }

    pub(crate) fn set_rpdo_sent_us(&mut self, t: u64) {
        self.rpdo_sent_us = Some(t);
    }

    /// The outputs of the last [`CanDrive::step`].
    pub const fn last_output(&self) -> Option<Output> {
        self.last_output
    }
}
