//! The SII EEPROM of an emulated slave: the representation, its encoding and the byte view are
//! the core's ([`crate::ec::sii`], re-exported here); what is the emulator's own is
//! [`from_esi`], which describes an ESI device in SII terms as a configuration tool would write
//! its EEPROM.

pub use crate::ec::sii::*;

/// Why an ESI device cannot be described in SII terms.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FromEsiError {
    /// A PDO entry is longer than an SII PDO entry's bit length byte can hold.
    #[error(
        "PDO 0x{pdo:04X} entry 0x{index:04X}:{sub:02X}: BitLen {bits} does not fit the SII (at most 255)"
    )]
    EntryTooLong {
        /// PDO index.
        pdo: u16,
        /// Entry index.
        index: u16,
        /// Entry sub-index.
        sub: u8,
        /// Its bit length.
        bits: u16,
    },
}

/// The PDOs of an ESI list in SII terms.
fn esi_pdos(list: &[crate::esi::EsiPdo]) -> Result<Vec<PdoDesc>, FromEsiError> {
    list.iter()
        .map(|p| {
            let entries = p
                .entries
                .iter()
                .map(|e| {
                    Ok(PdoEntryDesc {
                        index: e.index,
                        sub: e.sub,
                        name: e.name.clone(),
                        data_type: e.data_type().map(|t| t.code() as u8).unwrap_or(0),
                        bits: u8::try_from(e.bit_len).map_err(|_| FromEsiError::EntryTooLong {
                            pdo: p.index,
                            index: e.index,
                            sub: e.sub,
                            bits: e.bit_len,
                        })?,
                        flags: 0,
                    })
                })
                .collect::<Result<Vec<_>, _>>()?;
            // ETG.2010 PDO flags: bit 0 mandatory, bit 1 default, bit 4 fixed content,
            // bit 5 virtual content.
            let flags = u16::from(p.mandatory)
                | u16::from(p.is_default()) << 1
                | u16::from(p.fixed) << 4
                | u16::from(p.virtual_) << 5;
            Ok(PdoDesc {
                index: p.index,
                sm: p.sm.unwrap_or(0xFF),
                dc_sync: 0,
                name: p.name.clone(),
                flags,
                entries,
            })
        })
        .collect()
}

/// Describe an ESI device in SII terms, as a configuration tool would write its EEPROM:
/// identity (vendor from the file, serial given), names, the configuration area from
/// `<Eeprom><ConfigData>`, the mailbox from the `MBoxOut`/`MBoxIn` SyncManagers and `<Mailbox>`,
/// the bootstrap mailbox from `<Eeprom><BootStrap>`, CoE details, SyncManagers, FMMUs, all
/// PDOs (with the default SM assignment) and DC operation modes. The EEPROM size is
/// `<Eeprom><ByteSize>` if given, else [`DEFAULT_EEPROM_BYTES`]; \[REC\] when the image does
/// not fit that size (small ESCs carry a 1 Kbit EEPROM that real tools fill only partly), the
/// smallest power of two that holds it.
pub fn from_esi(
    vendor_id: u32,
    device: &crate::esi::Device,
    serial: u32,
) -> Result<DeviceDescription, FromEsiError> {
    use crate::esi::SmKind;
    let eeprom = device.eeprom.as_ref();
    let cfg = |word: usize| -> Option<u16> {
        let b = eeprom?.config_data.get(word * 2..word * 2 + 2)?;
        Some(u16::from_le_bytes([b[0], b[1]]))
    };
    let mailbox = match (
        device.sync_manager(SmKind::MBoxOut),
        device.sync_manager(SmKind::MBoxIn),
        device.mailbox.as_ref(),
    ) {
        (Some(out), Some(inp), Some(m)) => Some(MailboxDesc {
            rx_offset: out.start_address,
            rx_size: out.default_size.unwrap_or(0),
            tx_offset: inp.start_address,
            tx_size: inp.default_size.unwrap_or(0),
            protocols: m.protocols,
            bootstrap: eeprom.and_then(|e| {
                let w = |i: usize| {
                    e.boot_strap
                        .get(i * 2..i * 2 + 2)
                        .map(|b| u16::from_le_bytes([b[0], b[1]]))
                };
                Some([w(0)?, w(1)?, w(2)?, w(3)?])
            }),
        }),
        _ => None,
    };
    let coe_details = device
        .mailbox
        .as_ref()
        .and_then(|m| m.coe.as_ref())
        .map(|c| CoeDetails::from_bits_truncate(c.sii_byte()))
        .unwrap_or_default();
    let sync_managers = device
        .sync_managers
        .iter()
        .map(|s| SmDesc {
            start: s.start_address,
            length: s.default_size.unwrap_or(0),
            control: s.control_byte,
            enable: SmEnable::from_bits_truncate(s.sii_enable()),
            kind: match s.kind {
                SmKind::MBoxOut => SmType::MailboxOut,
                SmKind::MBoxIn => SmType::MailboxIn,
                SmKind::Outputs => SmType::Outputs,
                SmKind::Inputs => SmType::Inputs,
                SmKind::Unused => SmType::Unused,
            },
        })
        .collect();
    let fmmus = device.fmmus.iter().map(|f| f.usage).collect();
    let dc_modes = device.dc.iter().map(|m| m.mode.clone()).collect();
    let eeprom_bytes = eeprom
        .and_then(|e| e.byte_size)
        .map(|b| (b as usize).div_ceil(128).max(1) * 128)
        .unwrap_or(DEFAULT_EEPROM_BYTES);
    let mut desc = DeviceDescription {
        identity: Identity {
            vendor_id,
            product_code: device.type_.product_code,
            revision: device.type_.revision_no.unwrap_or(0),
            serial,
        },
        order: device.type_.name_text.clone(),
        name: device.name.clone(),
        group: device.group_type.clone().unwrap_or_default(),
        image: None,
        pdi_control: cfg(0).unwrap_or(0x0080),
        pdi_config: cfg(1).unwrap_or(0),
        sync_impulse_len: cfg(2).unwrap_or(0),
        pdi_config2: cfg(3).unwrap_or(0),
        alias: cfg(4).unwrap_or(0),
        mailbox,
        coe_details,
        ds402_channels: u8::from(device.profiles.iter().any(|p| p.profile_no == Some(402))),
        sync_managers,
        fmmus,
        tx_pdos: esi_pdos(&device.tx_pdos)?,
        rx_pdos: esi_pdos(&device.rx_pdos)?,
        dc_modes,
        eeprom_bytes,
        ..Default::default()
    };
    if let Err(SiiError::ImageTooLarge { needed, .. }) = build(&desc) {
        desc.eeprom_bytes = needed.next_power_of_two().max(eeprom_bytes);
    }
    Ok(desc)
}
