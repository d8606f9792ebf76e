//! Generative end-to-end tests: configurations and command sequences nobody wrote by hand,
//! run against the emulated devices in-process.
//!
//! Each case is a segment of 1–8 devices (the MR-J4-TM, the BDHDE, the generic CoE servo run
//! with the generic CiA 402 profile, the generic I/O device), each drive with a random PDO
//! mapping or its default, a start mode it supports, a cycle time every drive accepts,
//! foreign-device quirks, and a random command sequence (enable, disable, quick stop, mode
//! switches, a program, stop). The mappings follow the **manuals' PDO rules** as the fact
//! tables record them (`tests/manual_facts/*.toml`: the objects the manual marks PDO-mappable,
//! their data types, the entry and byte limits) — never the validator under test. The
//! configuration goes through the `ecdrive run` file parser, the run through the library. Each
//! case must reach OP, do what was asked and shut down with every drive disabled, and every
//! cycle is recorded to check **values**: a csp move ends within a few counts of its target, a
//! pp program's targets are reached, the commanded torque never exceeds the program's, and the
//! position demand never jumps (at a mode switch or anywhere else: no step beyond the
//! program's velocity). The drives' own supervision of the cyclic data is off and the master
//! holds its set-points over lost frames (up to 200 in a row) instead of stopping: a shared
//! test machine's stalls are not the subject.
//!
//! Reproducible: every run prints its seed (`ECDRIVE_SEED=N` replays it) and runs
//! `ECDRIVE_CASES` cases (default 64, about 20 s on two cores); a longer run:
//! `ECDRIVE_CASES=500 cargo test --release --test app generative::`. Shrunk failures are kept in
//! `tests/generative.proptest-regressions` and replayed first; the defects found have named
//! tests below.

use ecdrive::cia402::State;
use ecdrive::drives::DriveProfile;
use ecdrive::master::program::RunMode;
use ecdrive::master::session::Master;
use ecdrive::master::telemetry::{Axes, Command, EventKind, StopKind, Telemetry};
use ecdrive::pdo::{Direction, Mapping, Pdo, PdoEntry};
use proptest::prelude::*;
use proptest::test_runner::{Config, FileFailurePersistence, TestCaseError};
use std::time::Duration;

/// One at a time: every case runs its own cycle thread.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    MrJ4,
    Bdhde,
    GenericCoe,
    GenericIo,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::MrJ4 => "mr-j4-tm",
            Kind::Bdhde => "bdhde",
            Kind::GenericCoe => "generic-coe",
            Kind::GenericIo => "generic-io",
        }
    }

    fn profile(self) -> Option<&'static DriveProfile> {
        match self {
            Kind::MrJ4 => ecdrive::drives::by_key("mr-j4-tm"),
            Kind::Bdhde => ecdrive::drives::by_key("bdhde"),
            _ => None,
        }
    }

    fn is_drive(self) -> bool {
        self != Kind::GenericIo
    }

    /// Modes the device supports (the generic CoE servo: csp and csv).
    fn modes(self) -> &'static [RunMode] {
        match self {
            Kind::MrJ4 => &[RunMode::Csp, RunMode::Csv, RunMode::Cst],
            // The BDHDE runs every mode in one setting (the MR-J4-TM needs [Pr. PA01] = 2
            // for the profile modes, and then no cyclic one).
            Kind::Bdhde => &[
                RunMode::Csp,
                RunMode::Csv,
                RunMode::Cst,
                RunMode::Pp,
                RunMode::Pv,
                RunMode::Tq,
            ],
            Kind::GenericCoe => &[RunMode::Csp, RunMode::Csv],
            Kind::GenericIo => &[],
        }
    }

    /// Quirks that apply to it.
    fn quirks(self) -> &'static [&'static str] {
        match self {
            Kind::MrJ4 | Kind::Bdhde => &[
                "no-state-skipping",
                "cycle-time-read-only",
                "sync-objects-absent",
                "no-sdo-info",
                "no-complete-access",
                "odd-abort",
                "stale-inputs-until-op",
                "outputs-in-safeop",
                "following-error-zero",
            ],
            Kind::GenericCoe => &[
                "no-state-skipping",
                "cycle-time-read-only",
                "no-complete-access",
                "odd-abort",
                "stale-inputs-until-op",
                "outputs-in-safeop",
            ],
            Kind::GenericIo => &["stale-inputs-until-op", "outputs-in-safeop"],
        }
    }
}

/// One device of a case.
#[derive(Debug, Clone)]
struct Device {
    kind: Kind,
    quirks: Vec<&'static str>,
    mode: RunMode,
    /// A mapping override (profiled drives only).
    mapping: Option<Mapping>,
}

/// What the test does once every device is in OP.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Op {
    /// Enable every axis and wait for Operation enabled.
    Enable,
    /// Disable every axis and wait for it to be disabled.
    Disable,
    /// Quick stop every axis, wait until none is energised... then enable again.
    QuickStopThenEnable,
    /// Switch axis `n % axes` to its `m`-th mode that is mapped (while enabled).
    Mode(usize, usize),
    /// Run every axis's program and wait until it finished.
    Program,
}

