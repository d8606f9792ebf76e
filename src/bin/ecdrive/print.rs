//! Text output of the commands: tables and listings in the style of the IgH `ethercat` tool.

use ecdrive_cli::app::ethercat::tools::esi::{EsiCheck, EsiSummary};
use ecdrive_cli::app::ethercat::tools::run::{
    CycleSummary, DriveRunReport, IoRunReport, RunProgress, RunReport,
};
use ecdrive_cli::app::ethercat::tools::sii::{SiiDump, SiiInfo};
use ecdrive_cli::app::ethercat::tools::{
    OdListing, PdoReport, RegisterData, SdoValue, SlaveReport, StateChange,
};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Print rows as columns separated by two spaces, each as wide as its widest cell.
pub fn table(rows: &[Vec<String>]) {
    let n = rows.iter().map(Vec::len).max().unwrap_or(0);
    let widths: Vec<usize> = (0..n)
        .map(|c| {
            rows.iter()
                .filter_map(|r| r.get(c))
                .map(|s| s.chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    for r in rows {
        let mut line = String::new();
        for (c, cell) in r.iter().enumerate() {
            if c + 1 == r.len() {
                line.push_str(cell);
            } else {
                let w = widths.get(c).copied().unwrap_or(0);
                line.push_str(&format!("{cell:w$}  "));
            }
        }
        println!("{}", line.trim_end());
    }
}

pub fn slaves(list: &[SlaveReport], verbose: bool) {
    if verbose {
        for (i, s) in list.iter().enumerate() {
            if i > 0 {
                println!();
            }
            slave_verbose(s);
        }
        return;
    }
    let mut rows = vec![
        [
            "POS", "ADDR", "ALIAS", "STATE", "VENDOR", "PRODUCT", "REVISION", "SERIAL", "DC",
            "MAILBOX", "PROFILE", "NAME",
        ]
        .map(String::from)
        .to_vec(),
    ];
    for s in list {
        rows.push(vec![
            s.position.to_string(),
            format!("0x{:04X}", s.address),
            s.alias.to_string(),
            // The state the device was in when found: discovery takes every device to PREOP.
            match &s.found {
                Some(f) => match f.code {
                    Some(c) => format!("{}(0x{c:04X})", f.state),
                    None => f.state.clone(),
                },
                None => "?".into(),
            },
            format!("0x{:08X}", s.vendor_id),
            format!("0x{:08X}", s.product_code),
            format!("0x{:08X}", s.revision),
            s.serial.to_string(),
            if s.dc { "yes" } else { "no" }.to_string(),
            if s.mailbox_protocols.is_empty() {
                "-".into()
            } else {
                s.mailbox_protocols.join(",")
            },
            s.profile.clone().unwrap_or_else(|| "-".into()),
            match &s.description {
                Some(d) if d != &s.name => format!("{} ({d})", s.name),
                _ => s.name.clone(),
            },
        ]);
    }
    table(&rows);
}

fn slave_verbose(s: &SlaveReport) {
    println!(
        "=== Position {}, station address 0x{:04X} ===",
        s.position, s.address
    );
    println!("Name: {}", s.name);
    if let Some(d) = &s.description {
        println!("Description: {d}");
    }
    println!("Alias: {}", s.alias);
    let state =
        |al: &ecdrive_cli::app::ethercat::tools::AlStatusReport| match (&al.code, &al.code_text) {
            (Some(c), Some(t)) => format!("{} (AL status code 0x{c:04X}: {t})", al.state),
            _ => al.state.clone(),
        };
    match &s.found {
        Some(f) => println!("State when found: {}", state(f)),
        None => println!("State when found: unknown (no reply to the AL status read)"),
    }
    println!("State after discovery: {}", state(&s.al));
    println!("Identity:");
    println!("  Vendor Id:       0x{:08X}", s.vendor_id);
    println!("  Product code:    0x{:08X}", s.product_code);
    println!("  Revision number: 0x{:08X}", s.revision);
    println!("  Serial number:   {}", s.serial);
    match &s.profile {
        Some(p) => println!(
            "Profile: {p}{}",
            s.detail
                .as_ref()
                .and_then(|d| d.profile_vendor.as_ref())
                .map(|v| format!(" ({v})"))
                .unwrap_or_default()
        ),
        None => println!("Profile: none (unknown device)"),
    }
    println!(
        "Distributed clocks: {}",
        if s.dc {
            format!("yes, {}", s.dc_kind)
        } else {
            "no".into()
        }
    );
    let Some(d) = &s.detail else {
        return;
    };
    println!(
        "ESC: type 0x{:02X}, revision {}, build {}, {} FMMUs, {} SyncManagers, {} KiB RAM",
        d.esc.esc_type,
        d.esc.revision,
        d.esc.build,
        d.esc.fmmus,
        d.esc.sync_managers,
        d.esc.ram_kib
    );
    println!("Propagation delay: {} ns", d.propagation_delay_ns);
    println!("Ports:");
    for p in &d.ports {
        println!(
            "  {}  link {}  loop {}  communication {}",
            p.port,
            if p.link { "up  " } else { "down" },
            if p.loop_closed { "closed" } else { "open  " },
            if p.communication { "yes" } else { "no" }
        );
    }
    println!("Mailboxes:");
    match &d.mailbox {
        Some(m) => println!(
            "  Standard RX: 0x{:04X}/{}, TX: 0x{:04X}/{}",
            m.rx_offset, m.rx_size, m.tx_offset, m.tx_size
        ),
        None => println!("  none"),
    }
    println!(
        "  Supported protocols: {}",
        if s.mailbox_protocols.is_empty() {
            "none".into()
        } else {
            s.mailbox_protocols.join(", ")
        }
    );
    println!("EEPROM: {} bytes", d.eeprom_bytes);
}

pub fn sdo_value(v: &SdoValue) {
    match &v.hex {
        Some(h) => println!("{h} {}", v.text),
        None => println!("{}", v.text),
    }
}

pub fn downloaded(v: &SdoValue) {
    println!(
        "{} = {}{}, {}, type from {}",
        v.address,
        v.text,
        v.hex
            .as_ref()
            .map(|h| format!(" ({h})"))
            .unwrap_or_default(),
        v.data_type,
        match v.type_source {
            ecdrive_cli::app::ethercat::tools::TypeSource::Explicit => "--type",
            ecdrive_cli::app::ethercat::tools::TypeSource::Profile => "profile",
            ecdrive_cli::app::ethercat::tools::TypeSource::SdoInfo => "SDO information",
        }
    );
}

pub fn sdos(listing: &OdListing) {
    if let Some(n) = &listing.note {
        println!("({n})");
    }
    for o in &listing.objects {
        println!("SDO 0x{:04X}, {}, \"{}\"", o.index, o.object_code, o.name);
        for e in &o.entries {
            let map = e
                .pdo_mapping
                .as_ref()
                .map(|m| format!(", {m} mappable"))
                .unwrap_or_default();
            let val = e
                .value
                .as_ref()
                .map(|v| format!(" = {v}"))
                .unwrap_or_default();
            println!(
                "  {}, {}, {}, {} bit{map}, \"{}\"{val}",
                e.address, e.access, e.data_type, e.bit_len, e.name
            );
        }
    }
    for p in &listing.problems {
        println!(
            "(not listed: {} {}: {}{})",
            p.what,
            p.address,
            p.reason,
            if p.stopped {
                "; the listing stopped here"
            } else {
                ""
            }
        );
    }
}

pub fn reset(r: &ecdrive_cli::app::ethercat::tools::reset::ResetReport) {
    for d in &r.drives {
        match (&d.fault, d.cleared) {
            (Some(f), Some(true)) => println!(
                "drive {} ({}): {}: {f}; reset, now {}",
                d.position, d.drive, d.before, d.after
            ),
            (Some(f), _) => println!(
                "drive {} ({}): {}: {f}; NOT cleared, still {}",
                d.position, d.drive, d.before, d.after
            ),
            (None, _) => println!("drive {} ({}): {}, no fault", d.position, d.drive, d.before),
        }
    }
}

pub fn can_reset(r: &ecdrive_cli::app::canopen::reset::CanResetReport) {
    if r.drives.is_empty() {
        println!("{}: no drive found", r.bus);
    }
    for d in &r.drives {
        match (&d.fault, d.cleared) {
            (Some(f), Some(true)) => println!(
                "node {} ({}): {}: {f}; reset, now {}",
                d.node, d.drive, d.before, d.after
            ),
            (Some(f), _) => println!(
                "node {} ({}): {}: {f}; NOT cleared, still {}",
                d.node, d.drive, d.before, d.after
            ),
            (None, _) => println!("node {} ({}): {}, no fault", d.node, d.drive, d.before),
        }
    }
}

pub fn pdos(r: &PdoReport) {
    for sm in &r.sync_managers {
        let size = match sm.mapped_bytes {
            Some(b) => format!("{b:4} (mapped)"),
            None => format!("{:4}", sm.default_size),
        };
        println!(
            "SM{}: PhysAddr 0x{:04X}, Size {size}, ControlRegister 0x{:02X}, Enable {}, {}",
            sm.index,
            sm.start,
            sm.control,
            u8::from(sm.enable),
            sm.kind
        );
        for p in &sm.pdos {
            println!(
                "  {} 0x{:04X} \"{}\" ({} bit)",
                p.direction,
                p.index,
                p.name.as_deref().unwrap_or(""),
                p.bits
            );
            for e in &p.entries {
                println!(
                    "    PDO entry {}, {:2} bit, offset {:3}, \"{}\"",
                    e.address,
                    e.bits,
                    e.bit_offset,
                    e.name.as_deref().unwrap_or("")
                );
            }
        }
    }
    if r.source == ecdrive_cli::app::ethercat::tools::PdoSource::Sii {
        println!("(from the SII: the device has no CoE)");
    }
}

pub fn states(list: &[StateChange]) {
    let mut rows = vec![
        ["POS", "DRIVE", "REQUESTED", "REACHED", "RESULT"]
            .map(String::from)
            .to_vec(),
    ];
    for c in list {
        rows.push(vec![
            c.position.to_string(),
            c.drive.clone(),
            c.requested.clone(),
            c.reached.clone(),
            if c.ok {
                "ok".into()
            } else {
                match (c.al_status_code, &c.code_text) {
                    (Some(k), Some(t)) => format!("refused: AL status code 0x{k:04X} ({t})"),
                    _ => "not reached".into(),
                }
            },
        ]);
    }
    table(&rows);
}

pub fn register(r: &RegisterData) {
    let bytes: Vec<String> = r
        .bytes
        .as_bytes()
        .chunks(2)
        .map(|c| String::from_utf8_lossy(c).into_owned())
        .collect();
    let value = match (&r.value, &r.data_type) {
        (Some(v), Some(t)) => format!(
            "  = {} ({t})",
            serde_json::to_string(v)
                .unwrap_or_default()
                .trim_matches('"')
        ),
        _ => String::new(),
    };
    println!("0x{:04X}: {}{value}", r.address, bytes.join(" "));
}

pub fn hex_dump(b: &[u8]) {
    for (i, chunk) in b.chunks(16).enumerate() {
        let hex: Vec<String> = chunk.iter().map(|x| format!("{x:02x}")).collect();
        let text: String = chunk
            .iter()
            .map(|&x| {
                if x.is_ascii_graphic() || x == b' ' {
                    x as char
                } else {
                    '.'
                }
            })
            .collect();
        println!("{:06x}  {:<47}  {text}", i * 16, hex.join(" "));
    }
}

pub fn sii(d: &SiiDump, i: &SiiInfo) {
    println!(
        "EEPROM of position {} ({}): {} bytes read, size word {} bytes, SII version {}, checksum {}",
        d.position,
        d.drive,
        d.bytes.len(),
        i.size_bytes,
        i.version,
        if i.checksum_ok { "ok" } else { "WRONG" }
    );
    println!(
        "Identity: vendor 0x{:08X}, product 0x{:08X}, revision 0x{:08X}, serial {}",
        i.vendor_id, i.product_code, i.revision, i.serial
    );
    println!(
        "Config: PDI control 0x{:04X}, PDI config 0x{:04X}, SYNC impulse {} × 10 ns, alias {}",
        i.pdi_control, i.pdi_config, i.sync_impulse_len, i.alias
    );
    if let Some(m) = &i.mailbox {
        println!(
            "Mailbox: RX 0x{:04X}/{}, TX 0x{:04X}/{}, protocols {}",
            m.rx_offset,
            m.rx_size,
            m.tx_offset,
            m.tx_size,
            i.protocols.join(", ")
        );
    }
    if let Some(g) = &i.general {
        println!(
            "General: order {:?}, name {:?}, group {:?}, CoE details 0x{:02X}, flags 0x{:02X}",
            g.order, g.name, g.group, g.coe_details, g.flags
        );
    }
    println!("Categories:");
    for c in &i.categories {
        println!(
            "  {:>5}  {:<15} word 0x{:04X}, {} words",
            c.kind, c.name, c.word, c.words
        );
    }
    for (n, s) in i.sync_managers.iter().enumerate() {
        println!(
            "SM{n}: start 0x{:04X}, size {}, control 0x{:02X}, enable {}, {}",
            s.start, s.length, s.control, s.enable, s.kind
        );
    }
    for (dir, pdos) in [("RxPDO", &i.rx_pdos), ("TxPDO", &i.tx_pdos)] {
        for p in pdos {
            println!(
                "{dir} 0x{:04X} \"{}\" (SM {}, {} entries)",
                p.index,
                p.name,
                if p.sm == 0xFF {
                    "-".to_string()
                } else {
                    p.sm.to_string()
                },
                p.entries.len()
            );
        }
    }
    for m in &i.dc_modes {
        println!(
            "DC mode {:?}: AssignActivate 0x{:04X}, SYNC0 cycle {} ns, shift {} ns",
            m.name, m.assign_activate, m.cycle_time0, m.shift_time0
        );
    }
}

pub fn eds_summary(s: &ecdrive_cli::app::canopen::eds::EdsSummary) {
    let hex = |v: Option<u32>| v.map_or_else(|| "-".to_string(), |v| format!("0x{v:08X}"));
    println!(
        "{}: {:?} {:?}, vendor {} product {} revision {}{}",
        s.file,
        s.vendor,
        s.product,
        hex(s.vendor_number),
        hex(s.product_number),
        hex(s.revision_number),
        if s.dcf { " (DCF)" } else { "" }
    );
    println!(
        "  Device type (1000h): {}{}",
        hex(s.device_type),
        if s.cia402 {
            ", a CiA 402 drive"
        } else {
            ", not a CiA 402 drive"
        }
    );
    let n = |v: Option<u16>| v.map_or_else(|| "-".to_string(), |v| v.to_string());
    println!(
        "  PDOs: {} RPDO, {} TPDO; mappable objects: {} into an RPDO, {} into a TPDO",
        n(s.pdos.0),
        n(s.pdos.1),
        s.mappable.0,
        s.mappable.1
    );
    let rates: Vec<String> = s.baud_rates.iter().map(|r| format!("{r}k")).collect();
    println!(
        "  Bit rates: {}; {} objects",
        if rates.is_empty() {
            "-".into()
        } else {
            rates.join(", ")
        },
        s.objects
    );
    println!(
        "  Modes (6502h): {}",
        if s.modes.is_empty() {
            "none declared".into()
        } else {
            s.modes.join(", ")
        }
    );
    for n in &s.notes {
        println!("  Note: {n}");
    }
    for p in &s.plans {
        let side = |v: &[(String, &str)]| {
            v.iter()
                .map(|(o, how)| match *how {
                    "pdo" => o.clone(),
                    "sdo" => format!("{o} (no PDO may carry it: by SDO)"),
                    _ => format!("{o} (absent)"),
                })
                .collect::<Vec<_>>()
                .join(", ")
        };
        println!("    {:4} out {}; in {}", p.mode, side(&p.rx), side(&p.tx));
    }
    if !s.warnings.is_empty() {
        println!("  {} warning(s):", s.warnings.len());
        for w in &s.warnings {
            println!("    {w}");
        }
    }
}

pub fn esi_summary(s: &EsiSummary) {
    println!(
        "{}: vendor 0x{:08X} {:?}{}",
        s.file,
        s.vendor_id,
        s.vendor,
        s.version
            .as_ref()
            .map(|v| format!(", schema {v}"))
            .unwrap_or_default()
    );
    for d in &s.devices {
        println!();
        println!(
            "Device {:?} ({}): product 0x{:08X}, revision {}",
            d.name,
            d.type_name,
            d.product_code,
            d.revision
                .map_or_else(|| "-".to_string(), |r| format!("0x{r:08X}"))
        );
        if let Some(p) = &d.profile {
            println!("  ecdrive profile: {p}");
        }
        println!(
            "  Mailbox: {}",
            if d.mailbox_protocols.is_empty() {
                "none".into()
            } else {
                d.mailbox_protocols.join(", ")
            }
        );
        for sm in &d.sync_managers {
            println!(
                "  SM{}: {:<8} start 0x{:04X}, default size {}, control 0x{:02X}",
                sm.index,
                sm.kind,
                sm.start,
                sm.default_size
                    .map_or_else(|| "-".to_string(), |v| v.to_string()),
                sm.control
            );
        }
        for p in &d.pdos {
            println!(
                "  {} 0x{:04X} {:?}: {} entries, {} bit{}{}",
                p.direction,
                p.index,
                p.name,
                p.entries,
                p.bits,
                p.sm.map(|s| format!(", default on SM{s}"))
                    .unwrap_or_default(),
                if p.fixed { ", fixed" } else { "" }
            );
        }
        if let Some((o, i)) = d.default_image_bytes {
            println!("  Default process image: {o} output bytes, {i} input bytes");
        }
        for m in &d.dc_modes {
            println!("  DC {m}");
        }
        println!("  Dictionary: {} objects", d.dictionary_objects);
        if let Some(b) = d.eeprom_bytes {
            println!("  EEPROM: {b} bytes");
        }
        esi_plan(&d.plan);
    }
}

/// The "as ecdrive would drive it" part of `esi show`.
fn esi_plan(p: &ecdrive::esi::DrivePlan) {
    use ecdrive::esi::MappingSource;
    if let Some(why) = &p.not_a_drive {
        println!("  From this file alone: {why}");
        return;
    }
    println!(
        "  From this file alone: cyclic modes {} ({})",
        p.modes.join(", "),
        if p.modes_from_0x6502 {
            "0x6502"
        } else {
            "assumed: the file gives no 0x6502 default, or 0"
        }
    );
    let side = |r: &Result<ecdrive::esi::DirectionChoice, String>| match r {
        Ok(c) => {
            let pdos: Vec<String> = c.pdos.iter().map(|p| format!("0x{p:04X}")).collect();
            let how = match c.source {
                MappingSource::Default => "default",
                MappingSource::Chosen => "chosen",
                MappingSource::Built => "configured",
            };
            format!("{} ({how})", pdos.join("+"))
        }
        Err(e) => format!("impossible: {e}"),
    };
    for m in &p.mappings {
        println!(
            "    {:<12} RxPDO {}; TxPDO {}",
            m.modes.join("+"),
            side(&m.rx),
            side(&m.tx)
        );
    }
    match &p.dc {
        Some(dc) => println!(
            "    DC: {:?}, AssignActivate 0x{:04X}, SYNC0 = {} x cycle, shift {} ns",
            dc.name, dc.assign_activate, dc.sync0_factor, dc.shift_ns
        ),
        None => println!("    DC: none (free run)"),
    }
    match p.cycle_time_writable {
        Some(true) => println!("    0x1C32:02 (cycle time): writable in PRE-OP"),
        Some(false) => println!("    0x1C32:02 (cycle time): read-only"),
        None => println!("    0x1C32:02 (cycle time): not in the dictionary"),
    }
    for c in &p.init_cmds {
        let mut how = Vec::new();
        if c.disabled {
            how.push("disabled: not sent".to_string());
        }
        if c.fixed {
            how.push("fixed".to_string());
        }
        if let Some(ms) = c.timeout_ms {
            how.push(format!("timeout {ms} ms"));
        }
        if c.retries > 0 {
            how.push(format!("retries {}", c.retries));
        }
        if ["0x1C12", "0x1C13", "0x16", "0x17", "0x1A", "0x1B"]
            .iter()
            .any(|p| c.object.starts_with(p))
        {
            how.push("mapping object: ecdrive writes the mapping it chose instead".to_string());
        }
        let how = if how.is_empty() {
            String::new()
        } else {
            format!(" [{}]", how.join(", "))
        };
        println!(
            "    InitCmd line {}: {} {} = {}  {:?}{how}",
            c.line,
            c.transitions.join(","),
            c.object,
            c.data,
            c.comment
        );
    }
}

pub fn esi_check(c: &EsiCheck) {
    if c.valid {
        match c.warnings {
            0 => println!("{}: valid ({} device(s))", c.file, c.devices),
            n => println!(
                "{}: valid ({} device(s)), {n} warning(s): values read past, listed below",
                c.file, c.devices
            ),
        }
    }
    for i in &c.issues {
        let sev = match i.severity {
            ecdrive::esi::Severity::Error => "error",
            ecdrive::esi::Severity::Warning => "warning",
        };
        if i.line > 0 {
            println!(
                "{} line {}, column {}: {sev}: {}",
                c.file, i.line, i.column, i.message
            );
        } else {
            println!("{}: {sev}: {}", c.file, i.message);
        }
    }
}

/// A progress bar on stderr, hidden when stderr is not a terminal.
pub fn progress(what: &str) -> ProgressBar {
    // Length 1 until the operation knows its size, so the bar starts empty.
    let bar = ProgressBar::with_draw_target(Some(1), ProgressDrawTarget::stderr());
    if let Ok(style) = ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len}") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_string());
    bar
}

/// The progress display of `run`.
pub fn run_progress() -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr());
    if let Ok(style) = ProgressStyle::with_template("{spinner} {msg}") {
        bar.set_style(style);
    }
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    bar
}

