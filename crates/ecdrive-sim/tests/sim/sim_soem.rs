//! Conformance with a second master: SOEM 1.4 through pysoem, over a veth pair. Two generic
//! CoE devices (PDOs remapped in PRE-OP from pysoem's `config_func`) and one EEPROM-only I/O
//! device: `config_init`, `config_map`, `config_dc` + `dc_sync`, SAFE-OP and OP, process data
//! with SOEM's expected working counter, SDO access and the object dictionary via SDO
//! information, then back to INIT.
//!
//! Needs root and `pysoem` (`pip install pysoem`). Without pysoem the test prints a loud
//! SKIPPED line, unless `ECDRIVE_REQUIRE_PYSOEM` is set, which makes it fail instead.

use crate::support;

use ecdrive_sim::devices::{GenericCoeDevice, IoDevice};
use ecdrive_sim::{EscConfig, HostClock, Segment};
use std::sync::Arc;
use support::oracle::{oracle, transitions};
use support::python_master;

/// What both scripts start with: the interface from argv[1], generous SOEM timeouts (µs: a
/// loaded CI machine stalls for milliseconds), an opened master `m` and the output `out`.
macro_rules! prelude {
    () => {
        r#"
import json, struct, sys, time
import pysoem

ifname = sys.argv[1]
t = pysoem.settings.timeouts
t.ret = 50_000
t.safe = 200_000
t.eeprom = 200_000
t.tx_mailbox = 200_000
t.rx_mailbox = 2_000_000
t.state = 5_000_000
out = {}
m = pysoem.Master()
m.open(ifname)


def config_init(expected):
    """`config_init` as SOEM applications call it: a count below the devices expected (its
    broadcast read lost or late on a loaded machine: SOEM then finds 0) is retried twice; the
    attempts go to out["init_attempts"]."""
    for attempt in range(1, 4):
        n = m.config_init()
        out["init_attempts"] = attempt
        if n >= expected:
            break
    return n


def dc_sync0_to_op(cycle_ns=1_000_000):
    """DC with SYNC0 every `cycle_ns` (1 ms unless told), then `safeop_then_op()`."""
    m.config_dc()
    for s in m.slaves:
        s.dc_sync(True, cycle_ns)
    safeop_then_op()


def safeop_then_op():
    """SAFE-OP, then OP with process data flowing while requesting it, as SOEM applications
    do; the states reached go to out["safeop"] and out["op"]."""
    out["safeop"] = m.state_check(pysoem.SAFEOP_STATE, 2_000_000)
    # SAFE-OP: process data with every output zero, the working counter recorded (outputs
    # count from SAFE-OP on, ETG.1020).
    safeop_wkcs = []
    for _ in range(200):
        m.send_processdata()
        safeop_wkcs.append(m.receive_processdata(200_000))
        time.sleep(0.001)
    out["safeop_wkcs"] = safeop_wkcs
    m.state = pysoem.OP_STATE
    m.write_state()
    op = False
    for _ in range(2000):
        m.send_processdata()
        m.receive_processdata(200_000)
        if m.state_check(pysoem.OP_STATE, 1_000) == pysoem.OP_STATE:
            op = True
            break
        time.sleep(0.001)
    out["op"] = op

"#
    };
}