#[derive(Debug, Clone)]
struct Case {
    devices: Vec<Device>,
    cycle_us: u32,
    ops: Vec<Op>,
}

const A: fn(u16, u8) -> ecdrive::od::ObjectAddress = ecdrive::od::ObjectAddress::new;

fn setpoint(m: RunMode) -> ecdrive::od::ObjectAddress {
    match m {
        RunMode::Csp | RunMode::Pp => A(0x607A, 0),
        RunMode::Csv | RunMode::Pv => A(0x60FF, 0),
        RunMode::Cst | RunMode::Tq => A(0x6071, 0),
        // Not generated: ip is a CANopen mode (an EtherCAT run refuses it).
        RunMode::Ip => A(0x60C1, 1),
    }
}

/// A drive's PDO rules as its manual states them (the fact table, written from the manual
/// only): the objects it marks PDO-mappable with their sizes — outputs the writable ones,
/// inputs the read-only ones — the first mapping object of each direction, and the limits
/// (entries per PDO; bytes where the manual gives them).
struct PdoRules {
    rx: Vec<PdoEntry>,
    tx: Vec<PdoEntry>,
    max_entries: (usize, usize),
    max_bytes: (Option<usize>, Option<usize>),
}

fn bits_of(data_type: &str) -> Option<u8> {
    match data_type {
        "BOOLEAN" | "INTEGER8" | "UNSIGNED8" => Some(8),
        "INTEGER16" | "UNSIGNED16" => Some(16),
        "INTEGER32" | "UNSIGNED32" => Some(32),
        _ => None,
    }
}

fn rules(kind: Kind) -> Option<&'static PdoRules> {
    static RULES: std::sync::OnceLock<Vec<(Kind, PdoRules)>> = std::sync::OnceLock::new();
    let all = RULES.get_or_init(|| {
        [Kind::MrJ4, Kind::Bdhde]
            .into_iter()
            .map(|k| (k, read_rules(k.name())))
            .collect()
    });
    all.iter().find(|(k, _)| *k == kind).map(|(_, r)| r)
}

