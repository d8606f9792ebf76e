//! The scope of a recording (`ecdrive run --record`): per drive (titled by its position and
//! name), position, following error, velocity and torque against time on shared time axes,
//! demand and actual value as separate series with a legend, in the run's units (user units,
//! unit/s, % of rated torque) where the recording has them; the mode of operation as coloured
//! bands behind every panel, the cycles with the statusword's fault bit as red bands, touch-probe
//! latches as marks on the position. A quantity without meaning in a mode (the following error
//! outside csp, a velocity demand outside csv and pv) has no line there. Drawn with plotters
//! into SVG.

use plotters::prelude::*;
use std::collections::BTreeMap;
use std::path::Path;

/// A recording or its plot could not be read or drawn.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// Reading the file.
    #[error("{file}: {source}")]
    Io {
        /// The file.
        file: String,
        /// Why.
        source: std::io::Error,
    },
    /// A line of the recording is not what `--record` writes.
    #[error("{file}:{line}: {why}")]
    Format {
        /// The file.
        file: String,
        /// Line number (1-based).
        line: usize,
        /// What is wrong.
        why: String,
    },
    /// Drawing.
    #[error("drawing {file}: {why}")]
    Draw {
        /// The output file.
        file: String,
        /// Why.
        why: String,
    },
}

/// One axis of a recording, in the recording's physical units where it has them (the run's
/// user unit or counts, unit/s, % of rated torque), else in counts and the drive's units.
/// `None` where the column is empty: the quantity has no meaning in that cycle's mode.
#[derive(Debug, Default, Clone)]
pub struct AxisSeries {
    /// Position on the segment, if the recording names it.
    pub position: Option<u16>,
    /// The drive's name, if the recording names it.
    pub drive: String,
    /// The position unit of `demand`, `actual` and `following_error` ("count", "deg").
    pub unit: String,
    /// Whether velocity and torque are physical (unit/s, % rated) or in drive units.
    pub physical: bool,
    /// Time, s.
    pub t: Vec<f64>,
    /// Position demand.
    pub demand: Vec<Option<f64>>,
    /// Actual position.
    pub actual: Vec<f64>,
    /// Following error.
    pub following_error: Vec<Option<f64>>,
    /// Velocity demand.
    pub velocity_demand: Vec<Option<f64>>,
    /// Actual velocity.
    pub velocity: Vec<f64>,
    /// Torque demand.
    pub torque_demand: Vec<Option<f64>>,
    /// Actual torque.
    pub torque: Vec<f64>,
    /// Mode of operation display.
    pub mode: Vec<i8>,
    /// Statusword.
    pub statusword: Vec<u16>,
    /// Touch-probe latches: time, probe (1 or 2), latched position (in `unit`).
    pub latches: Vec<(f64, u8, f64)>,
    /// Each probe's column in the last cycle read.
    last_latch: [Option<f64>; 2],
}

/// A recording, by axis.
#[derive(Debug, Default, Clone)]
pub struct Recorded {
    /// The axes, by index.
    pub axes: BTreeMap<u16, AxisSeries>,
}

