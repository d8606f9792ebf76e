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
//! Numbers are read as ETG.2000 writes them: decimal, `#x` hex, and (tolerated) `0x` hex.
//! Unknown elements are ignored, since vendors add their own; a missing element the schema
//! requires or a value that is not allowed is an [`EsiError`] with line and column. Nothing in
//! this module panics on any input.

mod check;
mod convert;
mod dictionary;
mod drive_plan;
mod error;
mod model;
mod num;
mod parse;

pub use check::CheckIssue;
pub use convert::{EsiConvertError, static_dictionary};
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
    CoeDetails, CycleTimes, DcOpMode, DcSm, Device, DeviceType, Eeprom, EepromCategory, EsiFile,
    EsiPdo, EsiPdoEntry, Fmmu, FmmuUsage, Group, InitCmd, LCID_ENGLISH, LocalizedText, Mailbox,
    MailboxProtocols, OpMode, Profile, SmKind, SyncManager, Transition, Vendor, preferred_text,
};
pub use parse::ECDRIVE_NAMESPACE;

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
        Self::parse_bytes(&bytes).map_err(|e| e.with_path(path))
    }
}
