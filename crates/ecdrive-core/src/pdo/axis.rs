//! One axis in a process image: where its CiA 402 objects sit, read into a [`Feedback`] and
//! written from an [`Output`] every cycle. EtherCAT and CANopen use this one binding: the
//! EtherCAT master over the drive's slice of the LRW image, the CANopen master over the images
//! its TPDOs fill and its RPDOs send.
//!
//! Resolved once at start-up from the [`Layout`] and the drive's dictionary (or, for an object
//! the dictionary lacks, its CiA 402 type); reading and writing allocate nothing and never
//! panic (a field outside the buffer reads as absent and is not written).

use super::{Direction, Field, FieldError, Layout};
use crate::cia402::{ErrorCode, Feedback, OperationMode, Output, StatusWord};
use crate::od::{DataType, Dictionary, ObjectAddress};

/// Where one axis's CiA 402 objects sit in its output (RxPDO) and input (TxPDO) images; `None`
/// for an object that is not mapped.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AxisBinding {
    /// 0x6040 Controlword (output).
    pub controlword: Option<Field>,
    /// 0x6060 Modes of operation (output).
    pub mode: Option<Field>,
    /// 0x607A Target position (output).
    pub target_position: Option<Field>,
    /// 0x60FF Target velocity (output).
    pub target_velocity: Option<Field>,
    /// 0x6071 Target torque (output).
    pub target_torque: Option<Field>,
    /// 0x60B1 Velocity offset (output).
    pub velocity_offset: Option<Field>,
    /// 0x60B2 Torque offset (output).
    pub torque_offset: Option<Field>,
    /// 0x60C1:01 Interpolation data record, first entry (output): carries the target position
    /// in interpolated position mode.
    pub ip_position: Option<Field>,
    /// 0x6041 Statusword (input).
    pub statusword: Option<Field>,
    /// 0x6061 Modes of operation display (input).
    pub mode_display: Option<Field>,
    /// 0x6064 Position actual value (input).
    pub position: Option<Field>,
    /// 0x606C Velocity actual value (input).
    pub velocity: Option<Field>,
    /// 0x6077 Torque actual value (input).
    pub torque: Option<Field>,
    /// 0x603F Error code (input).
    pub error_code: Option<Field>,
    /// 0x60F4 Following error actual value (input).
    pub following_error: Option<Field>,
    /// 0x60FD Digital inputs (input).
    pub digital_inputs: Option<Field>,
    /// A drive-specific zero-speed flag (input object and bit), if the drive has one mapped.
    pub zero_speed: Option<(Field, u8)>,
}

/// The CiA 402 data type of an object this binding handles, for a dictionary that lacks it.
pub fn standard_type(addr: ObjectAddress) -> Option<DataType> {
    Some(match (addr.index, addr.sub) {
        // Error code, controlword, statusword.
        (0x603F..=0x6041, 0) => DataType::Unsigned16,
        (0x6060 | 0x6061, 0) => DataType::Integer8,
        (0x6063 | 0x6064 | 0x606C | 0x607A | 0x60FF | 0x60F4, 0) => DataType::Integer32,
        (0x6071 | 0x6077 | 0x60B2, 0) => DataType::Integer16,
        (0x60B1, 0) => DataType::Integer32,
        (0x60FD, 0) => DataType::Unsigned32,
        // Touch probe function and status, and the latched positions.
        (0x60B8 | 0x60B9, 0) => DataType::Unsigned16,
        (0x60BA..=0x60BD, 0) => DataType::Integer32,
        (0x60C1, 1) => DataType::Integer32,
        _ => return None,
    })
}

impl AxisBinding {
    /// Resolve every CiA 402 object the layout maps. An object that is mapped but cannot be
    /// read as its type (no type known, a length other than the type's) is an error naming it;
    /// one that is not mapped stays `None`.
    pub fn resolve(layout: &Layout, dictionary: &Dictionary<'_>) -> Result<Self, FieldError> {
        let get = |dir: Direction, index: u16, sub: u8| {
            resolve_mapped(layout, dictionary, dir, ObjectAddress::new(index, sub))
        };
        let (rx, tx) = (Direction::Rx, Direction::Tx);
        Ok(Self {
            controlword: get(rx, 0x6040, 0)?,
            mode: get(rx, 0x6060, 0)?,
            target_position: get(rx, 0x607A, 0)?,
            target_velocity: get(rx, 0x60FF, 0)?,
            target_torque: get(rx, 0x6071, 0)?,
            velocity_offset: get(rx, 0x60B1, 0)?,
            torque_offset: get(rx, 0x60B2, 0)?,
            ip_position: get(rx, 0x60C1, 1)?,
            statusword: get(tx, 0x6041, 0)?,
            mode_display: get(tx, 0x6061, 0)?,
            // A drive without 6064h (Animatics' EDS file) reports its position only as the
            // internal value 6063h: in increments, which the default factor group (1:1)
            // makes the same.
            position: match get(tx, 0x6064, 0)? {
                Some(f) => Some(f),
                None => get(tx, 0x6063, 0)?,
            },
            velocity: get(tx, 0x606C, 0)?,
            torque: get(tx, 0x6077, 0)?,
            error_code: get(tx, 0x603F, 0)?,
            following_error: get(tx, 0x60F4, 0)?,
            digital_inputs: get(tx, 0x60FD, 0)?,
            zero_speed: None,
        })
    }

