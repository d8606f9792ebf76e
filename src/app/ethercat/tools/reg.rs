//! `ecdrive reg`: reading and writing ESC registers of one device.

use super::{T_STEP, discover, drive_ref};
use crate::link::FrameLink;
use crate::master::bus::Bus;
use crate::master::error::{ErrorKind, MasterError, bus_error};
use crate::master::exec::exec_error;
use crate::od::{DataType, Value};
use serde::Serialize;

/// Largest register access in one datagram (the ESC's 4 KiB register and RAM window is larger,
/// but one Ethernet frame carries at most ~1486 bytes of data).
pub const MAX_REGISTER_BYTES: u16 = 1024;

/// Register bytes read or written.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RegisterData {
    /// Position of the device.
    pub position: u16,
    /// The device (profile name, or the SII name).
    pub drive: String,
    /// First register address.
    pub address: u16,
    /// The bytes, in hex, in address order.
    pub bytes: String,
    /// The value decoded with `--type`, if given.
    pub value: Option<super::od::JsonValue>,
    /// The data type name used, if given.
    pub data_type: Option<String>,
}

fn check_range(address: u16, len: u16) -> Result<(), MasterError> {
    if len == 0 || len > MAX_REGISTER_BYTES {
        return Err(MasterError::new(
            None,
            format!("accessing register 0x{address:04X}"),
            ErrorKind::Config,
            format!("the length must be 1–{MAX_REGISTER_BYTES} bytes, not {len}"),
        ));
    }
    if u32::from(address) + u32::from(len) > 0x1_0000 {
        return Err(MasterError::new(
            None,
            format!("accessing register 0x{address:04X}"),
            ErrorKind::Config,
            format!("{len} bytes from 0x{address:04X} run past 0xFFFF"),
        ));
    }
    Ok(())
}

fn hex(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02x}")).collect()
}

/// The register length of a `--type`, and a check that it has one.
pub fn type_len(dt: DataType) -> Result<u16, MasterError> {
    dt.bit_len().map(|b| b.div_ceil(8)).ok_or_else(|| {
        MasterError::new(
            None,
            "choosing the register length",
            ErrorKind::Config,
            format!("{dt} has no fixed size; give the length in bytes instead"),
        )
    })
}

/// Read `len` bytes from register `address` of the device at `position`; with `data_type`,
/// decode them (little-endian, as the ESC stores them).
pub fn reg_read<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    address: u16,
    len: u16,
    data_type: Option<DataType>,
) -> Result<RegisterData, MasterError> {
    check_range(address, len)?;
    let found = discover(bus)?;
    let d = found.device(position)?.clone();
    let drive = drive_ref(&d);
    let station = d.address;
    let step = format!("reading register 0x{address:04X} ({len} bytes)");
    let bytes = bus
        .block_on(&|| format!("{drive}: {step}"), T_STEP, |md| async move {
            ethercrab::Command::fprd(station, address)
                .receive_slice(md, len)
                .await
                .map(|b| b.to_vec())
        })
        .map_err(|e| exec_error(Some(&drive), e))?
        .map_err(|e| bus_error(Some(&drive), step.clone(), e))?;
    let value = match data_type {
        Some(dt) => Some(
            Value::decode(dt, &bytes)
                .map(|v| super::od::JsonValue::from(&v))
                .map_err(|e| MasterError::new(Some(&drive), step.clone(), ErrorKind::Config, e))?,
        ),
        None => None,
    };
    Ok(RegisterData {
        position,
        drive: drive.name,
        address,
        bytes: hex(&bytes),
        value,
        data_type: data_type.map(|t| t.name().to_string()),
    })
}

/// Write to register `address` of the device at `position`: `value` parsed as `data_type`
/// (little-endian), or, without a type, as hex bytes in address order (`"0x0200"`, `"02 00"`).
pub fn reg_write<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    address: u16,
    value: &str,
    data_type: Option<DataType>,
) -> Result<RegisterData, MasterError> {
    let dt = data_type.unwrap_or(DataType::OctetString);
    let v = Value::parse(value, dt).map_err(|e| {
        MasterError::new(
            None,
            format!("parsing the value for register 0x{address:04X}"),
            ErrorKind::Config,
            e,
        )
    })?;
    let bytes = v.encode(dt).map_err(|e| {
        MasterError::new(
            None,
            format!("encoding the value for register 0x{address:04X}"),
            ErrorKind::Config,
            e,
        )
    })?;
    let len = u16::try_from(bytes.len()).unwrap_or(u16::MAX);
    check_range(address, len)?;
    let found = discover(bus)?;
    let d = found.device(position)?.clone();
    let drive = drive_ref(&d);
    let station = d.address;
    let step = format!("writing register 0x{address:04X} ({len} bytes)");
    let data = bytes.clone();
    bus.block_on(&|| format!("{drive}: {step}"), T_STEP, |md| async move {
        ethercrab::Command::fpwr(station, address)
            .send(md, data.as_slice())
            .await
    })
    .map_err(|e| exec_error(Some(&drive), e))?
    .map_err(|e| bus_error(Some(&drive), step.clone(), e))?;
    Ok(RegisterData {
        position,
        drive: drive.name,
        address,
        bytes: hex(&bytes),
        value: data_type.map(|_| super::od::JsonValue::from(&v)),
        data_type: data_type.map(|t| t.name().to_string()),
    })
}