const SCRIPT: &str = concat!(
    prelude!(),
    r#"try:
    n = config_init(3)
    out["count"] = n
    out["slaves"] = [
        {"name": s.name, "man": s.man, "id": s.id, "rev": s.rev} for s in m.slaves
    ]

    def remap(pos):
        s = m.slaves[pos]
        s.sdo_write(0x1C12, 0, bytes([0]))
        s.sdo_write(0x1C13, 0, bytes([0]))
        s.sdo_write(0x1C12, 1, struct.pack("<H", 0x1601))
        s.sdo_write(0x1C12, 0, bytes([1]))
        s.sdo_write(0x1C13, 1, struct.pack("<H", 0x1A01))
        s.sdo_write(0x1C13, 0, bytes([1]))
        s.sdo_write(0x6060, 0, struct.pack("<b", 9))
        s.sdo_write(0x1C32, 1, struct.pack("<H", 2))

    for i, s in enumerate(m.slaves):
        if s.name.startswith("ecdrive generic CoE"):
            s.config_func = remap

    out["serial"] = struct.unpack("<I", m.slaves[1].sdo_read(0x1018, 4))[0]
    out["device_name"] = m.slaves[0].sdo_read(0x1008, 0).decode()
    iomap = m.config_map()
    out["iomap"] = iomap
    out["sizes"] = [[len(s.output), len(s.input)] for s in m.slaves]
    out["expected_wkc"] = m.expected_wkc
    dc_sync0_to_op()
    wkcs = []
    echo = False
    enabled = [False, False]
    for cycle in range(3000):
        io = m.slaves[2]
        io.output = bytes([0x42, cycle & 0xFF])
        for k in (0, 1):
            s = m.slaves[k]
            status = struct.unpack("<H", s.input[0:2])[0] if len(s.input) >= 2 else 0
            if status & 0x6F == 0x27:
                enabled[k] = True
            cw = {0x40: 6, 0x60: 6, 0x21: 7, 0x23: 15}.get(status & 0x6F, 15)
            s.output = struct.pack("<HiB", cw, 500_000, 9)
        m.send_processdata()
        wkcs.append(m.receive_processdata(200_000))
        if io.input[2:3] == bytes([0x42]):
            echo = True
        if echo and all(enabled) and cycle > 50:
            break
        time.sleep(0.001)
    out["wkc_last"] = wkcs[-20:]
    out["echo"] = echo
    out["enabled"] = enabled
    out["missed"] = struct.unpack("<H", m.slaves[0].sdo_read(0x1C32, 11))[0]
    out["od"] = sorted(o.index for o in m.slaves[0].od)[:6]
    m.state = pysoem.INIT_STATE
    m.write_state()
    out["init"] = m.state_check(pysoem.INIT_STATE, 2_000_000)
finally:
    m.close()
print(json.dumps(out))
"#
);

/// Every SAFE-OP reply SOEM got carries its expected working counter, outputs included; a
/// frame a loaded machine loses (a negative count) is not a wrong answer, and is rare.
fn assert_safeop_wkc(v: &serde_json::Value, expected: i64) {
    let wkcs = v["safeop_wkcs"]
        .as_array()
        .expect("SAFE-OP working counters");
    assert_eq!(wkcs.len(), 200);
    let wrong: Vec<i64> = wkcs
        .iter()
        .filter_map(|w| w.as_i64())
        .filter(|&w| w >= 0 && w != expected)
        .collect();
    assert!(
        wrong.is_empty(),
        "SAFE-OP working counters other than {expected}: {wrong:?}"
    );
    assert!(
        wkcs.iter()
            .filter(|w| w.as_i64().is_some_and(|w| w < 0))
            .count()
            <= 5
    );
}