/// Read a recording written by `ecdrive run --record`.
pub fn read(path: &Path) -> Result<Recorded, PlotError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| PlotError::Io {
        file: file.clone(),
        source,
    })?;
    let mut lines = text.lines();
    let header = lines.next().ok_or_else(|| PlotError::Format {
        file: file.clone(),
        line: 1,
        why: "empty file".into(),
    })?;
    let cols: Vec<&str> = header.split(',').collect();
    let col = |name: &str| {
        cols.iter()
            .position(|c| *c == name)
            .ok_or_else(|| PlotError::Format {
                file: file.clone(),
                line: 1,
                why: format!(
                    "no column {name} (not a recording of this version's `ecdrive run --record`?)"
                ),
            })
    };
    let names = [
        "time_s",                      // 0
        "axis",                        // 1
        "mode",                        // 2
        "statusword_hex",              // 3
        "position",                    // 4
        "drive",                       // 5
        "unit",                        // 6
        "demand_counts",               // 7
        "actual_counts",               // 8
        "following_error_counts",      // 9
        "velocity_demand_drive_units", // 10
        "velocity_drive_units",        // 11
        "torque_demand_drive_units",   // 12
        "torque_drive_units",          // 13
        "demand",                      // 14
        "actual",                      // 15
        "following_error",             // 16
        "velocity_demand_per_s",       // 17
        "velocity_per_s",              // 18
        "torque_demand_percent",       // 19
        "torque_percent",              // 20
        "probe1",                      // 21
        "probe2",                      // 22
        "probe1_counts",               // 23
        "probe2_counts",               // 24
    ];
    let mut c = [0usize; 25];
    for (k, n) in names.iter().enumerate() {
        c[k] = col(n)?;
    }
    let mut rec = Recorded::default();
    for (n, l) in lines.enumerate() {
        let f: Vec<&str> = l.split(',').collect();
        let bad = |what: &str| PlotError::Format {
            file: file.clone(),
            line: n + 2,
            why: format!("{what} is not a number"),
        };
        let text = |i: usize| f.get(c[i]).copied().unwrap_or("");
        // An empty cell is "no meaning in this mode"; anything else must be a number.
        let opt = |i: usize| -> Result<Option<f64>, PlotError> {
            match text(i) {
                "" => Ok(None),
                v => v.parse::<f64>().map(Some).map_err(|_| bad(names[i])),
            }
        };
        let num = |i: usize| opt(i)?.ok_or_else(|| bad(names[i]));
        let axis = num(1)? as u16;
        let a = rec.axes.entry(axis).or_default();
        if a.t.is_empty() {
            a.position = text(4).parse().ok();
            a.drive = text(5).to_string();
            a.physical = !text(6).is_empty();
            a.unit = if a.physical {
                text(6).to_string()
            } else {
                "count".to_string()
            };
        }
        // Physical columns where the recording has them, else the raw ones.
        let k = |phys: usize, raw: usize| if a.physical { phys } else { raw };
        a.t.push(num(0)?);
        a.mode.push(num(2)? as i8);
        let sw = u16::from_str_radix(text(3), 16).map_err(|_| bad("statusword_hex"))?;
        a.statusword.push(sw);
        a.demand.push(opt(k(14, 7))?);
        let actual = num(k(15, 8))?;
        a.actual.push(actual);
        a.following_error.push(opt(k(16, 9))?);
        a.velocity_demand.push(opt(k(17, 10))?);
        a.velocity.push(num(k(18, 11))?);
        a.torque_demand.push(opt(k(19, 12))?);
        a.torque.push(num(k(20, 13))?);
        // A latch is drawn in the cycle it appears (the column was empty or held another
        // position before).
        for (probe, i) in [(1u8, k(21, 23)), (2, k(22, 24))] {
            let v = opt(i)?;
            let slot = usize::from(probe - 1);
            if let Some(v) = v
                && a.last_latch[slot] != Some(v)
            {
                let t = num(0)?;
                a.latches.push((t, probe, v));
            }
            a.last_latch[slot] = v;
        }
    }
    Ok(rec)
}

/// The panels drawn for each axis, top to bottom.
pub const PANELS: [&str; 4] = ["position", "following error", "velocity", "torque"];

fn range(v: &[f64]) -> (f64, f64) {
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !lo.is_finite() || !hi.is_finite() {
        return (-1.0, 1.0);
    }
    // A constant (a torque that stays 0): ±1 around it, not a span of 10^-9 with nine-digit
    // labels.
    if hi - lo <= 1e-9 * hi.abs().max(1.0) {
        return (lo - 1.0, hi + 1.0);
    }
    let pad = ((hi - lo) * 0.05)
        .max(1e-6 * hi.abs().max(lo.abs()))
        .max(1e-9);
    (lo - pad, hi + pad)
}

/// The mode bands: (0x6060 code, name, colour).
pub const MODES: [(i8, &str, RGBColor); 8] = [
    (1, "pp", RGBColor(230, 159, 0)),
    (3, "pv", RGBColor(86, 180, 233)),
    (4, "tq", RGBColor(204, 121, 167)),
    (6, "hm", RGBColor(240, 228, 66)),
    (7, "ip", RGBColor(120, 94, 240)),
    (8, "csp", RGBColor(0, 114, 178)),
    (9, "csv", RGBColor(0, 158, 115)),
    (10, "cst", RGBColor(213, 94, 0)),
];