pub fn update_run_progress(bar: &ProgressBar, p: &RunProgress) {
    let time = match p.duration {
        Some(d) => format!("{:.1}/{:.1} s", p.elapsed.as_secs_f64(), d.as_secs_f64()),
        None => format!("{:.1} s", p.elapsed.as_secs_f64()),
    };
    let steps = if p.steps_total > 0 {
        format!(", program steps {}/{}", p.steps_done, p.steps_total)
    } else {
        String::new()
    };
    bar.set_message(format!("{}: {time}{steps}, cycle {}", p.phase, p.cycles));
}

fn us(ns: u64) -> String {
    format!("{:.1}", ns as f64 / 1000.0)
}

/// The report of `ecdrive run`: the outcome, each device in line order, start-up, the
/// recording, the cycle.
pub fn run_report(r: &RunReport) {
    println!(
        "{} on {}: {} ({}), {:.2} s, cycle {} µs",
        r.config,
        r.target,
        r.outcome.describe(),
        r.reason,
        r.run_seconds,
        r.cycle_ns / 1000
    );
    let last = r
        .drives
        .iter()
        .map(|d| d.position)
        .chain(r.io.iter().map(|o| o.position))
        .max();
    for pos in 0..=last.unwrap_or(0) {
        if let Some(o) = r.io.iter().find(|o| o.position == pos) {
            io_device(o);
        }
        if let Some(d) = r.drives.iter().find(|d| d.position == pos) {
            drive_report(d);
        }
    }
    if let Some(t) = &r.startup {
        println!();
        startup(t);
    }
    if let Some(rec) = &r.record {
        println!(
            "Recorded: {} samples to {}{}",
            rec.samples,
            rec.file,
            if rec.dropped > 0 {
                format!(" ({} dropped: the writer fell behind)", rec.dropped)
            } else {
                String::new()
            }
        );
    }
    if let Some(c) = &r.cycle {
        cycle_report(c);
    }
    if !r.shutdown_ok {
        println!("Not every drive confirmed INIT at the end.");
    }
}