#[test]
fn soem_brings_devices_to_op() {
    if !python_master::ready(
        "sim_soem::soem_brings_devices_to_op",
        "pysoem",
        "ECDRIVE_REQUIRE_PYSOEM",
    ) {
        return;
    }
    let mut seg = Segment::new(Arc::new(HostClock));
    let cfg = EscConfig {
        sm_watchdog: 0,
        ..Default::default()
    };
    seg.push(Box::new(GenericCoeDevice::new(11).unwrap()), cfg.clone())
        .unwrap();
    seg.push(Box::new(GenericCoeDevice::new(12).unwrap()), cfg.clone())
        .unwrap();
    seg.push(Box::new(IoDevice::new(2, 4).with_serial(13)), cfg)
        .unwrap();
    let (seg, v) = python_master::run("pysoem", seg, SCRIPT, &[]);

    assert_eq!(v["count"], 3);
    assert_eq!(v["slaves"][0]["name"], "ecdrive generic CoE device");
    assert_eq!(v["slaves"][0]["man"], 0x0ECD);
    assert_eq!(v["slaves"][0]["id"], 0x0402);
    assert_eq!(v["slaves"][2]["name"], "ecdrive generic I/O 2/4");
    assert_eq!(v["serial"], 12);
    assert_eq!(v["device_name"], "ecdrive generic CoE device");
    // Remapped CoE devices: 7 output / 11 input bytes; the I/O device 2 / 4 from its SII.
    assert_eq!(v["sizes"], serde_json::json!([[7, 11], [7, 11], [2, 4]]));
    assert_eq!(v["iomap"], 2 * (7 + 11) + 2 + 4);
    // SOEM's expectation: outputs ×2 + inputs, one each per device.
    assert_eq!(v["expected_wkc"], 9);
    assert_eq!(v["safeop"], 4);
    assert_safeop_wkc(&v, 9);
    assert_eq!(v["op"], true);
    for w in v["wkc_last"].as_array().expect("wkcs") {
        assert_eq!(w, 9, "working counter in OP");
    }
    assert_eq!(v["echo"], true, "I/O device echoed the outputs");
    assert_eq!(v["enabled"], serde_json::json!([true, true]));
    assert!(v["missed"].is_u64());
    assert_eq!(
        v["od"],
        serde_json::json!([0x1000, 0x1001, 0x1008, 0x1009, 0x100A, 0x1018])
    );
    assert_eq!(v["init"], 1);
    for i in 0..2 {
        let dev = seg.device::<GenericCoeDevice>(i).expect("CoE device");
        assert!(dev.seen.sync0_events > 0, "device {i} saw SYNC0");
    }
}

/// The emulated drives `names`, in line order, with the SM watchdog off (an independent
/// master's Python loop stalls on a loaded machine).
fn drives_segment(names: &[&str]) -> Segment {
    let mut seg = Segment::new(Arc::new(HostClock));
    for (i, d) in names.iter().enumerate() {
        let dev = ecdrive_sim::devices::by_name(d, i).expect("emulated drive");
        seg.push(
            dev,
            EscConfig {
                sm_watchdog: 0,
                ..Default::default()
            },
        )
        .unwrap();
    }
    seg
}

const DRIVES_SCRIPT: &str = concat!(
    prelude!(),
    r#"
reads = json.loads(sys.argv[2])   # [[position, index, sub], ...]
try:
    out["count"] = config_init(2)
    out["slaves"] = [{"name": s.name, "man": s.man, "id": s.id} for s in m.slaves]
    # Objects read over SDO in PRE-OP, as bytes (hex), for the oracle comparison.
    out["reads"] = [m.slaves[p].sdo_read(i, s).hex() for p, i, s in reads]

    # The remap SOEM users write in config_func (PRE-OP): clear the assignment, rewrite the
    # first RxPDO and TxPDO, assign them again.
    def remap(pos):
        s = m.slaves[pos]
        s.sdo_write(0x1C12, 0, bytes([0]))
        s.sdo_write(0x1C13, 0, bytes([0]))
        s.sdo_write(0x1600, 0, bytes([0]))
        s.sdo_write(0x1600, 1, struct.pack("<I", 0x60400010))
        s.sdo_write(0x1600, 2, struct.pack("<I", 0x607A0020))
        s.sdo_write(0x1600, 0, bytes([2]))
        s.sdo_write(0x1A00, 0, bytes([0]))
        s.sdo_write(0x1A00, 1, struct.pack("<I", 0x60410010))
        s.sdo_write(0x1A00, 2, struct.pack("<I", 0x60640020))
        s.sdo_write(0x1A00, 0, bytes([2]))
        s.sdo_write(0x1C12, 1, struct.pack("<H", 0x1600))
        s.sdo_write(0x1C12, 0, bytes([1]))
        s.sdo_write(0x1C13, 1, struct.pack("<H", 0x1A00))
        s.sdo_write(0x1C13, 0, bytes([1]))

    for s in m.slaves:
        s.config_func = remap
    out["iomap"] = m.config_map()
    out["sizes"] = [[len(s.output), len(s.input)] for s in m.slaves]
    out["expected_wkc"] = m.expected_wkc
    out["mapped_back"] = [
        [m.slaves[p].sdo_read(0x1600, 0).hex(), m.slaves[p].sdo_read(0x1A00, 2).hex()]
        for p in range(len(m.slaves))
    ]
    dc_sync0_to_op()
    out["al_codes"] = [s.al_status for s in m.slaves]
    # 1000 cycles of process data, every output zero (no drive is enabled).
    wkcs = []
    for cycle in range(1000):
        for s in m.slaves:
            s.output = bytes(len(s.output))
        m.send_processdata()
        wkcs.append(m.receive_processdata(200_000))
        time.sleep(0.001)
    out["wkcs"] = wkcs
    out["states"] = [s.state for s in m.slaves] if m.read_state() else []
    m.state = pysoem.INIT_STATE
    m.write_state()
    out["init"] = m.state_check(pysoem.INIT_STATE, 2_000_000)
finally:
    m.close()
print(json.dumps(out))
"#
);