fn read_rules(drive: &str) -> PdoRules {
    let path = format!(
        "{}/tests/manual_facts/{drive}.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let file: toml::Value = toml::from_str(&text).unwrap_or_else(|e| panic!("{path}: {e}"));
    let facts = file["fact"].as_array().expect("facts");
    let str_of = |f: &toml::Value, k: &str| f.get(k).and_then(|v| v.as_str()).map(String::from);
    let (mut rx, mut tx) = (Vec::new(), Vec::new());
    let mut r = PdoRules {
        rx: Vec::new(),
        tx: Vec::new(),
        max_entries: (usize::MAX, usize::MAX),
        max_bytes: (None, None),
    };
    for f in facts {
        match str_of(f, "kind").as_deref() {
            Some("object") if f.get("pdo_mappable").and_then(|v| v.as_bool()) == Some(true) => {
                let (Some(obj), Some(dt), Some(access)) = (
                    str_of(f, "object"),
                    str_of(f, "data_type"),
                    str_of(f, "access"),
                ) else {
                    continue;
                };
                let Some(bits) = bits_of(&dt) else { continue };
                let (i, s) = obj
                    .trim_start_matches("0x")
                    .split_once(':')
                    .expect("0xIIII:SS");
                let e = PdoEntry::new(
                    u16::from_str_radix(i, 16).expect("index"),
                    u8::from_str_radix(s, 16).expect("sub"),
                    bits,
                );
                match access.as_str() {
                    "rw" | "wo" => rx.push(e),
                    "ro" => tx.push(e),
                    _ => {}
                }
            }
            Some("pdo_limits") => {
                let n = |k: &str| f.get(k).and_then(|v| v.as_integer()).map(|v| v as usize);
                if let Some(v) = n("max_rx_entries") {
                    r.max_entries.0 = v;
                }
                if let Some(v) = n("max_tx_entries") {
                    r.max_entries.1 = v;
                }
                r.max_bytes.0 = n("max_rx_bytes").or(r.max_bytes.0);
                r.max_bytes.1 = n("max_tx_bytes").or(r.max_bytes.1);
            }
            _ => {}
        }
    }
    r.rx = rx;
    r.tx = tx;
    assert!(
        r.rx.len() > 5 && r.tx.len() > 5,
        "{drive}: the facts name few mappable objects"
    );
    r
}

/// A mapping by the manual's rules ([`PdoRules`]): the controlword and the set-points of
/// `modes` (and the mode object when there is more than one) first, the statusword and the
/// actual position, then `picks` from the rest of the manual's mappable objects in the order
/// given, with paddings; cut to the manual's limits, whole bytes. Into 0x1600 and 0x1A00.
fn mapping(
    kind: Kind,
    modes: &[RunMode],
    picks: (&[usize], &[usize]),
    pads: (Option<u8>, Option<u8>),
) -> Option<Mapping> {
    let r = rules(kind)?;
    let mut out = Vec::new();
    for (dir, must, pick, pad, mappable, max_entries, max_bytes) in [
        (
            Direction::Rx,
            {
                let mut v = vec![A(0x6040, 0)];
                // Each object once in the RxPDOs (pp and csp share 0x607A).
                for a in modes.iter().map(|m| setpoint(*m)) {
                    if !v.contains(&a) {
                        v.push(a);
                    }
                }
                if modes.len() > 1 {
                    v.push(A(0x6060, 0));
                }
                v
            },
            picks.0,
            pads.0,
            &r.rx,
            r.max_entries.0,
            r.max_bytes.0,
        ),
        (
            Direction::Tx,
            vec![A(0x6041, 0), A(0x6064, 0)],
            picks.1,
            pads.1,
            &r.tx,
            r.max_entries.1,
            r.max_bytes.1,
        ),
    ] {
        let entry = |a: ecdrive::od::ObjectAddress| {
            mappable
                .iter()
                .find(|e| e.index == a.index && e.sub == a.sub)
                .copied()
        };
        let mut entries: Vec<PdoEntry> = must.iter().map(|a| entry(*a)).collect::<Option<_>>()?;
        let rest: Vec<PdoEntry> = mappable
            .iter()
            .filter(|e| !entries.contains(e))
            .copied()
            .collect();
        for i in pick {
            if rest.is_empty() {
                break;
            }
            let e = rest[i % rest.len()];
            if !entries.contains(&e) {
                entries.push(e);
            }
        }
        if let Some(b) = pad {
            entries.insert(entries.len().min(2), PdoEntry::padding(b));
        }
        // The manual's limits: entries, then bytes (a padding counts as an entry).
        entries.truncate(max_entries.max(must.len()));
        let bits = |v: &[PdoEntry]| v.iter().map(|e| usize::from(e.bits)).sum::<usize>();
        while max_bytes.is_some_and(|b| bits(&entries).div_ceil(8) > b)
            && entries.len() > must.len()
        {
            entries.pop();
        }
        // Whole bytes per direction.
        if bits(&entries) % 8 != 0 {
            if entries.len() < max_entries {
                entries.push(PdoEntry::padding((8 - bits(&entries) % 8) as u8));
            } else {
                return None;
            }
        }
        let index = match dir {
            Direction::Rx => 0x1600,
            Direction::Tx => 0x1A00,
        };
        out.push(Pdo::owned(index, entries));
    }
    let tx = out.pop()?;
    let rx = out.pop()?;
    Some(Mapping::owned(vec![rx], vec![tx]))
}

fn device() -> impl Strategy<Value = Device> {
    (
        prop::sample::select(vec![
            Kind::MrJ4,
            Kind::Bdhde,
            Kind::GenericCoe,
            Kind::GenericIo,
        ]),
        any::<u16>(),
        any::<usize>(),
        prop::option::of((
            prop::collection::vec(any::<usize>(), 0..12),
            prop::collection::vec(any::<usize>(), 0..12),
            prop::option::of(prop::sample::select(vec![8u8, 16])),
            prop::option::of(prop::sample::select(vec![8u8, 16])),
            any::<bool>(),
        )),
    )
        .prop_map(|(kind, qbits, mode_pick, map)| {
            let quirks: Vec<&'static str> = kind
                .quirks()
                .iter()
                .enumerate()
                .filter(|(i, _)| qbits >> i & 1 == 1 && qbits >> 12 & 1 == 1)
                .map(|(_, q)| *q)
                .filter(|q| *q != "sync-objects-absent" || qbits >> 13 & 1 == 1)
                .collect();
            let quirks = if quirks.contains(&"sync-objects-absent") {
                quirks
                    .into_iter()
                    .filter(|q| *q != "cycle-time-read-only")
                    .collect()
            } else {
                quirks
            };
            let modes = kind.modes();
            let mode = modes
                .get(mode_pick % modes.len().max(1))
                .copied()
                .unwrap_or(RunMode::Csp);
            let mapping = match (rules(kind), map) {
                (Some(_), Some((rx, tx, prx, ptx, all_modes))) => {
                    let ms: Vec<RunMode> = if all_modes {
                        let mut v = vec![mode];
                        v.extend(modes.iter().filter(|m| **m != mode));
                        v
                    } else {
                        vec![mode]
                    };
                    mapping(kind, &ms, (&rx, &tx), (prx, ptx))
                }
                _ => None,
            };
            Device {
                kind,
                quirks,
                mode,
                mapping,
            }
        })
}

fn case() -> impl Strategy<Value = Case> {
    (
        prop::collection::vec(device(), 1..=8),
        prop::sample::select(vec![250u32, 500, 1000, 2000]),
        prop::collection::vec(
            prop_oneof![
                Just(Op::Disable),
                Just(Op::QuickStopThenEnable),
                (any::<usize>(), any::<usize>()).prop_map(|(a, m)| Op::Mode(a, m)),
                Just(Op::Program),
                Just(Op::Enable),
            ],
            0..5,
        ),
    )
        .prop_map(|(devices, cycle_us, mut ops)| {
            ops.insert(0, Op::Enable);
            Case {
                devices,
                cycle_us,
                ops,
            }
        })
}

/// The configuration file of a case.
fn toml(c: &Case) -> String {
    let names: Vec<String> = c
        .devices
        .iter()
        .map(|d| {
            let mut n = d.kind.name().to_string();
            for q in &d.quirks {
                n.push('+');
                n.push_str(q);
            }
            format!("{n:?}")
        })
        .collect();
    let mut t = format!(
        "interface = \"sim\"\ncycle = \"{}us\"\nallow_generic = true\n[sim]\ndevices = [{}]\nloss_detection = false\n",
        c.cycle_us,
        names.join(", ")
    );
    for (pos, d) in c.devices.iter().enumerate() {
        if !d.kind.is_drive() {
            continue;
        }
        t.push_str(&format!(
            "[[drive]]\nposition = {pos}\nmode = \"{}\"\n",
            d.mode.name()
        ));
        t.push_str(&format!("program = [{}]\n", program(d.mode)));
        if let Some(m) = &d.mapping {
            let side = |dir: Direction| {
                m.pdos(dir)
                    .iter()
                    .map(|p| {
                        let e: Vec<String> = p
                            .entries
                            .iter()
                            .map(|e| {
                                if e.is_padding() {
                                    format!("{{ padding = {} }}", e.bits)
                                } else {
                                    format!(
                                        "{{ object = \"0x{:04X}:{:02X}\", bits = {} }}",
                                        e.index, e.sub, e.bits
                                    )
                                }
                            })
                            .collect();
                        format!(
                            "{{ pdo = 0x{:04X}, entries = [{}] }}",
                            p.index,
                            e.join(", ")
                        )
                    })
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            t.push_str(&format!(
                "[drive.mapping]\nrx = [{}]\ntx = [{}]\n",
                side(Direction::Rx),
                side(Direction::Tx)
            ));
        }
    }
    t
}

/// A short program in the start mode.
fn program(m: RunMode) -> &'static str {
    match m {
        RunMode::Csp | RunMode::Ip => {
            "{ step = \"move\", by = 20000, velocity = 200000, acceleration = 4000000 }"
        }
        RunMode::Csv => "{ step = \"ramp\", velocity = 20000, acceleration = 400000, hold = 0.05 }",
        RunMode::Cst => "{ step = \"torque\", torque = 20, hold = 0.05 }",
        RunMode::Pp => {
            "{ step = \"pp\", by = [20000, -10000], velocity = 200000, acceleration = 4000000 }"
        }
        RunMode::Pv => "{ step = \"pv\", velocity = 20000, acceleration = 400000, seconds = 0.05 }",
        RunMode::Tq => "{ step = \"tq\", torque = 20, seconds = 0.05 }",
    }
}

fn all_axes(t: &Telemetry, f: impl Fn(Option<State>) -> bool) -> bool {
    t.axes.iter().all(|a| f(a.state))
}

fn check(
    m: &mut Master<impl ecdrive::link::FrameLink + Send + 'static>,
    what: &str,
    secs: u64,
    f: impl FnMut(&Telemetry) -> bool,
) -> Result<(), TestCaseError> {
    m.wait_until(what, Duration::from_secs(secs), f)
        .map_err(|e| TestCaseError::fail(format!("{e}\nhistory: {:#?}", m.history())))
}

/// A csp or pp program ends within this many counts of its target.
const POSITION_TOLERANCE: i64 = 20;
/// The programs' fastest velocity (counts/s) and largest torque (drive units), see [`program`].
const PROGRAM_VELOCITY: f64 = 200_000.0;
const PROGRAM_TORQUE: i16 = 20;
/// At the first cycle in csp after another mode, the demand starts this close to the actual
/// position (counts): a switch does not jump.
const SWITCH_TOLERANCE: i64 = 200;

/// Every recorded cycle of a case, drained by a thread of its own.
struct Recorder {
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    thread: std::thread::JoinHandle<(Vec<ecdrive::master::CycleSample>, u64)>,
}

impl Recorder {
    fn attach(cfg: &mut ecdrive::master::MasterConfig) -> Self {
        use std::sync::atomic::Ordering;
        let (tx, mut rx) = ecdrive::master::recording(1 << 16);
        cfg.record = Some(std::sync::Arc::new(std::sync::Mutex::new(tx)));
        let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let done = stop.clone();
        let thread = std::thread::spawn(move || {
            let mut all = Vec::new();
            loop {
                let last = done.load(Ordering::Acquire);
                rx.drain(|s| all.push(*s));
                if last {
                    return (all, rx.dropped());
                }
                std::thread::sleep(Duration::from_millis(5));
            }
        });
        Self { stop, thread }
    }

    /// The samples and how many were dropped (the cycle has ended).
    fn finish(self) -> (Vec<ecdrive::master::CycleSample>, u64) {
        self.stop.store(true, std::sync::atomic::Ordering::Release);
        self.thread.join().unwrap_or_default()
    }
}

/// The values of every recorded cycle: the commanded torque within the programs' (cst, tq;
/// or what the motor already produced, where a torque mode starts),
/// and the position demand in csp never stepping further than the programs' velocity allows
/// (per cycle, lost cycles counted) nor starting away from the actual position at a switch.
fn check_values(
    samples: &[ecdrive::master::CycleSample],
    cycle_us: u32,
    text: &str,
) -> Result<(), TestCaseError> {
    let step_max = PROGRAM_VELOCITY * f64::from(cycle_us) * 1e-6 * 1.05 + 2.0;
    let axes = samples.iter().map(|s| s.axis).max().map_or(0, |a| a + 1);
    for axis in 0..axes {
        let mut last: Option<&ecdrive::master::CycleSample> = None;
        for s in samples.iter().filter(|s| s.axis == axis) {
            if let Some(t) = s.torque_demand {
                // Beyond the program's torque only where the motor already produced as much:
                // entering a torque mode starts at the actual torque (no jump), then ramps.
                let before = last.map_or(0, |l| {
                    l.torque_demand
                        .map_or(0, i16::unsigned_abs)
                        .max(l.torque.unsigned_abs())
                });
                let bound = PROGRAM_TORQUE.unsigned_abs().max(before);
                prop_assert!(
                    t.unsigned_abs() <= bound,
                    "axis {} cycle {}: torque demand {} beyond the program's {} and the {} the \
                     motor had\n{}",
                    axis,
                    s.cycle,
                    t,
                    PROGRAM_TORQUE,
                    before,
                    text
                );
            }
            if let Some(d) = s.demand {
                match last.and_then(|l| l.demand.map(|ld| (l.cycle, ld))) {
                    Some((lc, ld)) => {
                        let cycles = s.cycle.saturating_sub(lc).max(1) as f64;
                        prop_assert!(
                            ((d - ld).abs() as f64) <= step_max * cycles,
                            "axis {} cycle {}: the csp demand stepped {} counts in {} cycle(s) \
                             (at most {:.0} a cycle at the programs' velocity)\n{}",
                            axis,
                            s.cycle,
                            d - ld,
                            cycles,
                            step_max,
                            text
                        );
                    }
                    None => prop_assert!(
                        (d - s.actual).abs() <= SWITCH_TOLERANCE,
                        "axis {} cycle {}: csp began with demand {} against actual {}\n{}",
                        axis,
                        s.cycle,
                        d,
                        s.actual,
                        text
                    ),
                }
            }
            last = Some(s);
        }
    }
    Ok(())
}

/// Run one case; `Err` says what went wrong.
fn run_case(c: &Case) -> Result<(), TestCaseError> {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let text = toml(c);
    let mut cfg = ecdrive_cli::app::config::parse(&text, "generated.toml")
        .map_err(|e| TestCaseError::fail(format!("the file was refused: {e}\n{text}")))?;
    // Lost frames hold the set-points; the subject is configuration and commands.
    cfg.master.cycle.lost_before_stop = 200;
    cfg.master.cycle.segment_lost_after = 200;
    cfg.master.cycle.segment_gone_after = Duration::from_secs(5);
    cfg.master.cycle.op_timeout = Duration::from_secs(15);
    let rec = Recorder::attach(&mut cfg.master);
    let link = cfg
        .target
        .open_with(&cfg.sim)
        .map_err(|e| TestCaseError::fail(e.to_string()))?;
    let mut m = Master::start(link, cfg.master.clone())
        .map_err(|f| TestCaseError::fail(format!("start-up: {}\n{text}", f.error)))?;
    let drives: Vec<&Device> = c.devices.iter().filter(|d| d.kind.is_drive()).collect();
    prop_assert_eq!(m.drives().len(), drives.len(), "{}", text);
    prop_assert_eq!(m.io().len(), c.devices.len() - drives.len());
    check(&mut m, "OP", 20, |t| t.cycle.all_op)?;
    let enabled = |t: &Telemetry| all_axes(t, |s| s == Some(State::OperationEnabled));
    let disabled = |t: &Telemetry| all_axes(t, |s| !s.is_some_and(State::is_energised));
    let mut is_enabled = false;
    let mut modes: Vec<RunMode> = drives.iter().map(|d| d.mode).collect();
    for op in &c.ops {
        match *op {
            Op::Enable => {
                m.command(Command::Enable(Axes::All))
                    .map_err(|e| TestCaseError::fail(e.to_string()))?;
                check(&mut m, "Operation enabled", 10, enabled)?;
                is_enabled = true;
            }
            Op::Disable => {
                m.command(Command::Disable(Axes::All))
                    .map_err(|e| TestCaseError::fail(e.to_string()))?;
                check(&mut m, "disabled", 10, disabled)?;
                is_enabled = false;
            }
            Op::QuickStopThenEnable if is_enabled => {
                m.command(Command::QuickStop(Axes::All))
                    .map_err(|e| TestCaseError::fail(e.to_string()))?;
                check(&mut m, "quick stop", 10, |t| {
                    all_axes(t, |s| s != Some(State::OperationEnabled))
                })?;
                // Enabling again leaves Quick stop active once the axis stands still (the
                // planner waits for it).
                m.command(Command::Enable(Axes::All))
                    .map_err(|e| TestCaseError::fail(e.to_string()))?;
                check(&mut m, "enabled after a quick stop", 10, enabled)?;
            }
            Op::Mode(axis, pick) if is_enabled && !drives.is_empty() => {
                let n = axis % drives.len();
                let d = drives[n];
                // A switch while enabled needs the mode object and the target's set-point
                // mapped (the default mappings carry every mode).
                let mapped: Vec<RunMode> = d
                    .kind
                    .modes()
                    .iter()
                    .copied()
                    .filter(|md| match &d.mapping {
                        None => true,
                        Some(map) => {
                            map.contains(Direction::Rx, setpoint(*md))
                                && map.contains(Direction::Rx, A(0x6060, 0))
                        }
                    })
                    .collect();
                if let Some(&to) = mapped.get(pick % mapped.len().max(1))
                    && to != modes[n]
                    && d.kind != Kind::GenericCoe
                {
                    // Done when the drive shows the mode in 0x6061 (when it is mapped; else
                    // when the master sends it): a second switch while one is under way is
                    // refused.
                    let display = match &d.mapping {
                        Some(map) => map.contains(Direction::Tx, A(0x6061, 0)),
                        None => d.kind.profile().is_some_and(|p| {
                            p.cyclic_mapping.contains(Direction::Tx, A(0x6061, 0))
                        }),
                    };
                    m.command(Command::Mode(Axes::One(n as u16), to))
                        .map_err(|e| TestCaseError::fail(e.to_string()))?;
                    let what = format!(
                        "the mode switch of axis {n} ({:?}, mapping {:?}) from {:?} to {:?}",
                        d.kind, d.mapping, modes[n], to
                    );
                    check(&mut m, &what, 10, |t| {
                        t.axes.get(n).is_some_and(|a| {
                            if display {
                                a.mode_display == to.code()
                            } else {
                                a.mode == to.code()
                            }
                        })
                    })?;
                    modes[n] = to;
                }
            }
            Op::Program if is_enabled && !drives.is_empty() => {
                let before: Vec<i64> = m
                    .telemetry()
                    .axes
                    .iter()
                    .map(|a| a.position_actual)
                    .collect();
                m.command(Command::RunProgram(Axes::All))
                    .map_err(|e| TestCaseError::fail(e.to_string()))?;
                // Started first: the telemetry of the last program (done, at its last step)
                // stands until the command is applied.
                check(&mut m, "every program started", 5, |t| {
                    t.axes
                        .iter()
                        .all(|a| a.program_running || a.program_step == 0)
                })?;
                check(&mut m, "every program done", 15, |t| {
                    t.axes
                        .iter()
                        .all(|a| !a.program_running && a.program_step >= 1)
                })?;
                // A program runs in its start mode.
                modes = drives.iter().map(|d| d.mode).collect();
                // Values: a csp move (by 20000) and a pp program (by 20000, then −10000) end
                // where they were sent, once the motor has settled.
                for (n, d) in drives.iter().enumerate() {
                    let want = match d.mode {
                        RunMode::Csp => 20_000,
                        RunMode::Pp => 10_000,
                        _ => continue,
                    };
                    let from = before.get(n).copied().unwrap_or(0);
                    let at = |t: &Telemetry| t.axes.get(n).map_or(0, |a| a.position_actual) - from;
                    if m.wait_until("the target", Duration::from_secs(10), |t| {
                        (at(t) - want).abs() <= POSITION_TOLERANCE
                    })
                    .is_err()
                    {
                        let moved = at(&m.telemetry().clone());
                        prop_assert!(
                            false,
                            "axis {} ({:?}, {:?}) moved {} counts, not {} ± {}\n{}",
                            n,
                            d.kind,
                            d.mode,
                            moved,
                            want,
                            POSITION_TOLERANCE,
                            text
                        );
                    }
                }
            }
            _ => {}
        }
    }
    let (report, _) = m.stop(StopKind::Ramp);
    let (samples, dropped) = rec.finish();
    let report = report.ok_or_else(|| TestCaseError::fail("no report"))?;
    prop_assert!(report.shutdown_ok, "{}", text);
    prop_assert_eq!(
        dropped,
        0,
        "samples dropped: the value checks need every cycle"
    );
    check_values(&samples, c.cycle_us, &text)?;
    let cycle = report
        .cycle
        .as_ref()
        .ok_or_else(|| TestCaseError::fail("no cycle report"))?;
    for (i, states) in cycle.states.iter().enumerate() {
        prop_assert!(
            !states.last().is_some_and(|s| s.is_energised()),
            "axis {} left {:?}\n{}",
            i,
            states,
            text
        );
    }
    let errors: Vec<_> = report
        .history
        .iter()
        .filter(|h| h.error && !matches!(h.kind, ecdrive::master::HistoryKind::FrameLost))
        .collect();
    prop_assert!(errors.is_empty(), "{:#?}\n{}", errors, text);
    Ok(())
}

/// The number of generated cases (`ECDRIVE_CASES`, or proptest's `PROPTEST_CASES`).
fn cases() -> u32 {
    ["ECDRIVE_CASES", "PROPTEST_CASES"]
        .iter()
        .find_map(|v| std::env::var(v).ok()?.trim().parse().ok())
        .unwrap_or(64)
}

proptest! {
    #![proptest_config(Config {
        cases: cases(),
        rng_seed: proptest::test_runner::RngSeed::Fixed(ecdrive::rt::audit::test_seed(file!())),
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("proptest-regressions"))),
        max_shrink_iters: std::env::var("PROPTEST_MAX_SHRINK_ITERS")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(64),
        .. Config::default()
    })]

    #[test]
    fn any_valid_configuration_runs(c in case()) {
        run_case(&c)?;
    }
}