/// A device of the run that is not a drive: its process data and last inputs.
fn io_device(o: &IoRunReport) {
    println!();
    println!(
        "Device {} {} (vendor 0x{:08X} product 0x{:08X}), not driven: {}",
        o.position, o.device.name, o.device.vendor_id, o.device.product_code, o.why
    );
    println!(
        "  Process data:        {} output, {} input bytes",
        o.outputs, o.inputs
    );
    println!(
        "  Last inputs:         {}",
        if o.last_inputs.is_empty() {
            "none".to_string()
        } else {
            o.last_inputs
                .iter()
                .map(|b| format!("{b:02X}"))
                .collect::<Vec<_>>()
                .join(" ")
        }
    );
}

/// A drive of the run: its process data, states, modes, probes, following error, program,
/// errors and warnings.
fn drive_report(d: &DriveRunReport) {
    println!();
    println!(
        "Drive {} {} ({}, vendor 0x{:08X} product 0x{:08X}), start mode {}",
        d.position, d.name, d.device.name, d.device.vendor_id, d.device.product_code, d.mode
    );
    let list = |v: &[u16]| {
        v.iter()
            .map(|i| format!("0x{i:04X}"))
            .collect::<Vec<_>>()
            .join("+")
    };
    println!(
        "  Process data:        RxPDO {} ({} bytes), TxPDO {} ({} bytes)",
        list(&d.pdos.0),
        d.image_bytes.0,
        list(&d.pdos.1),
        d.image_bytes.1
    );
    println!("  States:              {}", d.states.join(" → "));
    println!(
        "  Modes run:           {}",
        if d.modes_run.is_empty() {
            "none".into()
        } else {
            d.modes_run.join(", ")
        }
    );
    for l in &d.probe_latches {
        let at = match (&d.units, l.value) {
            (Some(u), Some(v)) => format!("{v:.4} {} ({} counts)", u.name, l.counts),
            _ => format!("{} counts", l.counts),
        };
        println!(
            "  Touch probe {}:       latched on the {} edge at {at}",
            l.probe, l.edge
        );
    }
    let drive_fe = if d.following_error_drive_stuck {
        "; the drive's 0x60F4 stayed 0 while moving (not trusted)".to_string()
    } else {
        d.max_following_error_drive
            .map_or(String::new(), |v| format!("; drive's 0x60F4 at most {v}"))
    };
    match (&d.units, d.max_following_error_units) {
        (Some(u), Some(v)) => println!(
            "  Max following error: {} counts ({v:.4} {}){drive_fe}",
            d.max_following_error, u.name
        ),
        _ => println!(
            "  Max following error: {} counts{drive_fe}",
            d.max_following_error
        ),
    }
    println!(
        "  Program:             {}/{} steps{}",
        d.steps_done,
        d.program.len(),
        if d.program.is_empty() {
            String::new()
        } else {
            format!(": {}", d.program.join("; "))
        }
    );
    for e in &d.errors {
        println!("  Error:               {e}");
    }
    for w in &d.warnings {
        println!("  Warning:             {w}");
    }
}