/// SOEM, an independent master, takes the emulated MR-J4-TM and BDHDE (not only generic
/// devices) through start-up as its users write it: identity read over SDO and compared with
/// the manuals' values (the oracle, not the emulation's constants), the first RxPDO and TxPDO
/// remapped by SDO writes in PRE-OP from `config_func`, DC SYNC0 at 1 ms, OP, 1000 cycles with
/// SOEM's expected working counter, INIT.
#[test]
fn soem_runs_the_emulated_drives() {
    if !python_master::ready(
        "sim_soem::soem_runs_the_emulated_drives",
        "pysoem",
        "ECDRIVE_REQUIRE_PYSOEM",
    ) {
        return;
    }
    let drives = ["mr-j4-tm", "bdhde"];
    let seg = drives_segment(&drives);
    let mut reads = Vec::new();
    let mut want = Vec::new();
    for (pos, d) in drives.iter().enumerate() {
        let o = oracle(d);
        assert!(o.len() >= 3, "{d}: the oracle has {o:?}");
        for ((i, s), v) in o {
            reads.push(serde_json::json!([pos, i, s]));
            want.push((pos, i, s, v));
        }
    }
    let reads = serde_json::Value::Array(reads).to_string();
    let (_, v) = python_master::run("pysoem", seg, DRIVES_SCRIPT, &[&reads]);
    eprintln!("{v}");
    assert_eq!(v["count"], 2);
    for (k, (pos, i, s, value)) in want.iter().enumerate() {
        let hex = v["reads"][k].as_str().unwrap();
        let bytes: Vec<u8> = (0..hex.len() / 2)
            .map(|j| u8::from_str_radix(&hex[2 * j..2 * j + 2], 16).unwrap())
            .collect();
        let mut got = 0u64;
        for (b, x) in bytes.iter().enumerate().take(8) {
            got |= u64::from(*x) << (8 * b);
        }
        assert_eq!(
            got, *value,
            "{}: 0x{i:04X}:{s:02X} read by SOEM is 0x{got:X}, the manual says 0x{value:X}",
            drives[*pos]
        );
    }
    // The remap took: two entries each way, 6 output and 6 input bytes per drive.
    assert_eq!(v["sizes"], serde_json::json!([[6, 6], [6, 6]]));
    for p in 0..2 {
        assert_eq!(v["mapped_back"][p][0], "02", "{v}");
        assert_eq!(v["mapped_back"][p][1], "20006460", "{v}");
    }
    // SOEM's expectation: outputs ×2 + inputs per drive.
    assert_eq!(v["expected_wkc"], 6);
    assert_eq!(v["safeop"], 4);
    assert_safeop_wkc(&v, 6);
    assert_eq!(v["op"], true, "{v}");
    let wkcs = v["wkcs"].as_array().unwrap();
    assert_eq!(wkcs.len(), 1000);
    // Every reply carries SOEM's expected working counter; a frame a loaded machine loses
    // (SOEM: no frame, a negative count) is not a wrong answer, and is rare.
    let wrong = wkcs
        .iter()
        .filter(|w| w.as_i64().is_some_and(|w| w >= 0 && w != 6))
        .count();
    let lost = wkcs
        .iter()
        .filter(|w| w.as_i64().is_some_and(|w| w < 0))
        .count();
    assert_eq!(wrong, 0, "replies with another working counter than 6: {v}");
    assert!(lost <= 10, "{lost} of 1000 frames lost: {v}");
    assert_eq!(v["init"], 1);
}