fn mode_band(mode: i8) -> (String, RGBAColor) {
    match MODES.iter().find(|(c, _, _)| *c == mode) {
        Some((_, name, colour)) => (name.to_string(), colour.mix(0.12)),
        None if mode == 0 => ("no mode".to_string(), BLACK.mix(0.04)),
        None => (format!("mode {mode}"), BLACK.mix(0.04)),
    }
}

/// Runs of equal values: (first index, last index, value).
fn runs<T: PartialEq + Copy>(v: &[T]) -> Vec<(usize, usize, T)> {
    let mut out = Vec::new();
    let mut start = 0;
    for i in 1..=v.len() {
        if i == v.len() || v[i] != v[start] {
            out.push((start, i - 1, v[start]));
            start = i;
        }
    }
    out
}

/// The defined stretches of a series with gaps, as point lists.
fn stretches<'a>(t: &'a [f64], v: &'a [Option<f64>]) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut cur = Vec::new();
    for (t, v) in t.iter().zip(v) {
        match v {
            Some(v) => cur.push((*t, *v)),
            None if !cur.is_empty() => out.push(std::mem::take(&mut cur)),
            None => {}
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// A tick label with as many decimals as the panel's span needs (a following error of
/// 0.0004 rev is not "0.0").
fn tick(v: f64, span: f64) -> String {
    let decimals = if span > 0.0 && span.is_finite() {
        (2.0 - span.log10().floor()).clamp(0.0, 9.0) as usize
    } else {
        1
    };
    let s = format!("{v:.decimals$}");
    // "-0.000" is 0.
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

/// How a panel of an axis is titled: "position 2 (BDHDE): velocity (deg/s)"; an axis whose
/// recording does not name its position is "axis N".
pub fn caption(axis: u16, a: &AxisSeries, panel: &str) -> String {
    let who = match a.position {
        Some(p) if a.drive.is_empty() => format!("position {p}"),
        Some(p) => format!("position {p} ({})", a.drive),
        None => format!("axis {axis}"),
    };
    let unit = match (panel, a.physical) {
        ("position" | "following error", _) => a.unit.clone(),
        ("velocity", true) => format!("{}/s", a.unit),
        ("torque", true) => "% of rated torque".to_string(),
        _ => "drive units".to_string(),
    };
    format!("{who}: {panel} ({unit})")
}

/// Draw `rec` into the SVG file `out`: one panel per axis and quantity ([`PANELS`]), titled by
/// position and drive; the mode of operation as coloured bands behind every panel and the
/// cycles with the statusword's fault bit as red bands; demands and actual values as separate
/// series with a legend; touch-probe latches marked on the position. Units as recorded
/// ([`AxisSeries`]).
pub fn draw(rec: &Recorded, out: &Path) -> Result<(), PlotError> {
    let file = out.display().to_string();
    let err = |e: &dyn std::fmt::Display| PlotError::Draw {
        file: file.clone(),
        why: e.to_string(),
    };
    let rows = rec.axes.len().max(1) * PANELS.len();
    let root = SVGBackend::new(out, (1200, (rows * 200) as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let panels = root.split_evenly((rows, 1));
    let t_end = rec
        .axes
        .values()
        .filter_map(|a| a.t.last().copied())
        .fold(0.0, f64::max)
        .max(1e-3);
    for (k, (axis, a)) in rec.axes.iter().enumerate() {
        type Lines<'a> = Vec<(&'static str, RGBColor, Vec<Option<f64>>)>;
        let some = |v: &[f64]| v.iter().map(|x| Some(*x)).collect::<Vec<_>>();
        let series: [Lines; 4] = [
            vec![
                ("demand", BLUE, a.demand.clone()),
                ("actual", RED, some(&a.actual)),
            ],
            vec![("following error (csp)", BLACK, a.following_error.clone())],
            vec![
                ("demand", BLUE, a.velocity_demand.clone()),
                ("actual", GREEN, some(&a.velocity)),
            ],
            vec![
                ("demand", BLUE, a.torque_demand.clone()),
                ("actual", MAGENTA, some(&a.torque)),
            ],
        ];
        let faults: Vec<bool> = a.statusword.iter().map(|sw| sw & 0x0008 != 0).collect();
        for (p, (panel, lines)) in PANELS.iter().zip(series).enumerate() {
            let area = &panels[k * PANELS.len() + p];
            let mut all: Vec<f64> = lines
                .iter()
                .flat_map(|(_, _, v)| v.iter().flatten().copied())
                .collect();
            if p == 0 {
                all.extend(a.latches.iter().map(|l| l.2));
            }
            let (lo, hi) = range(&all);
            let mut chart = ChartBuilder::on(area)
                .caption(caption(*axis, a, panel), ("sans-serif", 14))
                .margin(6)
                .x_label_area_size(34)
                .y_label_area_size(80)
                .build_cartesian_2d(0.0..t_end, lo..hi)
                .map_err(|e| err(&e))?;
            let span = hi - lo;
            chart
                .configure_mesh()
                .y_label_formatter(&|v| tick(*v, span))
                .x_desc("time (s)")
                .light_line_style(BLACK.mix(0.05))
                .draw()
                .map_err(|e| err(&e))?;
            // The modes as bands, each mode named once in the legend.
            let mut named: Vec<i8> = Vec::new();
            for (i0, i1, mode) in runs(&a.mode) {
                let (name, colour) = mode_band(mode);
                let end = a.t.get(i1 + 1).copied().unwrap_or(a.t[i1]);
                let band = chart
                    .draw_series(std::iter::once(Rectangle::new(
                        [(a.t[i0], lo), (end, hi)],
                        colour.filled(),
                    )))
                    .map_err(|e| err(&e))?;
                // Named in the legend of the position panel (the bands are the same below).
                if p == 0 && !named.contains(&mode) {
                    named.push(mode);
                    band.label(name).legend(move |(x, y)| {
                        Rectangle::new([(x, y - 5), (x + 16, y + 5)], colour.filled())
                    });
                }
            }
            // Faults: red bands over every panel.
            let mut fault_named = false;
            for (i0, i1, fault) in runs(&faults) {
                if !fault {
                    continue;
                }
                let end = a.t.get(i1 + 1).copied().unwrap_or(a.t[i1]);
                let band = chart
                    .draw_series(std::iter::once(Rectangle::new(
                        [(a.t[i0], lo), (end, hi)],
                        RED.mix(0.25).filled(),
                    )))
                    .map_err(|e| err(&e))?;
                if !fault_named {
                    fault_named = true;
                    band.label("fault (statusword bit 3)").legend(|(x, y)| {
                        Rectangle::new([(x, y - 5), (x + 16, y + 5)], RED.mix(0.25).filled())
                    });
                }
            }
            for (name, colour, v) in lines {
                for (n, pts) in stretches(&a.t, &v).into_iter().enumerate() {
                    let s = chart
                        .draw_series(LineSeries::new(pts, colour))
                        .map_err(|e| err(&e))?;
                    if n == 0 {
                        s.label(name).legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 16, y)], colour)
                        });
                    }
                }
            }
            if p == 0 {
                for probe in [1u8, 2] {
                    let marks: Vec<(f64, f64)> = a
                        .latches
                        .iter()
                        .filter(|l| l.1 == probe)
                        .map(|l| (l.0, l.2))
                        .collect();
                    if marks.is_empty() {
                        continue;
                    }
                    chart
                        .draw_series(
                            marks
                                .into_iter()
                                .map(|pt| TriangleMarker::new(pt, 6, BLACK.filled())),
                        )
                        .map_err(|e| err(&e))?
                        .label(if probe == 1 {
                            "probe 1 latch"
                        } else {
                            "probe 2 latch"
                        })
                        .legend(|(x, y)| TriangleMarker::new((x + 8, y), 5, BLACK.filled()));
                }
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK.mix(0.3))
                .label_font(("sans-serif", 11))
                .draw()
                .map_err(|e| err(&e))?;
        }
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
