//! `ecdrive alias` and `ecdrive sii write`: write a device's SII EEPROM, by position and
//! without a discovery (a discovery would assign station addresses and move every device to
//! PRE-OP; these leave the segment as it is).
//!
//! Both refuse a device that is not in INIT or PRE-OP (with process data running, the device's
//! processor may be using its EEPROM, and a configuration tool never writes it then), check
//! what they write, write only the words that change, and read everything back.
//!
//! The station alias is SII word 4; the header checksum (word 7, low byte: CRC-8 over words
//! 0–6, [`crate::ec::sii::SII_CRC`]) is updated with it. The ESC loads the alias into 0x0012
//! when it starts (power-on, or an EEPROM reload command): the new alias takes effect at the
//! device's next power cycle, as with the IgH tool.

use super::diag::aprd;
use super::eeprom::{read_words, write_word};
use crate::ec::AlStatus;
use crate::ec::sii::header_checksum;
use crate::link::FrameLink;
use crate::master::bus::Bus;
use crate::master::error::{ErrorKind, MasterError};
use serde::Serialize;

/// What `alias` did.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct AliasReport {
    /// Position of the device.
    pub position: u16,
    /// Its AL state when written.
    pub al_state: String,
    /// The alias in the EEPROM before.
    pub previous: u16,
    /// The alias now in the EEPROM (read back).
    pub alias: u16,
    /// The header checksum now in the EEPROM (word 7, low byte).
    pub checksum: u8,
    /// EEPROM words written (0 when the alias was already there).
    pub words_written: usize,
    /// The alias in the ESC's register 0x0012 now (it changes at the next power cycle).
    pub register_0x0012: u16,
}

/// What `sii write` did.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SiiWriteReport {
    /// Position of the device.
    pub position: u16,
    /// Its AL state when written.
    pub al_state: String,
    /// Bytes in the file.
    pub bytes: usize,
    /// Words that differed and were written.
    pub words_written: usize,
    /// Words already equal.
    pub words_unchanged: usize,
    /// Checks `--force` overrode, in words.
    pub overridden: Vec<String>,
}

fn refuse(position: u16, step: &str, reason: impl std::fmt::Display) -> MasterError {
    MasterError::new(
        None,
        format!("device {position}: {step}"),
        ErrorKind::Config,
        reason,
    )
}

/// The device's AL status; refuses a missing device and one not in INIT or PRE-OP.
fn writable_state<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    step: &str,
) -> Result<AlStatus, MasterError> {
    let r = aprd(bus, position, 0x0130, 2).map_err(|e| {
        if e.reason.contains("working counter") {
            refuse(position, step, "there is no device at this position")
        } else {
            e
        }
    })?;
    let status = AlStatus {
        raw: u16::from_le_bytes([
            r.first().copied().unwrap_or(0),
            r.get(1).copied().unwrap_or(0),
        ]),
    };
    match status.state() {
        Some(crate::ec::AlState::Init | crate::ec::AlState::PreOp) => Ok(status),
        _ => Err(refuse(
            position,
            step,
            format!(
                "it is in {status}: the EEPROM is written only in INIT or PRE-OP, where no \
                 process data runs (`ecdrive states -p {position} PREOP` first)"
            ),
        )),
    }
}

