//! `ecdrive slaves`: what each device on the segment is.

use super::{Discovered, T_STEP, al_state_text, discover, drive_ref, read_al_status};
use crate::ec::{AlStatus, AlStatusCode, register};
use crate::link::FrameLink;
use crate::master::bus::Bus;
use crate::master::error::{DriveRef, MasterError, bus_error};
use crate::master::exec::exec_error;
use serde::Serialize;

/// AL status of a device, with the status code when the error flag is set.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct AlStatusReport {
    /// The state as IgH writes it (`INIT`, `PREOP`, `SAFEOP`, `OP`, `BOOT`), with `+ERR` when the
    /// error flag is set.
    pub state: String,
    /// The error indication flag (0x0130 bit 4).
    pub error: bool,
    /// AL status code (0x0134), when the error flag is set.
    pub code: Option<u16>,
    /// Its ETG.1000.6 meaning.
    pub code_text: Option<String>,
}

impl AlStatusReport {
    /// The report of an AL status and its status code.
    pub fn new(status: AlStatus, code: AlStatusCode) -> Self {
        Self {
            state: al_state_text(status),
            error: status.error(),
            code: status.error().then_some(code.0),
            code_text: status
                .error()
                .then(|| code.text().unwrap_or("unknown AL status code").to_string()),
        }
    }
}

/// One device on the segment.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SlaveReport {
    /// Position on the segment (0 = first).
    pub position: u16,
    /// Configured station address.
    pub address: u16,
    /// Configured station alias (from the SII).
    pub alias: u16,
    /// The AL status the device was in when found, before discovery reset it to INIT and took
    /// it to PRE-OP (`None` if it did not answer that read).
    pub found: Option<AlStatusReport>,
    /// AL status now, after discovery (PRE-OP, unless the device refused it).
    pub al: AlStatusReport,
    /// Vendor ID.
    pub vendor_id: u32,
    /// Product code.
    pub product_code: u32,
    /// Revision.
    pub revision: u32,
    /// Serial number.
    pub serial: u32,
    /// The SII name (order code, e.g. `MR-J4-10TM`).
    pub name: String,
    /// The SII device description (long name), if it has one.
    pub description: Option<String>,
    /// The matched drive profile's name, if a profile matches the identity.
    pub profile: Option<String>,
    /// Whether the ESC supports distributed clocks.
    pub dc: bool,
    /// DC capability: `64 bit`, `32 bit`, `reference only` or `none`.
    pub dc_kind: String,
    /// Mailbox protocols the SII announces (`AoE`, `EoE`, `CoE`, `FoE`, `SoE`, `VoE`).
    pub mailbox_protocols: Vec<String>,
    /// The details of `--verbose`.
    pub detail: Option<SlaveDetail>,
}

/// ESC information (registers 0x0000–0x0009).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct EscInfo {
    /// ESC type (0x0000).
    pub esc_type: u8,
    /// ESC revision (0x0001).
    pub revision: u8,
    /// ESC build (0x0002).
    pub build: u16,
    /// FMMUs supported (0x0004).
    pub fmmus: u8,
    /// SyncManagers supported (0x0005).
    pub sync_managers: u8,
    /// Process data RAM in KiB (0x0006).
    pub ram_kib: u8,
}

/// One port's link state (DL status, 0x0110).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct PortReport {
    /// Port number 0–3.
    pub port: u8,
    /// Physical link.
    pub link: bool,
    /// Loop closed (the port forwards to itself).
    pub loop_closed: bool,
    /// Stable communication on the port.
    pub communication: bool,
}

/// The standard mailbox as the SII describes it (words 0x18–0x1B).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct MailboxReport {
    /// Master → device mailbox start (SM0).
    pub rx_offset: u16,
    /// Its size.
    pub rx_size: u16,
    /// Device → master mailbox start (SM1).
    pub tx_offset: u16,
    /// Its size.
    pub tx_size: u16,
}

/// What `slaves --verbose` adds.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SlaveDetail {
    /// ESC type and resources.
    pub esc: EscInfo,
    /// Port link states.
    pub ports: Vec<PortReport>,
    /// Propagation delay from the reference clock, ns (measured at discovery).
    pub propagation_delay_ns: u32,
    /// The standard mailbox, if the device has one.
    pub mailbox: Option<MailboxReport>,
    /// EEPROM size in bytes (SII word 0x3E).
    pub eeprom_bytes: usize,
    /// Vendor of the matched profile.
    pub profile_vendor: Option<String>,
}

/// The mailbox protocol names of SII word 0x1C.
pub(crate) fn protocol_names(bits: u16) -> Vec<String> {
    [
        (0x0001, "AoE"),
        (0x0002, "EoE"),
        (0x0004, "CoE"),
        (0x0008, "FoE"),
        (0x0010, "SoE"),
        (0x0020, "VoE"),
    ]
    .into_iter()
    .filter(|(b, _)| bits & b != 0)
    .map(|(_, n)| n.to_string())
    .collect()
}

/// Read SII words 0x18–0x1C (standard mailbox and protocols) of the device at `position`.
pub(crate) fn read_mailbox_words<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    found: &Discovered,
    position: u16,
    drive: &DriveRef,
) -> Result<[u16; 5], MasterError> {
    let group = &found.group;
    let bytes = bus
        .block_on(
            &|| format!("{drive}: reading the SII mailbox words (0x18–0x1C)"),
            T_STEP,
            |md| async move {
                let sd = group.subdevice(md, usize::from(position))?;
                let mut buf = [0u8; 10];
                sd.eeprom_read_raw(md, 0x18, &mut buf).await?;
                Ok::<_, ethercrab::error::Error>(buf)
            },
        )
        .map_err(|e| exec_error(Some(drive), e))?
        .map_err(|e| bus_error(Some(drive), "reading the SII mailbox words (0x18–0x1C)", e))?;
    let w = |i: usize| u16::from_le_bytes([bytes[2 * i], bytes[2 * i + 1]]);
    Ok([w(0), w(1), w(2), w(3), w(4)])
}