    /// The statusword in `inputs` (0 when it is not mapped or outside the buffer).
    pub fn statusword(&self, inputs: &[u8]) -> StatusWord {
        StatusWord::from_raw(read(self.statusword, inputs).unwrap_or(0) as u16)
    }

    /// The feedback for [`crate::cia402::Axis::step`] from `inputs`: every mapped object, the
    /// rest `None`.
    pub fn feedback(&self, inputs: &[u8]) -> Feedback {
        let [sw, mode, position, velocity, torque, error_code] = read_each(
            inputs,
            [
                self.statusword,
                self.mode_display,
                self.position,
                self.velocity,
                self.torque,
                self.error_code,
            ],
        );
        let mut fb = Feedback::new(StatusWord::from_raw(sw.unwrap_or(0) as u16));
        fb.mode_display = mode.map(|v| OperationMode::from_i8(v as i8));
        fb.position = position.map(|v| v as i32);
        fb.velocity = velocity.map(|v| v as i32);
        fb.torque = torque.map(|v| v as i16);
        fb.error_code = error_code.map(|v| ErrorCode(v as u16));
        fb.zero_speed = self.zero_speed.and_then(|(f, bit)| {
            f.read_raw(inputs)
                .ok()
                .map(|raw| raw >> bit.min(63) & 1 == 1)
        });
        fb
    }

    /// 0x60F4 from `inputs`, if mapped.
    pub fn following_error(&self, inputs: &[u8]) -> Option<i64> {
        read(self.following_error, inputs)
    }

    /// 0x60FD from `inputs`, if mapped.
    pub fn digital_inputs(&self, inputs: &[u8]) -> Option<u32> {
        read(self.digital_inputs, inputs).map(|v| v as u32)
    }

    /// Write `out` into `outputs`: the controlword, the mode, the three targets and the two
    /// offsets, and the target position into 0x60C1:01 too — each where it is mapped.
    pub fn write(&self, out: &Output, outputs: &mut [u8]) {
        write_each(
            outputs,
            [
                (self.controlword, i64::from(out.controlword.raw())),
                (self.mode, i64::from(out.mode.as_i8())),
                (self.target_position, i64::from(out.target_position)),
                (self.target_velocity, i64::from(out.target_velocity)),
                (self.target_torque, i64::from(out.target_torque)),
                (self.velocity_offset, i64::from(out.velocity_offset)),
                (self.torque_offset, i64::from(out.torque_offset)),
                (self.ip_position, i64::from(out.target_position)),
            ],
        );
    }

    /// Write controlword 0 (Disable voltage) into `outputs`: what a drive gets while it is not
    /// to be driven.
    pub fn write_disable_voltage(&self, outputs: &mut [u8]) {
        write(self.controlword, outputs, 0);
    }

    /// Whether `addr` is one of the outputs a binding writes every cycle.
    pub fn drives(addr: ObjectAddress) -> bool {
        matches!(
            (addr.index, addr.sub),
            (
                0x6040 | 0x6060 | 0x607A | 0x60FF | 0x6071 | 0x60B1 | 0x60B2,
                0
            ) | (0x60C1, 1)
        )
    }
}

/// The field of `addr` in direction `dir`, typed by the dictionary (or, for an object it lacks,
/// by [`standard_type`]); `None` when `addr` is not mapped. A mapped object whose type is unknown
/// or whose mapped length is not its type's is an error naming it.
pub fn resolve_mapped(
    layout: &Layout,
    dictionary: &Dictionary<'_>,
    dir: Direction,
    addr: ObjectAddress,
) -> Result<Option<Field>, FieldError> {
    if layout.find(dir, addr).is_none() {
        return Ok(None);
    }
    let data_type = dictionary
        .data_type(addr)
        .or_else(|| standard_type(addr))
        .ok_or(FieldError::NotInDictionary { addr })?;
    layout.field(dir, addr, data_type).map(Some)
}

/// A mapped field's value as an integer (`None`: not mapped, or outside the buffer).
#[inline]
pub fn read(field: Option<Field>, image: &[u8]) -> Option<i64> {
    field
        .and_then(|f| f.read_int(image).ok())
        .and_then(|v| i64::try_from(v).ok())
}

