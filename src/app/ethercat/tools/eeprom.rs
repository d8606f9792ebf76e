//! The SII EEPROM of a device by position, through its ESC's EEPROM interface (0x0500–0x050F),
//! without a discovery: `graph` reads identities with it, `alias` and `sii write` write with
//! it. Word by word, as the ESC datasheets describe the interface:
//!
//! - read: control 0x0502 = command 1 (read) with the word address in 0x0504, wait while busy
//!   (0x0502 bit 15), then 4 or 8 bytes (0x0502 bit 6) from 0x0508;
//! - write: the word into 0x0508, then control = write enable (bit 0) + command 2 in the same
//!   access as the address, wait while busy; bit 13 (no acknowledge from the EEPROM: write
//!   protection or a faulty part) and bit 14 (write enable error) say it failed.
//!
//! The EEPROM must be assigned to EtherCAT (0x0500 bit 0 = 0); when the device's processor
//! holds it and is not using it (0x0501 bit 0 = 0), it is taken back; when it is using it, the
//! access is refused.

use super::diag::{aprd, apwr};
use crate::link::FrameLink;
use crate::master::bus::Bus;
use crate::master::error::{ErrorKind, MasterError};
use std::time::{Duration, Instant};

/// How long the EEPROM interface may stay busy for one command (an EEPROM write takes a few
/// ms on real parts).
const T_EEPROM: Duration = Duration::from_millis(100);

/// Control/status bits of 0x0502.
const BUSY: u16 = 0x8000;
const NACK: u16 = 0x2000;
const WRITE_ENABLE_ERROR: u16 = 0x4000;
const READ_8: u16 = 0x0040;

fn u16_at(b: &[u8], i: usize) -> u16 {
    u16::from_le_bytes([
        b.get(i).copied().unwrap_or(0),
        b.get(i + 1).copied().unwrap_or(0),
    ])
}

fn device(position: u16) -> String {
    format!("device {position}")
}

/// Make sure EtherCAT owns the EEPROM interface of the device at `position`.
pub(super) fn take_access<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
) -> Result<(), MasterError> {
    let c = aprd(bus, position, 0x0500, 2)?;
    let (assigned_to_pdi, pdi_busy) = (
        c.first().is_some_and(|b| b & 0x01 != 0),
        c.get(1).is_some_and(|b| b & 0x01 != 0),
    );
    if !assigned_to_pdi {
        return Ok(());
    }
    if pdi_busy {
        return Err(MasterError::new(
            None,
            format!("{}: taking the EEPROM (0x0500)", device(position)),
            ErrorKind::Bus,
            "the device's processor is using its EEPROM (0x0501 bit 0); try again when it is \
             done, or in INIT",
        ));
    }
    apwr(bus, position, 0x0500, &[0x00])
}

/// Wait until the EEPROM interface is idle; returns 0x0502.
fn wait_idle<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    step: &dyn Fn() -> String,
) -> Result<u16, MasterError> {
    let until = Instant::now() + T_EEPROM;
    loop {
        let c = u16_at(&aprd(bus, position, 0x0502, 2)?, 0);
        if c & BUSY == 0 {
            return Ok(c);
        }
        if Instant::now() > until {
            return Err(MasterError::new(
                None,
                step(),
                ErrorKind::Timeout,
                format!(
                    "the EEPROM interface stayed busy for {} ms",
                    T_EEPROM.as_millis()
                ),
            ));
        }
        std::thread::sleep(Duration::from_micros(200));
    }
}

/// Read `count` words from `word` of the device at `position`.
pub fn read_words<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    word: u16,
    count: usize,
) -> Result<Vec<u16>, MasterError> {
    take_access(bus, position)?;
    let mut out = Vec::with_capacity(count);
    while out.len() < count {
        let at = usize::from(word) + out.len();
        let at = u16::try_from(at).map_err(|_| {
            MasterError::new(
                None,
                format!("{}: reading the EEPROM", device(position)),
                ErrorKind::Config,
                "the address is beyond word 0xFFFF",
            )
        })?;
        let step = || format!("{}: reading EEPROM word 0x{at:04X}", device(position));
        let w = at.to_le_bytes();
        apwr(bus, position, 0x0502, &[0x00, 0x01, w[0], w[1], 0, 0])?;
        let status = wait_idle(bus, position, &step)?;
        if status & NACK != 0 {
            return Err(MasterError::new(
                None,
                step(),
                ErrorKind::Bus,
                "the EEPROM did not acknowledge the read (0x0502 bit 13)",
            ));
        }
        let n = if status & READ_8 != 0 { 8 } else { 4 };
        let d = aprd(bus, position, 0x0508, n)?;
        for i in 0..usize::from(n) / 2 {
            if out.len() < count {
                out.push(u16_at(&d, 2 * i));
            }
        }
    }
    Ok(out)
}

/// Read 4 bytes (two words) from `word`.
pub fn read_u32<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    word: u16,
) -> Result<u32, MasterError> {
    let w = read_words(bus, position, word, 2)?;
    Ok(
        u32::from(w.first().copied().unwrap_or(0))
            | u32::from(w.get(1).copied().unwrap_or(0)) << 16,
    )
}

/// Write `value` to `word`. A write the EEPROM does not acknowledge is tried three times, then
/// reported as write protection.
pub fn write_word<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    word: u16,
    value: u16,
) -> Result<(), MasterError> {
    let step = || format!("{}: writing EEPROM word 0x{word:04X}", device(position));
    let w = word.to_le_bytes();
    for attempt in 0..3 {
        wait_idle(bus, position, &step)?;
        apwr(bus, position, 0x0508, &value.to_le_bytes())?;
        // Write enable (bit 0) and the write command (bits 8–10 = 2) in the access that also
        // carries the address: the ESC clears write enable after each command.
        apwr(bus, position, 0x0502, &[0x01, 0x02, w[0], w[1], 0, 0])?;
        let status = wait_idle(bus, position, &step)?;
        if status & WRITE_ENABLE_ERROR != 0 {
            return Err(MasterError::new(
                None,
                step(),
                ErrorKind::Bus,
                "the ESC refused the write (0x0502 bit 14, write enable error)",
            ));
        }
        if status & NACK == 0 {
            return Ok(());
        }
        if attempt < 2 {
            std::thread::sleep(Duration::from_millis(1));
        }
    }
    Err(MasterError::new(
        None,
        step(),
        ErrorKind::Refused,
        "the EEPROM did not acknowledge the write (0x0502 bit 13): it is write-protected or \
         faulty",
    ))
}
