//! The PDO configuration of a CANopen drive: which RPDOs and TPDOs carry which objects, with
//! which transmission type, checked against the drive's rules, and the SDO sequence that
//! installs it.
//!
//! The sequence is the one all three manuals give (BLV-R §4.7.1, Lexium §8.5.19; the ASDA-A2
//! defers to CiA 301), in Pre-operational, for each PDO:
//!
//! 1. COB-ID (14xxh/18xxh:01) with bit 31 = 1: PDO invalid;
//! 2. mapping (16xxh/1Axxh) sub 00h = 0;
//! 3. the entries, sub 01h…n (`index << 16 | sub << 8 | bits`);
//! 4. sub 00h = n;
//! 5. transmission type (sub 02h), and for TPDOs inhibit time (03h) and event timer (05h) —
//!    while invalid, because the BLV-R refuses an inhibit-time change on a valid PDO;
//! 6. COB-ID with bit 31 = 0: valid.
//!
//! PDOs the plan does not use are made invalid, so every default (BLV-R TPDO3/4 on SYNC, Lexium
//! PDO1 only, ASDA-A2 type 0 everywhere) is overwritten: the master always writes the full
//! configuration.

use super::frame::cob;
use super::profile::{CanDriveProfile, TransmissionTypes};
use crate::od::{DataType, Dictionary, EntryAccess, ObjectAddress};
use crate::pdo::{Direction, Mapping, MappingError, Pdo, PdoEntry};

/// One PDO of a plan.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CanPdo {
    /// PDO number 1–4.
    pub number: u8,
    /// COB-ID; `None` = the pre-defined one (e.g. 180h + node for TPDO1).
    pub cob_id: Option<u16>,
    /// Transmission type (sub 02h).
    pub transmission_type: u8,
    /// Inhibit time, × 100 µs (TPDOs).
    pub inhibit_time: u16,
    /// Event timer, ms (TPDOs).
    pub event_timer: u16,
    /// Mapped entries, in order.
    pub entries: Vec<PdoEntry>,
    /// The drive's own mapping, used as it is: its mapping object cannot be written (an EDS
    /// file that makes 16xxh/1Axxh read-only, as Faulhaber's and Animatics' do).
    pub fixed: bool,
}

impl CanPdo {
    /// Size in bytes.
    pub fn bytes(&self) -> usize {
        self.entries
            .iter()
            .map(|e| usize::from(e.bits))
            .sum::<usize>()
            .div_ceil(8)
    }

    /// The COB-ID for `node` in direction `dir`.
    pub fn cob_for(&self, dir: Direction, node: u8) -> u16 {
        self.cob_id.unwrap_or(match dir {
            Direction::Rx => cob::rpdo(self.number, node),
            Direction::Tx => cob::tpdo(self.number, node),
        })
    }
}

/// The RPDOs (master → drive) and TPDOs (drive → master) of one drive, and the cyclic
/// objects no PDO of the drive can carry, which go by SDO.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct PdoPlan {
    /// RPDOs.
    pub rpdos: Vec<CanPdo>,
    /// TPDOs.
    pub tpdos: Vec<CanPdo>,
    /// Outputs no RPDO carries (6060h not mappable, a drive with fixed RPDOs or none): written
    /// by SDO when they change, the controlword last.
    pub sdo_out: Vec<PdoEntry>,
    /// Inputs no TPDO carries: read by SDO every cycle.
    pub sdo_in: Vec<PdoEntry>,
}

/// **\[REC\]** The cyclic objects the master carries by SDO when no PDO of the drive can:
/// those the CiA 402 engine cannot run without (outputs, inputs). 603Fh and the ip record are
/// left out (optional).
const BY_SDO_RX: [u16; 5] = [0x6060, 0x607A, 0x60FF, 0x6071, 0x6040];
/// See [`BY_SDO_RX`].
const BY_SDO_TX: [u16; 6] = [0x6041, 0x6061, 0x6064, 0x6063, 0x606C, 0x6077];