/// Each field's value as [`read`] has it, through one copy of the code (not one per field): the
/// cycle runs it cold from memory after each sleep, so its size is its cost.
pub fn read_each<const N: usize>(image: &[u8], fields: [Option<Field>; N]) -> [Option<i64>; N] {
    fields.map(|f| read_one(f, image))
}

/// Each value written as [`write`] does, through one copy of the code (see [`read_each`]).
pub fn write_each<const N: usize>(image: &mut [u8], values: [(Option<Field>, i64); N]) {
    for (f, v) in values {
        write_one(f, image, v);
    }
}

/// [`read`], never inlined (see [`read_each`]).
#[inline(never)]
fn read_one(field: Option<Field>, image: &[u8]) -> Option<i64> {
    read(field, image)
}

/// [`write`], never inlined (see [`read_each`]).
#[inline(never)]
fn write_one(field: Option<Field>, image: &mut [u8], value: i64) {
    write(field, image, value)
}

/// Write an integer into a mapped field (nothing when it is not mapped or outside the buffer;
/// the value wraps to the field's width).
#[inline]
pub fn write(field: Option<Field>, image: &mut [u8], value: i64) {
    if let Some(f) = field {
        let _ = f.write_int(image, i128::from(value));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cia402::{ControlWord, OperationMode};
    use crate::pdo::{Mapping, Pdo, PdoEntry};

    fn layout() -> Layout {
        let rx = Pdo::owned(
            0x1600,
            vec![
                PdoEntry::new(0x6040, 0, 16),
                PdoEntry::new(0x6060, 0, 8),
                PdoEntry::new(0x607A, 0, 32),
            ],
        );
        let tx = Pdo::owned(
            0x1A00,
            vec![
                PdoEntry::new(0x6041, 0, 16),
                PdoEntry::new(0x6064, 0, 32),
                PdoEntry::new(0x60F4, 0, 32),
            ],
        );
        Layout::new(&Mapping::owned(vec![rx], vec![tx]))
    }

    #[test]
    fn reads_and_writes_what_is_mapped_only() {
        let b = AxisBinding::resolve(&layout(), &Dictionary::new(&[])).expect("standard types");
        assert!(b.target_velocity.is_none() && b.velocity.is_none());
        let mut inputs = [0u8; 10];
        inputs[..2].copy_from_slice(&0x0237u16.to_le_bytes());
        inputs[2..6].copy_from_slice(&(-5i32).to_le_bytes());
        inputs[6..10].copy_from_slice(&7i32.to_le_bytes());
        let fb = b.feedback(&inputs);
        assert_eq!(fb.statusword.raw(), 0x0237);
        assert_eq!(fb.position, Some(-5));
        assert_eq!(fb.velocity, None);
        assert_eq!(b.following_error(&inputs), Some(7));
        let out = Output {
            controlword: ControlWord::from_raw(0x000F),
            mode: OperationMode::CyclicSyncPosition,
            target_position: 1234,
            target_velocity: 99,
            target_torque: 5,
            velocity_offset: 0,
            torque_offset: 0,
        };
        let mut outputs = [0u8; 7];
        b.write(&out, &mut outputs);
        assert_eq!(outputs[..2], 0x000Fu16.to_le_bytes());
        assert_eq!(outputs[2], 8);
        assert_eq!(outputs[3..7], 1234i32.to_le_bytes());
        b.write_disable_voltage(&mut outputs);
        assert_eq!(outputs[..2], [0, 0]);
    }

    #[test]
    fn a_short_buffer_reads_as_absent_and_takes_no_write() {
        let b = AxisBinding::resolve(&layout(), &Dictionary::new(&[])).expect("standard types");
        let fb = b.feedback(&[0x37]);
        assert_eq!(fb.statusword.raw(), 0);
        assert_eq!(fb.position, None);
        let mut short = [0u8; 1];
        b.write_disable_voltage(&mut short);
        assert_eq!(short, [0]);
    }

    #[test]
    fn a_mapped_object_of_unknown_type_is_named() {
        let rx = Pdo::owned(0x1600, vec![PdoEntry::new(0x2000, 0, 16)]);
        let l = Layout::new(&Mapping::owned(vec![rx], vec![]));
        // 0x2000 is not one the binding resolves: ignored.
        assert!(AxisBinding::resolve(&l, &Dictionary::new(&[])).is_ok());
        let rx = Pdo::owned(0x1600, vec![PdoEntry::new(0x6040, 0, 8)]);
        let l = Layout::new(&Mapping::owned(vec![rx], vec![]));
        let e = AxisBinding::resolve(&l, &Dictionary::new(&[])).expect_err("8-bit controlword");
        assert!(e.to_string().contains("0x6040"), "{e}");
    }
}