/// The cycle of the run: cycles, lost frames and overruns, the frames, the latencies.
fn cycle_report(c: &CycleSummary) {
    println!();
    println!(
        "Cycle: {} cycles, {} lost, {} overruns{}",
        c.cycles,
        c.lost,
        c.overruns,
        match (c.priority, c.cpu) {
            (Some(p), Some(cpu)) => format!(", SCHED_FIFO {p} on CPU {cpu}"),
            (Some(p), None) => format!(", SCHED_FIFO {p}"),
            (None, Some(cpu)) => format!(", CPU {cpu}"),
            (None, None) => String::new(),
        }
    );
    let f = &c.frames;
    let per_s = |n: u64| n as f64 / f.seconds.max(1e-9);
    println!(
        "Frames: {} sent ({:.0}/s), {} answered, {} retransmitted; cycles {} lost, {} late, {} with a wrong working counter",
        f.sent,
        per_s(f.sent),
        f.answered,
        f.retransmitted,
        f.lost,
        f.late,
        f.wrong_wkc
    );
    println!("                 p50 µs    p99 µs    max µs");
    for (name, s) in [
        ("wake latency", &c.wake_latency),
        ("period", &c.period),
        ("exchange", &c.exchange),
    ] {
        println!(
            "  {name:<12} {:>9} {:>9} {:>9}",
            us(s.p50),
            us(s.p99),
            us(s.max)
        );
    }
    for w in &c.rt_warnings {
        println!("  warning: {w}");
    }
}