/// The pseudo mapping objects under which the SDO-carried objects sit in the process image
/// (after the PDOs; never written to the drive).
pub const SDO_IMAGE_RX: u16 = 0x17FF;
/// See [`SDO_IMAGE_RX`].
pub const SDO_IMAGE_TX: u16 = 0x1BFF;

/// A plan the drive would refuse; each message names the drive, the PDO and the rule.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PdoPlanError {
    /// PDO number outside 1–4.
    #[error("{dir} number {number} does not exist on the {drive} (PDOs 1–4)")]
    BadNumber {
        /// Drive.
        drive: &'static str,
        /// Direction.
        dir: Direction,
        /// Number.
        number: u8,
    },
    /// The same PDO twice.
    #[error("{dir} {number} is listed twice")]
    Duplicate {
        /// Direction.
        dir: Direction,
        /// Number.
        number: u8,
    },
    /// More than 8 bytes.
    #[error("{dir} {number} carries {bytes} bytes; a CAN PDO on the {drive} carries at most {max}")]
    TooManyBytes {
        /// Drive.
        drive: &'static str,
        /// Direction.
        dir: Direction,
        /// Number.
        number: u8,
        /// Bytes mapped.
        bytes: usize,
        /// Limit.
        max: u8,
    },
    /// An entry that is not a whole number of bytes.
    #[error("{dir} {number}: entry 0x{:08X} is not a whole number of bytes", entry.to_u32())]
    NotBytes {
        /// Direction.
        dir: Direction,
        /// Number.
        number: u8,
        /// Entry.
        entry: PdoEntry,
    },
    /// A transmission type the drive refuses.
    #[error(
        "{dir} {number}: transmission type {ttype} is not accepted by the {drive} (it aborts \
         with 0609 0030h)"
    )]
    TransmissionType {
        /// Drive.
        drive: &'static str,
        /// Direction.
        dir: Direction,
        /// Number.
        number: u8,
        /// Type.
        ttype: u8,
    },
    /// A COB-ID that is not a valid 11-bit identifier.
    #[error("{dir} {number}: COB-ID 0x{cob:X} is not a valid 11-bit identifier (001h–7FFh)")]
    CobId {
        /// Direction.
        dir: Direction,
        /// Number.
        number: u8,
        /// COB-ID.
        cob: u16,
    },
    /// An empty PDO (leave it out of the plan instead).
    #[error("{dir} {number} maps nothing; leave it out of the plan to disable it")]
    Empty {
        /// Direction.
        dir: Direction,
        /// Number.
        number: u8,
    },
    /// The generic mapping rules (entries per PDO, mappability, lengths).
    #[error(transparent)]
    Mapping(#[from] MappingError),
}

/// One SDO write of the configuration sequence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PdoWrite {
    /// Object.
    pub addr: ObjectAddress,
    /// Value.
    pub value: u32,
    /// Its type (UNSIGNED8/16/32).
    pub data_type: DataType,
    /// What the step does, for messages.
    pub what: &'static str,
}

impl PdoWrite {
    /// The little-endian bytes of the value in its type.
    pub fn bytes(&self) -> Vec<u8> {
        let n = usize::from(self.data_type.bit_len().unwrap_or(32) / 8);
        self.value.to_le_bytes().get(..n).unwrap_or(&[]).to_vec()
    }
}

const fn comm_index(dir: Direction, number: u8) -> u16 {
    match dir {
        Direction::Rx => 0x1400 + number as u16 - 1,
        Direction::Tx => 0x1800 + number as u16 - 1,
    }
}

const fn map_index(dir: Direction, number: u8) -> u16 {
    match dir {
        Direction::Rx => 0x1600 + number as u16 - 1,
        Direction::Tx => 0x1A00 + number as u16 - 1,
    }
}