const VENDOR_SCRIPT: &str = concat!(
    prelude!(),
    r#"
try:
    out["count"] = config_init(3)
    out["slaves"] = [{"name": s.name, "man": s.man, "id": s.id} for s in m.slaves]
    out["iomap"] = m.config_map()
    out["sizes"] = [[len(s.output), len(s.input)] for s in m.slaves]
    out["expected_wkc"] = m.expected_wkc
    safeop_then_op()
    wkcs = []
    echo = None
    for cycle in range(1000):
        m.slaves[0].output = bytes([0xA5, cycle & 0xFF])
        m.slaves[1].output = bytes([1, 2, 3, cycle & 0xFF])
        m.send_processdata()
        wkcs.append(m.receive_processdata(200_000))
        if cycle > 10 and m.slaves[0].input[0:1] == bytes([0xA5]):
            echo = m.slaves[0].input.hex()
            break
        time.sleep(0.001)
    out["wkc_last"] = wkcs[-5:]
    out["echo"] = echo
    m.state = pysoem.INIT_STATE
    m.write_state()
    out["init"] = m.state_check(pysoem.INIT_STATE, 2_000_000)
finally:
    m.close()
print(json.dumps(out))
"#
);

/// SOEM on devices emulated from real vendor files (`../shared/esi-corpus`), as ecdrive's own
/// corpus test runs them: the iTegva E7.820.001 (outputs on two one-byte SMs on the ESC's
/// digital output register, 0x0F02/0x0F03, inputs at 0x1000, no mailbox), the SMC EX260-SEC1
/// (outputs on four SMs, 0x0F00–0x0F03) and a Synapticon device whose file has no assignment
/// objects (SOEM reads 0x1C12/0x1C13 over CoE). SOEM maps them from the SII and over CoE,
/// takes them to OP with its expected working counter in SAFE-OP and OP, and the iTegva module
/// echoes the outputs SOEM wrote.
#[test]
fn soem_runs_devices_from_vendor_files() {
    if !python_master::ready(
        "sim_soem::soem_runs_devices_from_vendor_files",
        "pysoem",
        "ECDRIVE_REQUIRE_PYSOEM",
    ) {
        return;
    }
    let Some(dir) = support::corpus::dir() else {
        return;
    };
    let names = [
        format!(
            "esi:{}@0x100",
            dir.join("itegva/iTegva_E7x_Series.xml").display()
        ),
        format!(
            "esi:{}@0x01000001",
            dir.join("smc/SMC EX260-SECx_V11.xml").display()
        ),
        format!(
            "esi:{}@0x201",
            dir.join("synapticon/Somanet_CiA402-multi.xml").display()
        ),
    ];
    let mut seg = Segment::new(Arc::new(HostClock));
    for (i, n) in names.iter().enumerate() {
        let dev = ecdrive_sim::devices::by_name(n, i).unwrap_or_else(|e| panic!("{e}"));
        seg.push(
            dev,
            EscConfig {
                sm_watchdog: 0,
                ..Default::default()
            },
        )
        .unwrap();
    }
    let (seg, v) = python_master::run("pysoem", seg, VENDOR_SCRIPT, &[]);
    eprintln!("{v}");
    assert_eq!(v["count"], 3);
    assert_eq!(v["slaves"][0]["id"], 0x100);
    // 16 relay outputs and 16 inputs; 32 valve outputs; two 13-byte PDOs each way.
    assert_eq!(v["sizes"], serde_json::json!([[2, 2], [4, 0], [26, 26]]));
    // SOEM's expectation: outputs ×2 + inputs, per device that has them.
    assert_eq!(v["expected_wkc"], 3 + 2 + 3);
    assert_eq!(v["safeop"], 4);
    assert_safeop_wkc(&v, 8);
    assert_eq!(v["op"], true, "{v}");
    for w in v["wkc_last"].as_array().expect("wkcs") {
        assert!(w == 8 || w.as_i64().is_some_and(|w| w < 0), "{v}");
    }
    // The module's inputs echo its outputs: both bytes, the second one a recent cycle's.
    let echo = v["echo"].as_str().unwrap_or_else(|| panic!("no echo: {v}"));
    assert!(echo.starts_with("a5") && echo.len() == 4, "{v}");
    // The valve unit's four SMs took SOEM's four bytes, in order.
    let valves = seg.slave(1).expect("SMC").esc.outputs();
    assert_eq!(valves.get(..3), Some(&[1u8, 2, 3][..]), "{v}");
    assert_eq!(v["init"], 1);
}