/// Every device on the segment, in segment order. With `verbose`, ESC, port, mailbox and
/// EEPROM details too.
pub fn slaves<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    verbose: bool,
) -> Result<Vec<SlaveReport>, MasterError> {
    let found = discover(bus)?;
    let mut out = Vec::with_capacity(found.devices.len());
    for d in &found.devices {
        let drive = drive_ref(d);
        let (status, code) = read_al_status(bus, d.address, &drive)?;
        let mbx = read_mailbox_words(bus, &found, d.position, &drive)?;
        let group = &found.group;
        let pos = usize::from(d.position);
        let (description, dc_kind, delay) = bus
            .block_on(
                &|| format!("{drive}: reading the SII description"),
                T_STEP,
                |md| async move {
                    let sd = group.subdevice(md, pos)?;
                    let desc = sd.description().await?;
                    let kind = match sd.dc_support() {
                        ethercrab::DcSupport::None => "none",
                        ethercrab::DcSupport::RefOnly => "reference only",
                        ethercrab::DcSupport::Bits64 => "64 bit",
                        ethercrab::DcSupport::Bits32 => "32 bit",
                    };
                    Ok::<_, ethercrab::error::Error>((
                        desc.map(|s| s.to_string()),
                        kind,
                        sd.propagation_delay(),
                    ))
                },
            )
            .map_err(|e| exec_error(Some(&drive), e))?
            .map_err(|e| bus_error(Some(&drive), "reading the SII description", e))?;
        let profile = crate::drives::by_identity(d.vendor_id, d.product_code);
        let detail = if verbose {
            Some(detail(
                bus, &found, d.position, d.address, &drive, mbx, delay,
            )?)
            .map(|mut det| {
                det.profile_vendor = profile.map(|p| p.vendor.to_string());
                det
            })
        } else {
            None
        };
        out.push(SlaveReport {
            position: d.position,
            address: d.address,
            alias: d.alias,
            found: d.found.map(|f| AlStatusReport::new(f.status, f.code)),
            al: AlStatusReport::new(status, code),
            vendor_id: d.vendor_id,
            product_code: d.product_code,
            revision: d.revision,
            serial: d.serial,
            name: d.name.clone(),
            description,
            profile: d.profile.map(str::to_string),
            dc: d.dc,
            dc_kind: dc_kind.to_string(),
            mailbox_protocols: protocol_names(mbx[4]),
            detail,
        });
    }
    Ok(out)
}

fn detail<L: FrameLink>(
    bus: &mut Bus<'_, L>,
    found: &Discovered,
    position: u16,
    address: u16,
    drive: &DriveRef,
    mbx: [u16; 5],
    propagation_delay_ns: u32,
) -> Result<SlaveDetail, MasterError> {
    let esc = bus
        .block_on(
            &|| format!("{drive}: reading the ESC information (0x0000)"),
            T_STEP,
            |md| async move {
                ethercrab::Command::fprd(address, register::TYPE)
                    .receive::<[u8; 8]>(md)
                    .await
            },
        )
        .map_err(|e| exec_error(Some(drive), e))?
        .map_err(|e| bus_error(Some(drive), "reading the ESC information (0x0000)", e))?;
    let dl = bus
        .block_on(
            &|| format!("{drive}: reading DL status (0x0110)"),
            T_STEP,
            |md| async move {
                ethercrab::Command::fprd(address, register::DL_STATUS)
                    .receive::<u16>(md)
                    .await
            },
        )
        .map_err(|e| exec_error(Some(drive), e))?
        .map_err(|e| bus_error(Some(drive), "reading DL status (0x0110)", e))?;
    let group = &found.group;
    let eeprom_bytes = bus
        .block_on(
            &|| format!("{drive}: reading the EEPROM size"),
            T_STEP,
            |md| async move {
                let sd = group.subdevice(md, usize::from(position))?;
                sd.eeprom_size(md).await
            },
        )
        .map_err(|e| exec_error(Some(drive), e))?
        .map_err(|e| bus_error(Some(drive), "reading the EEPROM size (SII word 0x3E)", e))?;
    let ports = (0..4u8)
        .map(|p| PortReport {
            port: p,
            link: dl & (1 << (4 + p)) != 0,
            loop_closed: dl & (1 << (8 + 2 * p)) != 0,
            communication: dl & (1 << (9 + 2 * p)) != 0,
        })
        .collect();
    let [rx_offset, rx_size, tx_offset, tx_size, _] = mbx;
    Ok(SlaveDetail {
        esc: EscInfo {
            esc_type: esc[0],
            revision: esc[1],
            build: u16::from_le_bytes([esc[2], esc[3]]),
            fmmus: esc[4],
            sync_managers: esc[5],
            ram_kib: esc[6],
        },
        ports,
        propagation_delay_ns,
        mailbox: (rx_size > 0 && tx_size > 0 && rx_size != 0xFFFF).then_some(MailboxReport {
            rx_offset,
            rx_size,
            tx_offset,
            tx_size,
        }),
        eeprom_bytes,
        profile_vendor: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn protocol_bits_are_named() {
        assert_eq!(protocol_names(0x000C), vec!["CoE", "FoE"]);
        assert!(protocol_names(0).is_empty());
    }
}
