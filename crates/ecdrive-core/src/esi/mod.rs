//! ESI (EtherCAT Slave Information, ETG.2000) XML parsing.
//!
//! An ESI file describes a vendor's devices: identity, SyncManagers, FMMUs, the PDOs a device
//! offers, its mailbox protocols and CoE details, DC operation modes, EEPROM settings and its
//! object dictionary. Configuration tools build the SII EEPROM and the start-up configuration
//! from it; this crate builds the emulated drives' SII from the drive files in `esi/` and
//! checks drive profiles against them.
//!
//! ```
//! use ecdrive_core::esi::EsiFile;
//! use ecdrive_core::pdo::Direction;
//!
//! let xml = r##"<EtherCATInfo>
//!   <Vendor><Id>#x00000A1E</Id><Name>Example</Name></Vendor>
//!   <Descriptions><Devices>
//!     <Device Physics="YY">
//!       <Type ProductCode="#x201" RevisionNo="1">Drive</Type>
//!       <Name LcId="1033">Example drive</Name>
//!       <Sm StartAddress="#x1100" ControlByte="#x64" Enable="1">Outputs</Sm>
//!       <RxPdo Sm="0" Fixed="1"><Index>#x1600</Index><Name>Out</Name>
//!         <Entry><Index>#x6040</Index><SubIndex>0</SubIndex><BitLen>16</BitLen>
//!           <Name>Controlword</Name><DataType>UINT</DataType></Entry>
//!       </RxPdo>
//!     </Device>
//!   </Devices></Descriptions>
//! </EtherCATInfo>"##;
//! let esi = EsiFile::parse(xml)?;
//! let dev = esi.device(0x201, None).unwrap();
//! assert_eq!(esi.vendor.id, 0xA1E);
//! let mapping = dev.default_mapping()?;
//! assert_eq!(mapping.bytes(Direction::Rx), 2);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Numbers are read as ETG.2000 writes them: decimal, `#x` hex, and (tolerated) `0x` and
//! `#x0x` hex. Unknown elements are ignored, since vendors add their own.
//!
//! Real vendor files get many things wrong, and a master must read them as the masters people
//! use every day do. Reading is tolerant where the run does not depend on the value, and every
//! problem is reported at once, each with line and column:
//!
//! - an error in what a device's process data or start-up depends on (a PDO entry, a
//!   SyncManager, an `<InitCmd>`) makes that device unreadable ([`EsiFile::unreadable`], with
//!   why); the file's other devices are read;
//! - anything else that does not read (a default that is not hex data, an access keyword the
//!   schema does not have, an object whose index does not read, a DC mode without
//!   `AssignActivate`) is left out with a warning ([`EsiFile::warnings`]);
//! - values are decoded as vendors mean them: `#x80000000` for an INTEGER32 is the bit
//!   pattern (its minimum), `DefaultData` shorter than its type is its low bytes, byte arrays
//!   (`ARRAY [0..511] OF BYTE`) are one byte-string entry, not 512 sub-indices
//!   ([`ResolvedObject::problems`] notes each);
//! - only malformed XML, a root that is not `<EtherCATInfo>`, a missing `<Vendor><Id>`, text
//!   over [`MAX_TEXT_BYTES`] or elements nested deeper than [`MAX_DEPTH`] make the whole file
//!   an [`EsiError`]. Nothing in this module panics on any input.

mod check;
mod convert;
mod dictionary;
mod drive_plan;
mod error;
mod model;
mod num;
mod parse;

pub use check::{CheckIssue, Severity};
pub use convert::{EsiConvertError, pdo_entry_type, static_dictionary};
pub use dictionary::{
    ArrayInfo, Category, Dictionary, EsiDataType, EsiObject, EsiSubItem, EsiValue, Flags,
    ObjectDiff, ObjectInfo, ResolvedEntry, ResolvedObject,
};
pub use drive_plan::{
    CYCLIC_MODES, CyclicModeRef, DcPlan, DirectionChoice, DrivePlan, InitCmdPlan, MappingSource,
    ModeMapping, mapping_for, required_objects,
};
pub use error::{EsiError, EsiErrorKind, Position};
pub use model::{
    CoeDetails, CycleTimes, DcOpMode, DcSm, Device, DeviceChoice, DeviceType, Eeprom,
    EepromCategory, EsiFile, EsiPdo, EsiPdoEntry, Fmmu, FmmuUsage, Group, InitCmd, LCID_ENGLISH,
    LocalizedText, Mailbox, MailboxProtocols, OpMode, Profile, SmKind, SyncManager, Transition,
    UnreadableDevice, Vendor, preferred_text,
};
pub use parse::{ECDRIVE_NAMESPACE, MAX_DEPTH, MAX_TEXT_BYTES};

use std::path::Path;

impl EsiFile {
    /// Parse ESI text.
    pub fn parse(text: &str) -> Result<Self, EsiError> {
        parse::parse_str(text.strip_prefix('\u{feff}').unwrap_or(text))
    }

    /// Parse the bytes of an ESI file: UTF-8 (with or without byte-order mark), UTF-16 with a
    /// byte-order mark, or ISO-8859-1 when the bytes are not UTF-8 and the XML declaration
    /// names that encoding (as many vendor files do).
    pub fn parse_bytes(bytes: &[u8]) -> Result<Self, EsiError> {
        let text = parse::decode_bytes(bytes)?;
        Self::parse(&text)
    }

    /// Read and parse an ESI file. Errors name the file.
    pub fn from_path(path: impl AsRef<Path>) -> Result<Self, EsiError> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|e| {
            EsiError::new(
                EsiErrorKind::Io,
                Position::default(),
                format!("cannot read: {e}"),
            )
            .with_path(path)
        })?;
        let mut f = Self::parse_bytes(&bytes).map_err(|e| e.with_path(path))?;
        for u in &mut f.unreadable {
            u.error.path = Some(path.to_path_buf());
        }
        for w in &mut f.warnings {
            w.path = Some(path.to_path_buf());
        }
        Ok(f)
    }
}