// ---- named regression cases ------------------------------------------------------------------

fn drive(kind: Kind, mode: RunMode) -> Device {
    Device {
        kind,
        quirks: Vec::new(),
        mode,
        mapping: None,
    }
}

/// The configuration example's mapping (docs/reference/configuration.md) failed at start-up
/// ("timeout: mailbox response") whenever the MR-J4-TM's rx + tx entry count was 10, 17 or 24:
/// ecdrive's CoE client and ethercrab's each counted mailbox requests from 1, and ethercrab's
/// first request repeated the counter of ecdrive's last, which the drive ignores as a repeat.
/// Every total from 4 to 24 on both drives.
#[test]
fn every_entry_count_remaps_without_a_mailbox_counter_collision() {
    for kind in [Kind::MrJ4, Kind::Bdhde] {
        let mut seen = Vec::new();
        for extra in 0..=20usize {
            let rx: Vec<usize> = (0..extra / 2).collect();
            let tx: Vec<usize> = (0..extra - extra / 2).collect();
            let Some(m) = mapping(kind, &[RunMode::Csp], (&rx, &tx), (None, None)) else {
                continue;
            };
            let n = m.pdos(Direction::Rx)[0].entries.len() + m.pdos(Direction::Tx)[0].entries.len();
            if seen.contains(&n) {
                continue;
            }
            seen.push(n);
            let mut d = drive(kind, RunMode::Csp);
            d.mapping = Some(m);
            let c = Case {
                devices: vec![d],
                cycle_us: 1000,
                ops: vec![Op::Enable],
            };
            run_case(&c).unwrap_or_else(|e| panic!("{} with {n} entries: {e}", kind.name()));
        }
        // The failing totals, as far as the drive's limits reach (the BDHDE maps at most 8
        // entries per direction).
        let most = seen.iter().copied().max().unwrap_or(0);
        for n in [10, 17, 24].into_iter().filter(|n| *n <= most) {
            assert!(
                seen.contains(&n),
                "{}: {n} entries not tried ({seen:?})",
                kind.name()
            );
        }
        assert!(seen.contains(&10), "{seen:?}");
    }
}