/// **\[REC\]** Objects the standard plan maps, in order, if the drive has them mappable:
/// controlword, mode, the three targets and the ip data record (RPDOs); statusword, mode
/// display, position, velocity, torque and error code (TPDOs).
pub const STANDARD_RX: &[PdoEntry] = &[
    PdoEntry::new(0x6040, 0, 16),
    PdoEntry::new(0x6060, 0, 8),
    PdoEntry::new(0x607A, 0, 32),
    PdoEntry::new(0x60FF, 0, 32),
    PdoEntry::new(0x6071, 0, 16),
    PdoEntry::new(0x60C1, 1, 32),
];

/// See [`STANDARD_RX`].
pub const STANDARD_TX: &[PdoEntry] = &[
    PdoEntry::new(0x6041, 0, 16),
    PdoEntry::new(0x6061, 0, 8),
    PdoEntry::new(0x6064, 0, 32),
    PdoEntry::new(0x606C, 0, 32),
    PdoEntry::new(0x6077, 0, 16),
    PdoEntry::new(0x603F, 0, 16),
];

/// What the engine needs (`wanted`, of the candidates `list`) and no PDO of `pdos` carries: by
/// SDO, where the dictionary has the object with its size and lets the master write it
/// (`outputs`) or read it; taken off `left_out`.
fn by_sdo(
    dict: &Dictionary<'_>,
    list: &[PdoEntry],
    wanted: &[u16],
    pdos: &[CanPdo],
    outputs: bool,
    left_out: &mut Vec<PdoEntry>,
) -> Vec<PdoEntry> {
    let mut out = Vec::new();
    for index in wanted {
        let Some(e) = list.iter().find(|e| e.index == *index) else {
            continue;
        };
        let mapped = pdos.iter().any(|p| p.entries.contains(e));
        let usable = dict.entry(e.address()).is_some_and(|d| {
            d.bit_len == u16::from(e.bits)
                && if outputs {
                    d.access.writable()
                } else {
                    d.access.readable()
                }
        });
        if !mapped && usable {
            out.push(*e);
            left_out.retain(|x| x != e);
        }
    }
    out
}

fn pick_type(t: &TransmissionTypes, prefs: &[u8]) -> u8 {
    prefs.iter().copied().find(|p| t.allows(*p)).unwrap_or(255)
}

impl PdoPlan {
    /// The standard plan for `profile`: the objects of [`STANDARD_RX`]/[`STANDARD_TX`] the
    /// dictionary has mappable (6071h only with tq, 60C1h:01 only with ip), packed in order into
    /// as few PDOs as the drive's entry limit and 8 bytes allow. RPDOs use transmission type 0
    /// (applied at the next SYNC, so a controlword and its target take effect together), TPDOs
    /// type 1 (sent at every SYNC). Inhibit times and event timers 0.
    pub fn standard(profile: &CanDriveProfile) -> Self {
        Self::packed(profile, STANDARD_RX, STANDARD_TX).0
    }

    /// The standard plan plus the touch probe's objects for `probes` (probe number and edge,
    /// as a program arms them: [`ecdrive_motion::program::probes_used`]): 60B8h in an RPDO,
    /// 60B9h and each probe's latch (60BAh–60BDh) in the TPDOs. An error names what the
    /// drive's PDOs cannot carry (no such mappable object, or more than its four PDOs of eight
    /// bytes).
    pub fn with_probes(
        profile: &CanDriveProfile,
        probes: &[(u8, ecdrive_motion::ProbeEdge)],
    ) -> Result<Self, String> {
        if probes.is_empty() {
            return Ok(Self::standard(profile));
        }
        let mut rx = STANDARD_RX.to_vec();
        let mut tx = STANDARD_TX.to_vec();
        rx.push(PdoEntry::new(0x60B8, 0, 16));
        tx.push(PdoEntry::new(0x60B9, 0, 16));
        for &(probe, edge) in probes {
            let rising = edge == ecdrive_motion::ProbeEdge::Rising;
            let index = match (probe, rising) {
                (1, true) => 0x60BA,
                (1, false) => 0x60BB,
                (2, true) => 0x60BC,
                _ => 0x60BD,
            };
            let e = PdoEntry::new(index, 0, 32);
            if !tx.contains(&e) {
                tx.push(e);
            }
        }
        let (plan, left_out) = Self::packed(profile, &rx, &tx);
        let wanted = |e: &PdoEntry| matches!(e.index, 0x60B8..=0x60BD);
        match left_out.iter().find(|e| wanted(e)) {
            None => Ok(plan),
            Some(e) => Err(format!(
                "the {}'s PDOs cannot carry {:04X}h:{:02X} for the touch probe (not mappable, or \
                 more than its 4 PDOs of {} bytes per direction)",
                profile.name, e.index, e.sub, profile.pdo.max_pdo_bytes
            )),
        }
    }

