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
use crate::cia402::{Axis, ErrorCode, Feedback, OperationMode, Output, StatusWord};
use crate::od::{Dictionary, ObjectAddress};
use crate::pdo::{Direction, Field, Layout};

/// Bytes of an image: four PDOs of eight bytes.
pub const IMAGE_BYTES: usize = 32;

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

#[derive(Debug, Clone, Copy, Default)]
struct Fields {
    controlword: Option<Field>,
    mode: Option<Field>,
    target_position: Option<Field>,
    target_velocity: Option<Field>,
    target_torque: Option<Field>,
    ip_position: Option<Field>,
    statusword: Option<Field>,
    mode_display: Option<Field>,
    position: Option<Field>,
    velocity: Option<Field>,
    torque: Option<Field>,
    error_code: Option<Field>,
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
    fields: Fields,
    last_output: Option<Output>,
}

impl CanDrive {
    /// A drive on `node` with the (validated) `plan` and an `axis`.
    pub fn new(node: u8, profile: &'static CanDriveProfile, plan: PdoPlan, axis: Axis) -> Self {
        let mapping = plan.mapping();
        let layout = Layout::new(&mapping);
        let dict = Dictionary::new(profile.dictionary);
        let field = |dir, i: u16, s: u8| layout.resolve(dir, ObjectAddress::new(i, s), &dict).ok();
        let fields = Fields {
            controlword: field(Direction::Rx, 0x6040, 0),
            mode: field(Direction::Rx, 0x6060, 0),
            target_position: field(Direction::Rx, 0x607A, 0),
            target_velocity: field(Direction::Rx, 0x60FF, 0),
            target_torque: field(Direction::Rx, 0x6071, 0),
            ip_position: field(Direction::Rx, 0x60C1, 1),
            statusword: field(Direction::Tx, 0x6041, 0),
            mode_display: field(Direction::Tx, 0x6061, 0),
            position: field(Direction::Tx, 0x6064, 0),
            velocity: field(Direction::Tx, 0x606C, 0),
            torque: field(Direction::Tx, 0x6077, 0),
            error_code: field(Direction::Tx, 0x603F, 0),
        };
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
        Self {
            node,
            profile,
            axis,
            plan,
            rx: [0; IMAGE_BYTES],
            tx: [0; IMAGE_BYTES],
            rpdos,
            tpdos,
            tpdo_seen_us: [None; 4],
            fields,
            last_output: None,
        }
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
    pub const fn plan(&self) -> &PdoPlan {
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

    /// Whether every TPDO has been received at least once.
    pub fn has_feedback(&self) -> bool {
        (0..self.tpdos.len()).all(|i| self.tpdo_seen_us.get(i).is_some_and(Option::is_some))
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

    fn read_i64(&self, f: Option<Field>) -> Option<i64> {
        f.and_then(|f| f.read_int(&self.tx).ok())
            .and_then(|v| i64::try_from(v).ok())
    }

    /// The statusword from the input image (0 before the first TPDO).
    pub fn statusword(&self) -> StatusWord {
        StatusWord::from_raw(self.read_i64(self.fields.statusword).unwrap_or(0) as u16)
    }

    /// The feedback for [`Axis::step`] from the input image.
    pub fn feedback(&self) -> Feedback {
        let mut fb = Feedback::new(self.statusword());
        fb.mode_display = self
            .read_i64(self.fields.mode_display)
            .map(|v| OperationMode::from_i8(v as i8));
        fb.position = self.read_i64(self.fields.position).map(|v| v as i32);
        fb.velocity = self.read_i64(self.fields.velocity).map(|v| v as i32);
        fb.torque = self.read_i64(self.fields.torque).map(|v| v as i16);
        fb.error_code = self
            .read_i64(self.fields.error_code)
            .map(|v| ErrorCode(v as u16));
        fb
    }

    /// Run the axis on this cycle's feedback and write its outputs into the output image (the
    /// target position also into 60C1h:01 when the ip data record is mapped). Allocation-free.
    pub fn step(&mut self) -> Output {
        let fb = self.feedback();
        let out = self.axis.step(&fb);
        let f = self.fields;
        let w = |img: &mut [u8; IMAGE_BYTES], field: Option<Field>, v: i128| {
            if let Some(field) = field {
                let _ = field.write_int(img, v);
            }
        };
        w(
            &mut self.rx,
            f.controlword,
            i128::from(out.controlword.raw()),
        );
        w(&mut self.rx, f.mode, i128::from(out.mode.as_i8()));
        w(
            &mut self.rx,
            f.target_position,
            i128::from(out.target_position),
        );
        w(
            &mut self.rx,
            f.target_velocity,
            i128::from(out.target_velocity),
        );
        w(&mut self.rx, f.target_torque, i128::from(out.target_torque));
        w(&mut self.rx, f.ip_position, i128::from(out.target_position));
        self.last_output = Some(out);
        out
    }

    /// The outputs of the last [`CanDrive::step`].
    pub const fn last_output(&self) -> Option<Output> {
        self.last_output
    }
}