/// Drives that implement only the standard transitions, in a mixed segment with an I/O device
/// and the generic servo: enable, quick stop, enable, program.
#[test]
fn standard_transitions_only_in_a_mixed_segment() {
    let mut a = drive(Kind::MrJ4, RunMode::Csp);
    a.quirks = vec!["no-state-skipping"];
    let mut b = drive(Kind::Bdhde, RunMode::Csv);
    b.quirks = vec!["no-state-skipping"];
    let mut g = drive(Kind::GenericCoe, RunMode::Csp);
    g.quirks = vec!["no-state-skipping", "cycle-time-read-only"];
    let c = Case {
        devices: vec![a, drive(Kind::GenericIo, RunMode::Csp), b, g],
        cycle_us: 1000,
        ops: vec![Op::Enable, Op::QuickStopThenEnable, Op::Program],
    };
    run_case(&c).unwrap_or_else(|e| panic!("{e}"));
}

/// Found by the generative test: a mapping with objects the master does not drive (here the
/// BDHDE's max torque 0x6072 and max current 0x6073, the following-error window 0x6065, a
/// position offset) sent 0 in them every cycle, so the drive had no torque and the move never
/// finished. Such outputs now carry the value the drive had before they were mapped.
#[test]
fn mapped_limits_the_master_does_not_drive_keep_the_drives_values() {
    let e = |i: u16, bits: u8| PdoEntry::new(i, 0, bits);
    let m = Mapping::owned(
        vec![Pdo::owned(
            0x1600,
            vec![
                e(0x6040, 16),
                e(0x607A, 32),
                e(0x6065, 32),
                e(0x60B0, 32),
                e(0x6073, 16),
                e(0x6072, 16),
            ],
        )],
        vec![Pdo::owned(0x1A00, vec![e(0x6041, 16), e(0x6064, 32)])],
    );
    let mut d = drive(Kind::Bdhde, RunMode::Csp);
    d.mapping = Some(m);
    let c = Case {
        devices: vec![d],
        cycle_us: 1000,
        ops: vec![Op::Enable, Op::Program],
    };
    run_case(&c).unwrap_or_else(|e| panic!("{e}"));
}