    /// `rx`/`tx` packed in order into as few PDOs as the drive allows (see
    /// [`PdoPlan::standard`]), with the entries left out (not mappable here, or no room). A
    /// PDO whose mapping the drive fixes is used as it is where it carries a wanted object;
    /// the rest go into the PDOs the drive lets the master map; what still has no place and
    /// the engine needs ([`BY_SDO_RX`], [`BY_SDO_TX`]) goes by SDO.
    fn packed(
        profile: &CanDriveProfile,
        rx: &[PdoEntry],
        tx: &[PdoEntry],
    ) -> (Self, Vec<PdoEntry>) {
        let dict = Dictionary::new(profile.dictionary);
        let tq = profile.supports(crate::cia402::OperationMode::ProfileTorque);
        let ip = profile.supports(crate::cia402::OperationMode::InterpolatedPosition);
        // A drive without 6064h reports its position as 6063h (internal increments).
        let tx: Vec<PdoEntry> = tx
            .iter()
            .map(|e| {
                if e.index == 0x6064
                    && dict.object(0x6064).is_none()
                    && dict.object(0x6063).is_some()
                {
                    PdoEntry::new(0x6063, 0, 32)
                } else {
                    *e
                }
            })
            .collect();
        let tx = tx.as_slice();
        // The object exists with this size and the drive's modes use it.
        let exists = |e: &PdoEntry| {
            if (e.index == 0x6071 && !tq) || (e.index == 0x60C1 && !ip) {
                return false;
            }
            dict.entry(e.address())
                .is_some_and(|d| d.bit_len == u16::from(e.bits))
        };
        let usable = |e: &PdoEntry, flag: EntryAccess| {
            exists(e)
                && dict
                    .entry(e.address())
                    .is_some_and(|d| d.access.contains(flag))
        };
        let mut left_out = Vec::new();
        let mut pack = |cands: &[PdoEntry], flag: EntryAccess, dir: Direction, ttype: u8| {
            let limits = profile.pdo.limits.direction(dir);
            let defaults = match dir {
                Direction::Rx => profile.pdo.default_rpdos,
                Direction::Tx => profile.pdo.default_tpdos,
            };
            let mut out: Vec<CanPdo> = Vec::new();
            // The drive's fixed PDOs that carry something wanted, as they are.
            for number in 1..=4u8 {
                let fixed = limits
                    .range_of(map_index(dir, number))
                    .is_some_and(|r| !r.mapping_writable);
                let Some(d) = defaults.iter().find(|d| d.number == number) else {
                    continue;
                };
                if fixed && d.mapping.iter().any(|e| cands.contains(e) && exists(e)) {
                    out.push(CanPdo {
                        number,
                        cob_id: None,
                        transmission_type: ttype,
                        inhibit_time: 0,
                        event_timer: 0,
                        entries: d.mapping.to_vec(),
                        fixed: true,
                    });
                }
            }
            let carried: Vec<PdoEntry> = out.iter().flat_map(|p| p.entries.clone()).collect();
            let free: Vec<u8> = (1..=4u8)
                .filter(|n| {
                    limits
                        .range_of(map_index(dir, *n))
                        .is_some_and(|r| r.mapping_writable)
                })
                .collect();
            let mut current: Option<usize> = None;
            let mut next_free = 0usize;
            for e in cands {
                if carried.contains(e) {
                    continue;
                }
                if !usable(e, flag) {
                    left_out.push(*e);
                    continue;
                }
                let fits = current.and_then(|i| out.get(i)).is_some_and(|p| {
                    let max_entries = limits
                        .range_of(map_index(dir, p.number))
                        .map_or(0, |r| usize::from(r.max_entries));
                    p.entries.len() < max_entries
                        && p.bytes() * 8 + usize::from(e.bits)
                            <= usize::from(profile.pdo.max_pdo_bytes) * 8
                });
                if !fits {
                    // At most four PDOs, and only those the drive lets the master map.
                    let Some(&number) = free.get(next_free) else {
                        left_out.push(*e);
                        continue;
                    };
                    next_free += 1;
                    out.push(CanPdo {
                        number,
                        cob_id: None,
                        transmission_type: ttype,
                        inhibit_time: 0,
                        event_timer: 0,
                        entries: Vec::new(),
                        fixed: false,
                    });
                    current = Some(out.len() - 1);
                }
                if let Some(p) = current.and_then(|i| out.get_mut(i)) {
                    p.entries.push(*e);
                }
            }
            out.sort_by_key(|p| p.number);
            out
        };
        let rt = pick_type(&profile.pdo.rpdo_types, &[0, 1, 255]);
        let tt = pick_type(&profile.pdo.tpdo_types, &[1, 0, 255]);
        let rpdos = pack(rx, EntryAccess::RXPDO, Direction::Rx, rt);
        let tpdos = pack(tx, EntryAccess::TXPDO, Direction::Tx, tt);
        // What the engine needs and no PDO carries: by SDO (of what the drive's modes use).
        let used = |l: &[PdoEntry]| l.iter().copied().filter(|e| exists(e)).collect::<Vec<_>>();
        let sdo_out = by_sdo(&dict, &used(rx), &BY_SDO_RX, &rpdos, true, &mut left_out);
        let sdo_in = by_sdo(&dict, &used(tx), &BY_SDO_TX, &tpdos, false, &mut left_out);
        (
            Self {
                rpdos,
                tpdos,
                sdo_out,
                sdo_in,
            },
            left_out,
        )
    }

