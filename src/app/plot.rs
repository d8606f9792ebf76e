//! The scope of a recording (`ecdrive run --record`): per axis, demand and actual position,
//! following error, velocity and torque against time on shared time axes, the mode of
//! operation as coloured bands behind the position, and the cycles with the statusword's fault
//! bit as red marks on the following error. Drawn with plotters into SVG.

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

/// One axis of a recording.
#[derive(Debug, Default, Clone)]
pub struct AxisSeries {
    /// Time, s.
    pub t: Vec<f64>,
    /// Position demand, counts.
    pub demand: Vec<f64>,
    /// Actual position, counts.
    pub actual: Vec<f64>,
    /// Following error, counts.
    pub following_error: Vec<f64>,
    /// Actual velocity, the drive's unit.
    pub velocity: Vec<f64>,
    /// Actual torque, the drive's unit.
    pub torque: Vec<f64>,
    /// Mode of operation display.
    pub mode: Vec<i8>,
    /// Statusword.
    pub statusword: Vec<u16>,
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
                why: format!("no column {name} (not a recording of `ecdrive run --record`?)"),
            })
    };
    let c = [
        col("time_s")?,
        col("axis")?,
        col("demand_counts")?,
        col("actual_counts")?,
        col("following_error_counts")?,
        col("velocity_drive_units")?,
        col("torque_drive_units")?,
        col("mode")?,
        col("statusword_hex")?,
    ];
    let mut rec = Recorded::default();
    for (n, l) in lines.enumerate() {
        let f: Vec<&str> = l.split(',').collect();
        let bad = |what: &str| PlotError::Format {
            file: file.clone(),
            line: n + 2,
            why: format!("{what} is not a number"),
        };
        let num = |i: usize, what: &str| -> Result<f64, PlotError> {
            f.get(c[i])
                .and_then(|v| v.parse::<f64>().ok())
                .ok_or_else(|| bad(what))
        };
        let axis = num(1, "axis")? as u16;
        let a = rec.axes.entry(axis).or_default();
        a.t.push(num(0, "time_s")?);
        a.demand.push(num(2, "demand_counts")?);
        a.actual.push(num(3, "actual_counts")?);
        a.following_error.push(num(4, "following_error_counts")?);
        a.velocity.push(num(5, "velocity_drive_units")?);
        a.torque.push(num(6, "torque_drive_units")?);
        a.mode.push(num(7, "mode")? as i8);
        let sw = f
            .get(c[8])
            .and_then(|v| u16::from_str_radix(v, 16).ok())
            .ok_or_else(|| bad("statusword_hex"))?;
        a.statusword.push(sw);
    }
    Ok(rec)
}

/// The panels drawn for each axis, top to bottom.
pub const PANELS: [&str; 4] = [
    "position (counts): demand, actual",
    "following error (counts)",
    "velocity (drive units)",
    "torque (drive units)",
];