fn bytes_of(words: &[u16]) -> Vec<u8> {
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

/// Write `image` (whole words from word 0) into the EEPROM of the device at `position`: only
/// the words that differ, then every word read back and compared.
fn write_image<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    image: &[u16],
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(usize, usize), MasterError> {
    let before = read_words(bus, position, 0, image.len())?;
    let mut written = 0;
    for (i, (new, old)) in image.iter().zip(&before).enumerate() {
        if new != old {
            write_word(bus, position, i as u16, *new)?;
            written += 1;
        }
        progress(i + 1, image.len());
    }
    let after = read_words(bus, position, 0, image.len())?;
    if let Some(i) = after.iter().zip(image).position(|(a, b)| a != b) {
        return Err(MasterError::new(
            None,
            format!("device {position}: verifying the EEPROM"),
            ErrorKind::Bus,
            format!(
                "word 0x{i:04X} reads back 0x{:04X}, 0x{:04X} was written",
                after.get(i).copied().unwrap_or(0),
                image.get(i).copied().unwrap_or(0)
            ),
        ));
    }
    Ok((written, image.len() - written))
}

/// Set the station alias of the device at `position` to `alias` in its EEPROM.
pub fn alias<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    alias: u16,
) -> Result<AliasReport, MasterError> {
    let step = "writing the station alias";
    let status = writable_state(bus, position, step)?;
    let mut header = read_words(bus, position, 0, 8)?;
    let bytes = bytes_of(&header);
    let stored = bytes.get(14).copied().unwrap_or(0);
    let computed = header_checksum(&bytes).unwrap_or(0);
    if stored != computed {
        return Err(refuse(
            position,
            step,
            format!(
                "the EEPROM header's checksum is wrong (0x{stored:02X} stored, 0x{computed:02X} \
                 computed): not writing a valid checksum over a damaged header; restore the \
                 SII with `ecdrive sii write`"
            ),
        ));
    }
    let previous = header.get(4).copied().unwrap_or(0);
    if let Some(w) = header.get_mut(4) {
        *w = alias;
    }
    let crc = header_checksum(&bytes_of(&header)).unwrap_or(0);
    if let Some(w) = header.get_mut(7) {
        *w = (*w & 0xFF00) | u16::from(crc);
    }
    let (written, _) = write_image(bus, position, &header, &mut |_, _| {})?;
    let reg = aprd(bus, position, 0x0012, 2)?;
    Ok(AliasReport {
        position,
        al_state: status.to_string(),
        previous,
        alias,
        checksum: crc,
        words_written: written,
        register_0x0012: u16::from_le_bytes([
            reg.first().copied().unwrap_or(0),
            reg.get(1).copied().unwrap_or(0),
        ]),
    })
}

/// Write a whole SII image (`ecdrive sii` output, a vendor's `.bin`) into the EEPROM of the
/// device at `position`. Checked first: whole words, at least the header, no larger than the
/// device's EEPROM (never overridden); the header checksum, the categories, and the identity
/// (vendor ID and product code must be the device's) unless `force`.
pub fn sii_write<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    position: u16,
    image: &[u8],
    force: bool,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<SiiWriteReport, MasterError> {
    let step = "writing the SII";
    if image.len() % 2 != 0 || image.len() < 128 {
        return Err(refuse(
            position,
            step,
            format!(
                "the file has {} bytes: an SII image is whole 16-bit words, at least the \
                 128-byte header",
                image.len()
            ),
        ));
    }
    let status = writable_state(bus, position, step)?;
    let current = read_words(bus, position, 0, 64)?;
    let size = (usize::from(current.get(0x3E).copied().unwrap_or(0)) + 1) * 128;
    if image.len() > size {
        return Err(refuse(
            position,
            step,
            format!(
                "the file has {} bytes, the device's EEPROM {size} (SII word 0x3E)",
                image.len()
            ),
        ));
    }
    let mut problems = Vec::new();
    let stored = image.get(14).copied().unwrap_or(0);
    let computed = header_checksum(image).unwrap_or(0);
    if stored != computed {
        problems.push(format!(
            "the header checksum is wrong (0x{stored:02X} stored, 0x{computed:02X} computed)"
        ));
    }
    if let Err(e) = super::sii::SiiInfo::decode(image) {
        problems.push(format!("the categories do not decode: {e}"));
    }
    let ident = |w: &[u16], at: usize| {
        u32::from(w.get(at).copied().unwrap_or(0))
            | u32::from(w.get(at + 1).copied().unwrap_or(0)) << 16
    };
    let file_words: Vec<u16> = image
        .chunks_exact(2)
        .map(|c| u16::from_le_bytes([c[0], c[1]]))
        .collect();
    let (fv, fp) = (ident(&file_words, 8), ident(&file_words, 10));
    let (dv, dp) = (ident(&current, 8), ident(&current, 10));
    if (fv, fp) != (dv, dp) {
        problems.push(format!(
            "the file is for vendor 0x{fv:08X} product 0x{fp:08X}, the device is vendor \
             0x{dv:08X} product 0x{dp:08X}"
        ));
    }
    if !problems.is_empty() && !force {
        return Err(refuse(
            position,
            step,
            format!("{} (--force writes it anyway)", problems.join("; ")),
        ));
    }
    let (written, unchanged) = write_image(bus, position, &file_words, progress)?;
    Ok(SiiWriteReport {
        position,
        al_state: status.to_string(),
        bytes: image.len(),
        words_written: written,
        words_unchanged: unchanged,
        overridden: problems,
    })
}