    /// The PDOs of one direction.
    pub fn pdos(&self, dir: Direction) -> &[CanPdo] {
        match dir {
            Direction::Rx => &self.rpdos,
            Direction::Tx => &self.tpdos,
        }
    }

    /// The process image of a drive with this plan: the PDOs' [`PdoPlan::mapping`], then the
    /// objects carried by SDO under [`SDO_IMAGE_RX`]/[`SDO_IMAGE_TX`], for
    /// [`crate::pdo::Layout`].
    pub fn image_mapping(&self) -> Mapping {
        let m = self.mapping();
        let mut rx: Vec<Pdo> = m.pdos(Direction::Rx).to_vec();
        let mut tx: Vec<Pdo> = m.pdos(Direction::Tx).to_vec();
        if !self.sdo_out.is_empty() {
            rx.push(Pdo::owned(SDO_IMAGE_RX, self.sdo_out.clone()));
        }
        if !self.sdo_in.is_empty() {
            tx.push(Pdo::owned(SDO_IMAGE_TX, self.sdo_in.clone()));
        }
        Mapping::owned(rx, tx)
    }

    /// The plan as a generic [`Mapping`] (mapping objects 0x16xx/0x1Axx in PDO-number order),
    /// for [`crate::pdo::Layout`] and [`crate::pdo::validate`].
    pub fn mapping(&self) -> Mapping {
        let conv = |dir: Direction, v: &[CanPdo]| {
            let mut v: Vec<&CanPdo> = v.iter().collect();
            v.sort_by_key(|p| p.number);
            v.into_iter()
                .map(|p| Pdo::owned(map_index(dir, p.number.clamp(1, 0xFF)), p.entries.clone()))
                .collect::<Vec<_>>()
        };
        Mapping::owned(
            conv(Direction::Rx, &self.rpdos),
            conv(Direction::Tx, &self.tpdos),
        )
    }