/// Found by the generative test (`cc daae7c29…`): an MR-J4-TM whose cst program left the motor
/// turning could not switch to csp. The drive switches to or from a position mode only at zero
/// speed, and a torque set-point ramped to 0 only lets the motor coast, so the engine gave up
/// after its timeout. It now brakes in csv first. Both drives, and a cst → csv → csp chain.
/// The value checks then found the switch made at 46 r/min: the MR-J4-TM's zero-speed flag
/// S_ZSP shows below [Pr. PC07] (50 r/min) while the engine's csv ramp still braked, and csp
/// stopped the rest within a cycle (the demand stepped 6326 counts, torque −36 %). The engine
/// now waits for its own ramp to end as well.
#[test]
fn a_turning_torque_axis_switches_to_a_position_mode() {
    for kind in [Kind::MrJ4, Kind::Bdhde] {
        let c = Case {
            devices: vec![drive(kind, RunMode::Cst)],
            cycle_us: 2000,
            ops: vec![
                Op::Enable,
                Op::QuickStopThenEnable,
                Op::Program,
                Op::Mode(0, 0),
                Op::Mode(0, 2),
                Op::Program,
                Op::Mode(0, 1),
                Op::Mode(0, 0),
            ],
        };
        run_case(&c).unwrap_or_else(|e| panic!("{}: {e}", kind.name()));
    }
}