fn range(v: &[f64]) -> (f64, f64) {
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !lo.is_finite() || !hi.is_finite() {
        return (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1.0);
    (lo - pad, hi + pad)
}

fn mode_colour(mode: i8) -> RGBAColor {
    match mode {
        8 => BLUE.mix(0.08),
        9 => GREEN.mix(0.10),
        10 => MAGENTA.mix(0.08),
        _ => BLACK.mix(0.04),
    }
}

/// The units of the configuration's drives by axis, for [`draw`]: drives selected by position,
/// in the order of their positions (the order of the axes); a drive selected otherwise ends
/// the list (its axis and the ones after it stay in counts).
pub fn units_of(
    cfg: &crate::app::config::RunConfig,
) -> Vec<Option<crate::master::startup::UserUnits>> {
    let mut by_position: Vec<(u16, Option<crate::master::startup::UserUnits>)> = Vec::new();
    for d in &cfg.drives {
        match d.select {
            crate::master::Selector::Position(p) => by_position.push((p, d.units.clone())),
            _ => break,
        }
    }
    by_position.sort_by_key(|(p, _)| *p);
    by_position.into_iter().map(|(_, u)| u).collect()
}

/// Draw `rec` into the SVG file `out`: one panel per axis and quantity ([`PANELS`]); position
/// and following error in `units[axis]` where given (else counts).
pub fn draw(
    rec: &Recorded,
    out: &Path,
    units: &[Option<crate::master::startup::UserUnits>],
) -> Result<(), PlotError> {
    let file = out.display().to_string();
    let err = |e: &dyn std::fmt::Display| PlotError::Draw {
        file: file.clone(),
        why: e.to_string(),
    };
    let rows = rec.axes.len().max(1) * PANELS.len();
    let root = SVGBackend::new(out, (1200, (rows * 190) as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let panels = root.split_evenly((rows, 1));
    let t_end = rec
        .axes
        .values()
        .filter_map(|a| a.t.last().copied())
        .fold(0.0, f64::max)
        .max(1e-3);
    for (k, (axis, a)) in rec.axes.iter().enumerate() {
        let u = units.get(usize::from(*axis)).and_then(Option::as_ref);
        let scale = |v: &[f64]| -> Vec<f64> {
            let k = u.map_or(1.0, |u| u.counts_per_unit);
            v.iter().map(|x| x / k).collect()
        };
        let (demand, actual, fe) = (
            scale(&a.demand),
            scale(&a.actual),
            scale(&a.following_error),
        );
        let series: [Vec<(&[f64], RGBColor)>; 4] = [
            vec![(&demand, BLUE), (&actual, RED)],
            vec![(&fe, BLACK)],
            vec![(&a.velocity, GREEN)],
            vec![(&a.torque, MAGENTA)],
        ];
        for (p, (title, lines)) in PANELS.iter().zip(series).enumerate() {
            let title = match (u, p) {
                (Some(u), 0 | 1) => title.replace("counts", &u.name),
                _ => title.to_string(),
            };
            let area = &panels[k * PANELS.len() + p];
            let all: Vec<f64> = lines.iter().flat_map(|(v, _)| v.iter().copied()).collect();
            let (lo, hi) = range(&all);
            let mut chart = ChartBuilder::on(area)
                .caption(format!("axis {axis}: {title}"), ("sans-serif", 14))
                .margin(6)
                .x_label_area_size(34)
                .y_label_area_size(70)
                .build_cartesian_2d(0.0..t_end, lo..hi)
                .map_err(|e| err(&e))?;
            chart
                .configure_mesh()
                .x_desc("time (s)")
                .light_line_style(BLACK.mix(0.05))
                .draw()
                .map_err(|e| err(&e))?;
            if p == 0 {
                // The mode of operation as bands behind the position.
                let mut start = 0;
                for i in 1..=a.mode.len() {
                    if i == a.mode.len() || a.mode[i] != a.mode[start] {
                        let (t0, t1) = (a.t[start], a.t[i - 1]);
                        chart
                            .draw_series(std::iter::once(Rectangle::new(
                                [(t0, lo), (t1, hi)],
                                mode_colour(a.mode[start]).filled(),
                            )))
                            .map_err(|e| err(&e))?;
                        start = i;
                    }
                }
            }
            for (v, colour) in lines {
                chart
                    .draw_series(LineSeries::new(
                        a.t.iter().copied().zip(v.iter().copied()),
                        colour,
                    ))
                    .map_err(|e| err(&e))?;
            }
            if p == 1 {
                // Cycles with the statusword's fault bit (bit 3).
                let faults =
                    a.t.iter()
                        .zip(&a.statusword)
                        .filter(|(_, sw)| *sw & 0x0008 != 0)
                        .map(|(t, _)| Circle::new((*t, 0.0), 3, RED.filled()));
                chart.draw_series(faults).map_err(|e| err(&e))?;
            }
        }
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