    /// Check the plan against the drive: numbers 1–4 once each, whole bytes, at most
    /// `max_pdo_bytes` per PDO, accepted transmission types, valid COB-IDs, and the generic rules
    /// (entries per PDO, every object present, mappable in its direction, mapped with its own
    /// length) of [`crate::pdo::validate`].
    pub fn validate(&self, profile: &CanDriveProfile) -> Result<(), PdoPlanError> {
        let drive = profile.name;
        for dir in Direction::ALL {
            let types = match dir {
                Direction::Rx => &profile.pdo.rpdo_types,
                Direction::Tx => &profile.pdo.tpdo_types,
            };
            let pdos = self.pdos(dir);
            for (i, p) in pdos.iter().enumerate() {
                let number = p.number;
                if !(1..=4).contains(&number) {
                    return Err(PdoPlanError::BadNumber { drive, dir, number });
                }
                if pdos.iter().take(i).any(|q| q.number == number) {
                    return Err(PdoPlanError::Duplicate { dir, number });
                }
                if p.entries.is_empty() {
                    return Err(PdoPlanError::Empty { dir, number });
                }
                if let Some(e) = p.entries.iter().find(|e| e.bits % 8 != 0 || e.bits == 0) {
                    return Err(PdoPlanError::NotBytes {
                        dir,
                        number,
                        entry: *e,
                    });
                }
                let bytes = p.bytes();
                if bytes > usize::from(profile.pdo.max_pdo_bytes) {
                    return Err(PdoPlanError::TooManyBytes {
                        drive,
                        dir,
                        number,
                        bytes,
                        max: profile.pdo.max_pdo_bytes,
                    });
                }
                if !types.allows(p.transmission_type) {
                    return Err(PdoPlanError::TransmissionType {
                        drive,
                        dir,
                        number,
                        ttype: p.transmission_type,
                    });
                }
                if let Some(c) = p.cob_id
                    && (c == 0 || c > 0x7FF)
                {
                    return Err(PdoPlanError::CobId {
                        dir,
                        number,
                        cob: c,
                    });
                }
            }
        }
        // The drive's fixed PDOs are its own: the generic rules apply to what the master maps.
        let mapped = PdoPlan {
            rpdos: self.rpdos.iter().filter(|p| !p.fixed).cloned().collect(),
            tpdos: self.tpdos.iter().filter(|p| !p.fixed).cloned().collect(),
            ..PdoPlan::default()
        };
        crate::pdo::validate(
            &mapped.mapping(),
            &profile.pdo.limits,
            Some(profile.dictionary),
        )?;
        Ok(())
    }

