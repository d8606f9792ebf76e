//! An SII [`DeviceDescription`] from an ESI device: what a configuration tool writes into a
//! device's EEPROM, so that the emulated drive's EEPROM and its ESI file cannot drift apart.

use crate::esi::{self, EsiFile, FmmuUsage as EsiFmmu, MailboxProtocols as EsiProtocols, SmKind};
use crate::pdo::Direction;
use crate::sim::sii::{
    CoeDetails, DcOpMode, DeviceDescription, FmmuUsage, Identity, MailboxDesc, MailboxProtocols,
    PdoDesc, PdoEntryDesc, SmDesc, SmEnable, SmType,
};

/// Why an ESI device cannot be turned into an SII description.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("ESI device {device:?} (product 0x{product_code:08X}): {reason}")]
pub struct EsiSiiError {
    /// The device name.
    pub device: String,
    /// Its product code.
    pub product_code: u32,
    /// What is missing or wrong.
    pub reason: String,
}

/// ETG.2010 PDO flags of the SII PDO categories.
mod pdo_flag {
    pub const MANDATORY: u16 = 0x0001;
    pub const DEFAULT: u16 = 0x0002;
    pub const FIXED_CONTENT: u16 = 0x0010;
}

impl DeviceDescription {
    /// The SII description of `device` from `file`: identity (serial 0), names, the EEPROM
    /// configuration words (`<Eeprom><ConfigData>`, `<ByteSize>`), the mailbox (from the
    /// mailbox SyncManagers and `<Mailbox>`), CoE and FoE details, SyncManagers, FMMUs, every
    /// PDO with its entries, and the DC modes.
    pub fn from_esi(file: &EsiFile, device: &esi::Device) -> Result<Self, EsiSiiError> {
        let err = |reason: String| EsiSiiError {
            device: device.name.clone(),
            product_code: device.type_.product_code,
            reason,
        };
        let mut d = DeviceDescription {
            identity: Identity {
                vendor_id: file.vendor.id,
                product_code: device.type_.product_code,
                revision: device.type_.revision_no.unwrap_or(0),
                serial: 0,
            },
            order: device.type_.name_text.clone(),
            name: device.name.clone(),
            group: device
                .group_type
                .as_deref()
                .and_then(|t| file.group(t))
                .map(|g| g.name.clone())
                .unwrap_or_default(),
            ..Default::default()
        };
        if let Some(e) = &device.eeprom {
            let w = |i: usize| -> u16 {
                let lo = e.config_data.get(2 * i).copied().unwrap_or(0);
                let hi = e.config_data.get(2 * i + 1).copied().unwrap_or(0);
                u16::from_le_bytes([lo, hi])
            };
            if !e.config_data.is_empty() {
                d.pdi_control = w(0);
                d.pdi_config = w(1);
                d.sync_impulse_len = w(2);
                d.pdi_config2 = w(3);
                d.alias = w(4);
            }
            if let Some(b) = e.byte_size {
                d.eeprom_bytes = usize::try_from(b).map_err(|_| err("EEPROM size".into()))?;
            }
        }
        d.sync_managers = device
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
        d.fmmus = device
            .fmmus
            .iter()
            .map(|f| match f.usage {
                EsiFmmu::Outputs => FmmuUsage::Outputs,
                EsiFmmu::Inputs => FmmuUsage::Inputs,
                EsiFmmu::MBoxState => FmmuUsage::SmStatus,
                EsiFmmu::Unused => FmmuUsage::Unused,
            })
            .collect();
        if let Some(m) = &device.mailbox {
            let sm = |k: SmKind| device.sync_manager(k);
            let (Some(out), Some(inp)) = (sm(SmKind::MBoxOut), sm(SmKind::MBoxIn)) else {
                return Err(err(
                    "the device has a mailbox but no MBoxOut/MBoxIn SyncManager".into(),
                ));
            };
            let protocols = MailboxProtocols::from_bits_truncate(m.protocols.bits());
            let size = |s: &esi::SyncManager| {
                s.default_size
                    .ok_or_else(|| err(format!("mailbox SM{} has no DefaultSize", s.index)))
            };
            d.mailbox = Some(MailboxDesc {
                rx_offset: out.start_address,
                rx_size: size(out)?,
                tx_offset: inp.start_address,
                tx_size: size(inp)?,
                protocols,
                bootstrap: None,
            });
            if let Some(c) = &m.coe {
                d.coe_details = CoeDetails::from_bits_truncate(c.sii_byte());
            }
            if m.protocols.contains(EsiProtocols::FOE) {
                d.foe_details = 1;
            }
        }
        d.ds402_channels = u8::from(device.profiles.iter().any(|p| p.profile_no == Some(402)));
        let sm_of = |kind: SmKind| {
            device
                .sync_managers
                .iter()
                .find(|s| s.kind == kind)
                .map(|s| s.index)
        };
        for (dir, list) in [
            (Direction::Tx, &mut d.tx_pdos),
            (Direction::Rx, &mut d.rx_pdos),
        ] {
            let own_sm = sm_of(match dir {
                Direction::Rx => SmKind::Outputs,
                Direction::Tx => SmKind::Inputs,
            });
            for p in device.pdos(dir) {
                let mut flags = 0;
                if p.mandatory {
                    flags |= pdo_flag::MANDATORY;
                }
                if p.is_default() {
                    flags |= pdo_flag::DEFAULT;
                }
                if p.fixed {
                    flags |= pdo_flag::FIXED_CONTENT;
                }
                let entries = p
                    .entries
                    .iter()
                    .map(|e| {
                        let bits = u8::try_from(e.bit_len).map_err(|_| {
                            err(format!(
                                "PDO 0x{:04X} entry 0x{:04X}:{:02X} is {} bits",
                                p.index, e.index, e.sub, e.bit_len
                            ))
                        })?;
                        Ok(PdoEntryDesc {
                            index: e.index,
                            sub: e.sub,
                            name: e.name.clone(),
                            data_type: e.data_type().map_or(0, |t| t.code() as u8),
                            bits,
                            flags: 0,
                        })
                    })
                    .collect::<Result<Vec<_>, EsiSiiError>>()?;
                list.push(PdoDesc {
                    index: p.index,
                    sm: match p.sm {
                        Some(s) => s,
                        None if p.mandatory => own_sm.unwrap_or(0xFF),
                        None => 0xFF,
                    },
                    dc_sync: 0,
                    name: p.name.clone(),
                    flags,
                    entries,
                });
            }
        }
        d.dc_modes = device
            .dc
            .iter()
            .map(|m| DcOpMode {
                name: m.name.clone(),
                description: m.desc.clone(),
                assign_activate: m.assign_activate,
                cycle_time0: m.cycle_time_sync0,
                shift_time0: m.shift_time_sync0 as u32,
                shift_time1: m.shift_time_sync1 as u32,
                sync0_cycle_factor: m
                    .cycle_time_sync0_factor
                    .and_then(|f| i16::try_from(f).ok())
                    .unwrap_or(0),
                sync1_cycle_factor: m
                    .cycle_time_sync1_factor
                    .and_then(|f| i16::try_from(f).ok())
                    .unwrap_or(0),
            })
            .collect();
        Ok(d)
    }
}