const TRANSITIONS_SCRIPT: &str = concat!(
    prelude!(),
    r#"
cases = json.loads(sys.argv[2])   # [[position, [controlwords to the start state], controlword], ...]
setup = json.loads(sys.argv[3])   # per position: [[index, subindex, size, value], ...] in PRE-OP
cycle_ns = json.loads(sys.argv[4])
STATES = [
    (0x4F, 0x40, "Switch on disabled"),
    (0x6F, 0x21, "Ready to switch on"),
    (0x6F, 0x23, "Switched on"),
    (0x6F, 0x27, "Operation enabled"),
    (0x6F, 0x07, "Quick stop active"),
    (0x4F, 0x0F, "Fault reaction active"),
    (0x4F, 0x08, "Fault"),
    (0x4F, 0x00, "Not ready to switch on"),
]


def state_of(sw):
    for mask, value, name in STATES:
        if sw & mask == value:
            return name
    return "?"


cw_out = [0, 0]


def cycle():
    """One cycle: every drive gets its controlword and its actual position as target (no
    motion); the states of both."""
    for k, s in enumerate(m.slaves):
        actual = struct.unpack("<i", s.input[2:6])[0] if len(s.input) >= 6 else 0
        s.output = struct.pack("<Hi", cw_out[k], actual)
    m.send_processdata()
    m.receive_processdata(200_000)
    time.sleep(0.001)
    return [state_of(struct.unpack("<H", s.input[0:2])[0]) for s in m.slaves]


def error_code(k):
    """The drive's 0x603F. A drive that has just faulted also sends its emergency, which SOEM
    hands to the next mailbox read as an exception: its code is the same fact, and the read is
    tried again for the object itself."""
    code = None
    for _ in range(5):
        try:
            return struct.unpack("<H", m.slaves[k].sdo_read(0x603F, 0)[:2])[0]
        except pysoem.Emergency as e:
            code = e.error_code
    return code


try:
    out["count"] = config_init(2)

    def remap(pos):
        s = m.slaves[pos]
        s.sdo_write(0x1C12, 0, bytes([0]))
        s.sdo_write(0x1C13, 0, bytes([0]))
        s.sdo_write(0x1600, 0, bytes([0]))
        s.sdo_write(0x1600, 1, struct.pack("<I", 0x60400010))
        s.sdo_write(0x1600, 2, struct.pack("<I", 0x607A0020))
        s.sdo_write(0x1600, 0, bytes([2]))
        s.sdo_write(0x1A00, 0, bytes([0]))
        s.sdo_write(0x1A00, 1, struct.pack("<I", 0x60410010))
        s.sdo_write(0x1A00, 2, struct.pack("<I", 0x60640020))
        s.sdo_write(0x1A00, 0, bytes([2]))
        s.sdo_write(0x1C12, 1, struct.pack("<H", 0x1600))
        s.sdo_write(0x1C12, 0, bytes([1]))
        s.sdo_write(0x1C13, 1, struct.pack("<H", 0x1A00))
        s.sdo_write(0x1C13, 0, bytes([1]))
        for index, sub, size, value in setup[pos]:
            s.sdo_write(index, sub, value.to_bytes(size, "little", signed=value < 0))

    for s in m.slaves:
        s.config_func = remap
    m.config_map()
    dc_sync0_to_op(cycle_ns)
    results = []
    faults = []
    for pos, path, cw in cases:
        # Back to Switch on disabled, every drive; a drive in Fault gets a fault reset (and the
        # error code it shows is recorded, so a fault no case asked for names its reason).
        cw_out[0] = cw_out[1] = 0
        for _ in range(100):
            states = cycle()
        for k, st in enumerate(states):
            if st == "Fault":
                code = error_code(k)
                faults.append([k, code])
                cw_out[k] = 0x80
                for _ in range(50):
                    states = cycle()
                cw_out[k] = 0
                for _ in range(50):
                    states = cycle()
        reached = states[pos] == "Switch on disabled"
        # The way to the start state: each controlword until the state changes.
        for c in path:
            before = states[pos]
            cw_out[pos] = c
            for _ in range(200):
                states = cycle()
                if states[pos] != before:
                    break
        start = states[pos]
        # The fact's controlword: every state seen in the next 100 cycles.
        cw_out[pos] = cw
        seen = []
        for _ in range(100):
            st = cycle()[pos]
            if not seen or seen[-1] != st:
                seen.append(st)
        results.append({"reached": reached, "start": start, "seen": seen})
    out["results"] = results
    out["faults"] = faults
    out["al"] = [s.state for s in m.slaves] if m.read_state() else []
    m.state = pysoem.INIT_STATE
    m.write_state()
finally:
    m.close()
print(json.dumps(out))
"#
);

