//! The configuration file as serde reads it: every table denies unknown keys, and the values
//! whose meaning is checked afterwards keep their position in the file ([`Spanned`]).

use crate::master::program::Step;
use serde::Deserialize;
use std::collections::BTreeMap;
use toml::Spanned;

/// The whole file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct File {
    pub interface: Spanned<String>,
    #[serde(default)]
    pub cycle: Option<Spanned<String>>,
    #[serde(default)]
    pub dc_shift: Option<Spanned<String>>,
    #[serde(default)]
    pub dc_start_delay: Option<Spanned<String>>,
    #[serde(default)]
    pub duration: Option<Spanned<String>>,
    #[serde(default)]
    pub allow_generic: bool,
    #[serde(default)]
    pub reset_faults: bool,
    #[serde(default)]
    pub answer_rereads: Option<bool>,
    #[serde(default)]
    pub rt: Option<Rt>,
    #[serde(default)]
    pub supervision: Option<Supervision>,
    #[serde(default)]
    pub sim: Option<Spanned<Sim>>,
    #[serde(default)]
    pub drive: Vec<Spanned<Drive>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Rt {
    #[serde(default)]
    pub priority: Option<Spanned<u8>>,
    #[serde(default)]
    pub cpu: Option<Spanned<usize>>,
    #[serde(default)]
    pub lock_memory: bool,
    #[serde(default)]
    pub reply: Option<Spanned<String>>,
    #[serde(default)]
    pub frames: Option<Spanned<String>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Supervision {
    #[serde(default)]
    pub lost_cycles: Option<Spanned<u32>>,
    #[serde(default)]
    pub lost_before_stop: Option<Spanned<u32>>,
    #[serde(default)]
    pub wkc_errors: Option<Spanned<u32>>,
    #[serde(default)]
    pub safeop_cycles: Option<Spanned<u32>>,
    #[serde(default)]
    pub op_timeout: Option<Spanned<String>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Sim {
    pub devices: Vec<Spanned<String>>,
    #[serde(default)]
    pub sm_watchdog: Option<u16>,
    #[serde(default)]
    pub loss_detection: Option<bool>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Identity {
    pub vendor_id: u32,
    pub product_code: u32,
}

/// `esi = "FILE"`, or `esi = { file = "FILE", product = 0x…, revision = 0x… }` to choose one
/// device of a file that describes several.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub(super) enum EsiRef {
    /// The file.
    File(String),
    /// The file and the device's identity.
    Device {
        /// The file.
        file: String,
        /// Its `ProductCode`.
        product: u32,
        /// Its `RevisionNo` (any, when only one device has the product code).
        #[serde(default)]
        revision: Option<u32>,
    },
}

impl EsiRef {
    /// The file.
    pub fn file(&self) -> &str {
        match self {
            Self::File(f) | Self::Device { file: f, .. } => f,
        }
    }

    /// The device it names, if it names one.
    pub fn choice(&self) -> Option<crate::esi::DeviceChoice> {
        match self {
            Self::File(_) => None,
            Self::Device {
                product, revision, ..
            } => Some(crate::esi::DeviceChoice::Identity {
                product_code: *product,
                revision: *revision,
            }),
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Drive {
    #[serde(default)]
    pub node: Option<Spanned<u8>>,
    #[serde(default)]
    pub position: Option<Spanned<u16>>,
    #[serde(default)]
    pub alias: Option<Spanned<u16>>,
    #[serde(default)]
    pub identity: Option<Spanned<Identity>>,
    #[serde(default)]
    pub profile: Option<Spanned<String>>,
    #[serde(default)]
    pub esi: Option<Spanned<EsiRef>>,
    /// CANopen: the drive's EDS/DCF file (relative to the configuration file).
    #[serde(default)]
    pub eds: Option<Spanned<String>>,
    #[serde(default)]
    pub profile_file: Option<Spanned<String>>,
    #[serde(default)]
    pub mode: Option<Spanned<String>>,
    #[serde(default)]
    pub mapping: Option<Spanned<Mapping>>,
    #[serde(default)]
    pub sdos: Option<Spanned<BTreeMap<String, Spanned<toml::Value>>>>,
    #[serde(default)]
    pub limits: Option<Spanned<Limits>>,
    #[serde(default)]
    pub units: Option<Spanned<Units>>,
    /// The program, in the drive's user units: the motion runtime's own steps
    /// ([`Step::scaled`] takes them to counts).
    #[serde(default)]
    pub program: Vec<Spanned<Step>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Mapping {
    #[serde(default)]
    pub rx: Vec<Spanned<Pdo>>,
    #[serde(default)]
    pub tx: Vec<Spanned<Pdo>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Pdo {
    pub pdo: u16,
    /// `"0x6040:00"`, `{ object = "0x6040:00", bits = 16 }` or `{ padding = 8 }`.
    pub entries: Vec<Spanned<toml::Value>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Limits {
    #[serde(default)]
    pub following_error: Option<f64>,
    #[serde(default)]
    pub max_velocity: Option<f64>,
    #[serde(default)]
    pub max_acceleration: Option<f64>,
    #[serde(default)]
    pub max_torque: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Units {
    pub name: String,
    pub counts_per_unit: f64,
}