/// Found by the value checks (seed 2): after a tq program the BDHDE turns; a quick stop lets
/// the drive brake with its own torque (−36.5 % here), and the engine took that torque as its
/// set-point while not in Operation enabled, so 0x6071 carried it — and going back to
/// Operation enabled would have driven the motor with it. Outside Operation enabled the
/// torque set-point is now 0.
#[test]
fn a_quick_stop_in_a_torque_mode_commands_no_braking_torque() {
    let c = Case {
        devices: vec![drive(Kind::Bdhde, RunMode::Tq)],
        cycle_us: 500,
        ops: vec![Op::Enable, Op::Program, Op::Enable, Op::QuickStopThenEnable],
    };
    run_case(&c).unwrap_or_else(|e| panic!("{e}"));
}

/// Found by seed 12026296202516686879 (300 cases): a second `RunProgram` right after the first
/// program had finished was taken as done at once (the last program's telemetry — not running,
/// at its last step — stood until the command was applied), so the next mode command met the
/// new program starting: the program took its start mode back and the switch neither happened
/// nor was refused. The case now waits for the programs to start, and a mode command while a
/// program runs is refused (`mode_commands_wait_for_the_program`).
#[test]
fn a_program_run_twice_then_every_mode() {
    let c = Case {
        devices: vec![drive(Kind::Bdhde, RunMode::Csv)],
        cycle_us: 500,
        ops: vec![
            Op::Enable,
            Op::Program,
            Op::Program,
            Op::Mode(0, 0),
            Op::Mode(0, 1),
            Op::Mode(0, 2),
            Op::Mode(0, 3),
            Op::Mode(0, 4),
            Op::Mode(0, 5),
        ],
    };
    run_case(&c).unwrap_or_else(|e| panic!("{e}"));
}