/// The emulated side of the manuals' state-machine transitions, driven by an independent
/// master: SOEM takes both emulated EtherCAT drives to OP (the controlword acts only there, by
/// process data) and, for each transition fact of their manuals (`tests/manual_facts`), brings
/// the drive to the fact's start state by the standard commands, sends the fact's controlword
/// and records every state the statusword shows. A transition the manual says exists must show
/// its end state; one it says does not, must not. A start state the commands cannot set up on
/// an idle motor (Fault; Quick stop active, which an idle motor leaves at once) is named, and
/// at least ten facts per drive are checked.
#[test]
fn soem_drives_the_transitions_the_manuals_list() {
    if !python_master::ready(
        "sim_soem::soem_drives_the_transitions_the_manuals_list",
        "pysoem",
        "ECDRIVE_REQUIRE_PYSOEM",
    ) {
        return;
    }
    let drives = ["mr-j4-tm", "bdhde"];
    let seg = drives_segment(&drives);
    let path = |from: &str| -> Option<Vec<u16>> {
        Some(match from {
            "Switch on disabled" => vec![],
            "Ready to switch on" => vec![0x06],
            "Switched on" => vec![0x06, 0x07],
            "Operation enabled" => vec![0x06, 0x07, 0x0F],
            "Quick stop active" => vec![0x06, 0x07, 0x0F, 0x02],
            _ => return None,
        })
    };
    let mut cases = Vec::new();
    let mut facts = Vec::new();
    let mut unset = Vec::new();
    for (pos, d) in drives.iter().enumerate() {
        for (id, from, to, cw, exists) in transitions(d) {
            match path(&from) {
                Some(p) => {
                    cases.push(serde_json::json!([pos, p, cw]));
                    facts.push((*d, id, from, to, cw, exists));
                }
                None => unset.push(format!("{d} [{id}]: {from} is not set up by controlword")),
            }
        }
    }
    // SYNC0 every 2 ms, the longest cycle the MR-J4-TM takes (§1.3, §7.3.3(4)): a Python loop
    // (about 1.2 ms a turn) is no real-time cycle, and both drives count SYNC0 events without
    // fresh outputs towards a loss fault (the BDHDE's 0x818D, the MR-J4-TM's AL.86); at a 1 ms
    // SYNC0 a loaded machine trips them. Each drive is told the cycle as its manual says: the
    // MR-J4-TM in 0x1C32:02, ns; the BDHDE in 0x60C2 (:01 × 10^(:02) s, §2.4), 2 × 10^−3 s.
    let cycle_ns: u32 = 2_000_000;
    let setup = serde_json::json!([
        [[0x1C32, 2, 4, cycle_ns]],
        [[0x60C2, 1, 1, 2], [0x60C2, 2, 1, -3]],
    ]);
    let arg = serde_json::Value::Array(cases).to_string();
    let (_, v) = python_master::run(
        "pysoem",
        seg,
        TRANSITIONS_SCRIPT,
        &[&arg, &setup.to_string(), &cycle_ns.to_string()],
    );
    assert_eq!(v["count"], 2, "{v}");
    let results = v["results"].as_array().expect("results");
    assert_eq!(results.len(), facts.len());
    let mut wrong = Vec::new();
    let mut checked = std::collections::BTreeMap::new();
    for ((d, id, from, to, cw, exists), r) in facts.iter().zip(results) {
        let start = r["start"].as_str().unwrap_or("?");
        let seen: Vec<&str> = r["seen"]
            .as_array()
            .map(|a| a.iter().filter_map(|x| x.as_str()).collect())
            .unwrap_or_default();
        if r["reached"] != true || start != from {
            // An idle motor leaves Quick stop active at once (quick-stop codes ending in
            // Switch on disabled): that start cannot be held.
            unset.push(format!("{d} [{id}]: {from} not set up (reached {start})"));
            continue;
        }
        // The transition the controlword caused: the first state after the start state.
        let first = seen.iter().copied().find(|s| *s != from.as_str());
        let sod = Some("Switch on disabled");
        if first == sod
            && to != "Switch on disabled"
            && (from == "Quick stop active" || to == "Quick stop active")
        {
            // Quick stop active on an idle motor lasts no cycle (quick-stop codes ending in
            // Switch on disabled): the transition into or out of it cannot be seen.
            unset.push(format!(
                "{d} [{id}]: Quick stop active not held by an idle motor"
            ));
            continue;
        }
        *checked.entry(*d).or_insert(0) += 1;
        if (first == Some(to.as_str())) != *exists {
            wrong.push(format!(
                "{d} [{id}]: {from} with controlword 0x{cw:04X} showed {seen:?}; the manual says \
                 it {} go to {to}",
                if *exists { "does" } else { "does not" }
            ));
        }
    }
    eprintln!("not set up: {unset:#?}");
    eprintln!(
        "faults reset between cases ([position, 0x603F]): {}",
        v["faults"]
    );
    assert!(wrong.is_empty(), "{wrong:#?}");
    for d in drives {
        let n = checked.get(d).copied().unwrap_or(0);
        assert!(
            n >= 10,
            "{d}: only {n} transition facts checked; not set up: {unset:#?}"
        );
    }
}