/// Where start-up's time went, one line: milliseconds, frames sent in brackets (and the frames
/// of ethercrab's answered from what ecdrive read, which were not sent).
pub fn startup(t: &ecdrive::master::StartupTimes) {
    let f = &t.frames;
    let answered = |n: u64| {
        if n > 0 {
            format!(", {n} answered")
        } else {
            String::new()
        }
    };
    println!(
        "Start-up: {:.1} ms to {}: discovery {:.1} [{} frames{}] (SII {:.1} [{}]), CoE {:.1} [{}], image {:.1} [{}{}], DC settle {:.1} [{}], SAFE-OP {:.1} [{}]{}",
        t.total_ms,
        if t.op_ms.is_some() { "OP" } else { "SAFE-OP" },
        t.discovery_ms,
        f.discovery,
        answered(f.answered_discovery),
        t.sii_ms,
        f.sii,
        t.coe_ms,
        f.coe,
        t.image_ms,
        f.image,
        answered(f.answered_image),
        t.dc_settle_ms,
        f.dc_settle,
        t.safe_op_ms,
        f.safe_op,
        t.op_ms.map(|o| format!(", OP {o:.1}")).unwrap_or_default()
    );
}

/// A CANopen run's summary: per drive its program, states, modes and final position, then how
/// the run ended and every EMCY decoded.
pub fn can_run_report(r: &ecdrive_cli::app::canopen::run::CanRunReport) {
    println!(
        "{}: CANopen run on {}, SYNC every {} µs",
        r.config, r.bus, r.cycle_us
    );
    for d in &r.drives {
        let position = match d.position_user {
            Some(u) => format!("{u:.4} {} ({} counts)", d.units, d.position),
            None => format!("{} counts", d.position),
        };
        println!(
            "node {} ({}): program {}; modes {}; at {position}",
            d.node,
            d.drive,
            if d.program.is_empty() {
                "none"
            } else if d.program_done {
                "done"
            } else {
                "not finished"
            },
            if d.modes.is_empty() {
                "-".to_string()
            } else {
                d.modes.join(" → ")
            },
        );
        println!("  states: {}", d.states.join(" → "));
        for l in &d.probe_latches {
            let at = match l.value {
                Some(v) => format!("{v:.4} {} ({} counts)", d.units, l.counts),
                None => format!("{} counts", l.counts),
            };
            println!(
                "  touch probe {}: latched on the {} edge at {at}",
                l.probe, l.edge
            );
        }
        for e in &d.errors {
            println!("  error: {e}");
        }
    }
    for e in &r.emergencies {
        println!("EMCY: {e}");
    }
    for w in &r.warnings {
        println!("warning: {w}");
    }
    if let Some(rec) = &r.record {
        println!("recorded {} samples to {}", rec.samples, rec.file);
    }
    if let Some(c) = &r.candump {
        println!("logged {} CAN frames to {}", c.frames, c.file);
    }
    println!(
        "{}: {} ({} cycles, {:.3} s of bus time)",
        r.outcome.describe(),
        r.reason,
        r.cycles,
        r.bus_time_us as f64 * 1e-6
    );
}