/// A mode command while a program runs is refused with the reason (the program owns the
/// axis's mode, as it owns its set-points and pp targets); the program goes on in its mode.
#[test]
fn mode_commands_wait_for_the_program() {
    use ecdrive::master::{Axes, Command, StopKind};
    let text = "interface = \"sim\"\ncycle = \"1ms\"\n[sim]\ndevices = [\"bdhde\"]\n\
                loss_detection = false\n[[drive]]\nposition = 0\nmode = \"csv\"\n\
                program = [{ step = \"ramp\", velocity = 100000, acceleration = 1000000, hold = 2 }, \
                { step = \"ramp\", velocity = 0, acceleration = 1000000 }]\n";
    let cfg = ecdrive_cli::app::config::parse(text, "mode.toml").unwrap_or_else(|e| panic!("{e}"));
    let link = cfg
        .target
        .open_with(&cfg.sim)
        .unwrap_or_else(|e| panic!("{e}"));
    let mut m = ecdrive::master::Master::start(link, cfg.master.clone())
        .unwrap_or_else(|f| panic!("{}", f.error));
    let guard = Duration::from_secs(20);
    m.wait_until("OP", guard, |t| t.cycle.all_op).expect("OP");
    m.command(Command::Enable(Axes::All)).expect("enable");
    m.wait_until("enabled", guard, |t| {
        t.axes
            .iter()
            .all(|a| a.state == Some(ecdrive::State::OperationEnabled))
    })
    .expect("enabled");
    m.command(Command::RunProgram(Axes::All)).expect("run");
    m.wait_until("running", guard, |t| t.axes[0].program_running)
        .expect("running");
    m.command(Command::Mode(Axes::All, RunMode::Pv))
        .expect("mode");
    m.wait_until("the program", guard, |t| {
        !t.axes[0].program_running && t.axes[0].program_step >= 1
    })
    .expect("program done");
    let refused = m.history().iter().any(|h| {
        matches!(
            h.cycle_event(),
            Some(EventKind::CommandRefused { why, .. })
                if why.contains("mode switch refused: a program runs on the axis")
        )
    });
    assert_eq!(m.telemetry().axes[0].mode, RunMode::Csv.code());
    let _ = m.stop(StopKind::Ramp);
    assert!(refused, "no refusal in the history");
}