    /// The SDO writes that install the plan on node `node` (see the [module
    /// documentation](self)); PDOs not in the plan are made invalid. Validate first.
    pub fn writes(&self, profile: &CanDriveProfile, node: u8) -> Vec<PdoWrite> {
        let mut out = Vec::new();
        // A drive with fewer than four PDOs (as its EDS file says), a TPDO record without
        // inhibit time or event timer, a COB-ID or transmission type the file makes
        // read-only: what the drive does not have, or does not let the master write, is not
        // written.
        let dict = Dictionary::new(profile.dictionary);
        let has = |addr: ObjectAddress| dict.entry(addr).is_some_and(|e| e.access.writable());
        for dir in Direction::ALL {
            let defaults = match dir {
                Direction::Rx => profile.pdo.default_rpdos,
                Direction::Tx => profile.pdo.default_tpdos,
            };
            for number in 1..=4u8 {
                let comm = comm_index(dir, number);
                let map = map_index(dir, number);
                let no_rtr = if dir == Direction::Tx { 0x4000_0000 } else { 0 };
                let w =
                    |addr: ObjectAddress, value: u32, dt: DataType, what: &'static str| PdoWrite {
                        addr,
                        value,
                        data_type: dt,
                        what,
                    };
                match self.pdos(dir).iter().find(|p| p.number == number) {
                    None if !has(ObjectAddress::new(comm, 1)) => {}
                    None => {
                        let default_cob = defaults
                            .iter()
                            .find(|d| d.number == number)
                            .map(|d| (d.cob_id & 0x7FF) as u16 + u16::from(node))
                            .unwrap_or(match dir {
                                Direction::Rx => cob::rpdo(number, node),
                                Direction::Tx => cob::tpdo(number, node),
                            });
                        out.push(w(
                            ObjectAddress::new(comm, 1),
                            0x8000_0000 | no_rtr | u32::from(default_cob),
                            DataType::Unsigned32,
                            "disable the unused PDO",
                        ));
                    }
                    Some(p) => {
                        let c = u32::from(p.cob_for(dir, node));
                        let cob_writable = has(ObjectAddress::new(comm, 1));
                        if cob_writable {
                            out.push(w(
                                ObjectAddress::new(comm, 1),
                                0x8000_0000 | no_rtr | c,
                                DataType::Unsigned32,
                                "invalidate the PDO (COB-ID bit 31)",
                            ));
                        }
                        if !p.fixed {
                            out.push(w(
                                ObjectAddress::new(map, 0),
                                0,
                                DataType::Unsigned8,
                                "clear the mapping",
                            ));
                            for (k, e) in p.entries.iter().enumerate() {
                                out.push(w(
                                    ObjectAddress::new(map, (k + 1) as u8),
                                    e.to_u32(),
                                    DataType::Unsigned32,
                                    "map an object",
                                ));
                            }
                            out.push(w(
                                ObjectAddress::new(map, 0),
                                p.entries.len() as u32,
                                DataType::Unsigned8,
                                "set the number of mapped objects",
                            ));
                        }
                        if has(ObjectAddress::new(comm, 2)) {
                            out.push(w(
                                ObjectAddress::new(comm, 2),
                                u32::from(p.transmission_type),
                                DataType::Unsigned8,
                                "set the transmission type",
                            ));
                        }
                        if dir == Direction::Tx && has(ObjectAddress::new(comm, 3)) {
                            out.push(w(
                                ObjectAddress::new(comm, 3),
                                u32::from(p.inhibit_time),
                                DataType::Unsigned16,
                                "set the inhibit time",
                            ));
                        }
                        if dir == Direction::Tx && has(ObjectAddress::new(comm, 5)) {
                            out.push(w(
                                ObjectAddress::new(comm, 5),
                                u32::from(p.event_timer),
                                DataType::Unsigned16,
                                "set the event timer",
                            ));
                        }
                        if cob_writable {
                            out.push(w(
                                ObjectAddress::new(comm, 1),
                                no_rtr | c,
                                DataType::Unsigned32,
                                "validate the PDO",
                            ));
                        }
                    }
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drives::{asda_a2, blv_r, lexium_mdrive};

    #[test]
    fn standard_plans_fit_every_drive() {
        for p in [
            &blv_r::PROFILE,
            &asda_a2::PROFILE,
            &lexium_mdrive::PROFILE,
            &lexium_mdrive::PROFILE_CLOSED_LOOP,
        ] {
            let plan = PdoPlan::standard(p);
            assert_eq!(plan.validate(p), Ok(()), "{}", p.name);
            let m = plan.mapping();
            for a in [0x6040u16, 0x6060, 0x607A, 0x60FF] {
                assert!(
                    m.contains(Direction::Rx, ObjectAddress::new(a, 0)),
                    "{} {a:04X}",
                    p.name
                );
            }
            for a in [0x6041u16, 0x6061, 0x6064, 0x606C] {
                assert!(
                    m.contains(Direction::Tx, ObjectAddress::new(a, 0)),
                    "{} {a:04X}",
                    p.name
                );
            }
        }
        let blv = PdoPlan::standard(&blv_r::PROFILE);
        assert!(blv.rpdos.iter().all(|p| p.entries.len() <= 4));
        assert!(blv.rpdos.iter().all(|p| p.transmission_type == 0));
        let delta = PdoPlan::standard(&asda_a2::PROFILE);
        assert!(
            delta
                .mapping()
                .contains(Direction::Rx, ObjectAddress::new(0x60C1, 1))
        );
        let lex = PdoPlan::standard(&lexium_mdrive::PROFILE);
        assert!(
            !lex.mapping()
                .contains(Direction::Rx, ObjectAddress::new(0x6071, 0))
        );
    }

    #[test]
    fn refusals_name_the_rule() {
        let mut plan = PdoPlan::standard(&blv_r::PROFILE);
        plan.rpdos[0].transmission_type = 1;
        let e = plan.validate(&blv_r::PROFILE).unwrap_err();
        assert!(
            matches!(e, PdoPlanError::TransmissionType { ttype: 1, .. }),
            "{e}"
        );
        assert!(e.to_string().contains("BLV-R"));
        let mut plan = PdoPlan::standard(&blv_r::PROFILE);
        plan.tpdos[0].entries = vec![
            PdoEntry::new(0x6041, 0, 16),
            PdoEntry::new(0x6061, 0, 8),
            PdoEntry::new(0x603F, 0, 16),
            PdoEntry::new(0x6077, 0, 16),
            PdoEntry::new(0x6061, 0, 8),
        ];
        let e = plan.validate(&blv_r::PROFILE).unwrap_err();
        assert!(
            matches!(
                e,
                PdoPlanError::Mapping(MappingError::TooManyEntriesInPdo { max: 4, .. })
            ),
            "{e}"
        );
        let mut plan = PdoPlan::standard(&asda_a2::PROFILE);
        plan.rpdos[0].entries.push(PdoEntry::new(0x60FF, 0, 32));
        plan.rpdos[0].entries.push(PdoEntry::new(0x60FF, 0, 32));
        let e = plan.validate(&asda_a2::PROFILE).unwrap_err();
        assert!(
            matches!(e, PdoPlanError::TooManyBytes { max: 8, .. }),
            "{e}"
        );
        let mut plan = PdoPlan::standard(&lexium_mdrive::PROFILE);
        plan.tpdos[0].entries = vec![PdoEntry::new(0x6041, 0, 16), PdoEntry::new(0x6040, 0, 16)];
        let e = plan.validate(&lexium_mdrive::PROFILE).unwrap_err();
        assert!(
            matches!(e, PdoPlanError::Mapping(MappingError::NotMappable { .. })),
            "{e}"
        );
    }

    #[test]
    fn write_sequence_follows_the_manuals() {
        let plan = PdoPlan::standard(&blv_r::PROFILE);
        let w = plan.writes(&blv_r::PROFILE, 5);
        // RPDO1: invalidate, clear, entries, count, type, validate.
        assert_eq!(w[0].addr, ObjectAddress::new(0x1400, 1));
        assert_eq!(w[0].value, 0x8000_0205);
        assert_eq!((w[1].addr, w[1].value), (ObjectAddress::new(0x1600, 0), 0));
        assert_eq!(w[2].value, 0x6040_0010);
        let valid = w
            .iter()
            .position(|x| x.addr == ObjectAddress::new(0x1400, 1) && x.value == 0x205);
        assert!(valid.is_some());
        // Unused RPDO4 is disabled.
        assert!(
            w.iter()
                .any(|x| x.addr == ObjectAddress::new(0x1403, 1) && x.value == 0x8000_0505)
        );
        // TPDOs get bit 30 (no RTR) and an inhibit time written while invalid.
        let inhibit = w
            .iter()
            .position(|x| x.addr == ObjectAddress::new(0x1800, 3))
            .unwrap();
        let valid_t = w
            .iter()
            .position(|x| x.addr == ObjectAddress::new(0x1800, 1) && x.value == 0x4000_0185)
            .unwrap();
        assert!(inhibit < valid_t);
        assert_eq!(w[1].bytes(), vec![0]);
        assert_eq!(w[0].bytes().len(), 4);
    }
}
