//! The `--svg` plot: the wake-up latency histograms of the runs of the first repetition on one
//! log–log plot
//! (latency on x, samples per bin on y), written by hand as plain SVG 1.1 (a few paths and
//! texts; no plotting crate needed).

use super::report::{Bucket, JitterReport, RunReport};
use std::fmt::Write as _;

const W: f64 = 960.0;
const H: f64 = 540.0;
const LEFT: f64 = 80.0;
const RIGHT: f64 = 24.0;
const TOP: f64 = 64.0;
const BOTTOM: f64 = 64.0;

const COLOURS: [(&str, &str); 4] = [
    ("sleep", "#7f7f7f"),
    ("ethercrab", "#1f77b4"),
    ("soem", "#2ca02c"),
    ("ecdrive", "#d62728"),
];

fn colour(name: &str) -> &'static str {
    COLOURS
        .iter()
        .find(|(n, _)| *n == name)
        .map_or("#000000", |(_, c)| c)
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

struct Axes {
    x0: f64,
    x1: f64,
    y1: f64,
}

impl Axes {
    /// x position of a latency in ns (log scale over [10^x0, 10^x1] ns).
    fn x(&self, ns: f64) -> f64 {
        let v = ns.max(1.0).log10();
        LEFT + (v - self.x0) / (self.x1 - self.x0) * (W - LEFT - RIGHT)
    }

    /// y position of a count (log scale over [10^-0.3, 10^y1]); 0 sits on the axis.
    fn y(&self, count: f64) -> f64 {
        let bottom = H - BOTTOM;
        if count <= 0.0 {
            return bottom;
        }
        let y0 = -0.3;
        let v = count.log10();
        bottom - (v - y0) / (self.y1 - y0) * (H - TOP - BOTTOM)
    }
}

fn step_path(ax: &Axes, buckets: &[Bucket]) -> String {
    let mut d = String::new();
    let mut prev_hi: Option<u64> = None;
    for b in buckets {
        let (xl, xh, y) = (
            ax.x(b.lo_ns as f64),
            ax.x(b.hi_ns as f64),
            ax.y(b.count as f64),
        );
        let base = ax.y(0.0);
        match prev_hi {
            Some(h) if h == b.lo_ns => {
                let _ = write!(d, " L{xl:.1},{y:.1}");
            }
            Some(h) => {
                let _ = write!(
                    d,
                    " L{:.1},{base:.1} M{xl:.1},{base:.1} L{xl:.1},{y:.1}",
                    ax.x(h as f64)
                );
            }
            None => {
                let _ = write!(d, "M{xl:.1},{base:.1} L{xl:.1},{y:.1}");
            }
        }
        let _ = write!(d, " L{xh:.1},{y:.1}");
        prev_hi = Some(b.hi_ns);
    }
    if let Some(h) = prev_hi {
        let _ = write!(d, " L{:.1},{:.1}", ax.x(h as f64), ax.y(0.0));
    }
    d
}

fn label_ns(ns: f64) -> String {
    if ns >= 1e6 {
        format!("{} ms", ns / 1e6)
    } else if ns >= 1e3 {
        format!("{} µs", ns / 1e3)
    } else {
        format!("{ns} ns")
    }
}

/// The plot for a report, as an SVG document.
pub fn render(report: &JitterReport) -> String {
    let runs: Vec<&RunReport> = report
        .repetitions
        .first()
        .map(|r| r.runs())
        .unwrap_or_default();
    let all = runs.iter().flat_map(|r| r.wake_latency_histogram.iter());
    let lo = all.clone().map(|b| b.lo_ns).min().unwrap_or(1_000).max(1);
    let hi = all
        .clone()
        .map(|b| b.hi_ns)
        .max()
        .unwrap_or(1_000_000)
        .max(lo * 10);
    let max_count = all.map(|b| b.count).max().unwrap_or(1).max(1);
    let ax = Axes {
        x0: (lo as f64).log10().floor(),
        x1: (hi as f64).log10().ceil(),
        y1: (max_count as f64).log10().ceil().max(1.0),
    };

    let mut s = String::new();
    heading(&mut s, report);
    grid(&mut s, &ax);
    histograms(&mut s, &ax, &runs);
    s.push_str("</svg>\n");
    s
}

/// The document's start, the title (the settings) and the host line.
fn heading(s: &mut String, report: &JitterReport) {
    let _ = writeln!(
        s,
        r#"<?xml version="1.0" encoding="UTF-8"?>
<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width="{W}" height="{H}" viewBox="0 0 {W} {H}" font-family="sans-serif" font-size="12">
<rect x="0" y="0" width="{W}" height="{H}" fill="white"/>"#
    );
    let st = &report.settings;
    let title = format!(
        "Wake-up latency, cycle {} µs, {} cycles per run{}, {}, {} drive(s); priority {}",
        st.cycle_ns / 1000,
        st.cycles,
        if st.repeat > 1 {
            format!(" (repetition 1 of {})", st.repeat)
        } else {
            String::new()
        },
        st.transport,
        st.drives.len(),
        match st.priority {
            Some(p) if report.priority_granted => format!("SCHED_FIFO {p}"),
            Some(p) => format!("SCHED_FIFO {p} NOT granted"),
            None => "normal".into(),
        }
    );
    let _ = writeln!(
        s,
        r#"<text x="{}" y="24" font-size="15" text-anchor="middle">{}</text>"#,
        W / 2.0,
        esc(&title)
    );
    let host = format!(
        "{} | PREEMPT_RT {} | {}",
        report.host.kernel,
        if report.host.preempt_rt { "yes" } else { "no" },
        report.host.cpu_model
    );
    let _ = writeln!(
        s,
        r##"<text x="{}" y="44" font-size="11" fill="#555" text-anchor="middle">{}</text>"##,
        W / 2.0,
        esc(&host)
    );
}

/// The plot's frame, its log-scale grid with the tick labels, and the axis titles.
fn grid(s: &mut String, ax: &Axes) {
    let (bx0, bx1, by0, by1) = (LEFT, W - RIGHT, TOP, H - BOTTOM);
    let _ = writeln!(
        s,
        r#"<rect x="{bx0}" y="{by0}" width="{}" height="{}" fill="none" stroke="black"/>"#,
        bx1 - bx0,
        by1 - by0
    );
    let mut e = ax.x0 as i32;
    while f64::from(e) <= ax.x1 {
        for m in [1.0, 2.0, 5.0] {
            let v = m * 10f64.powi(e);
            let x = ax.x(v);
            if x < bx0 - 0.5 || x > bx1 + 0.5 {
                continue;
            }
            let major = m == 1.0;
            let _ = writeln!(
                s,
                r##"<line x1="{x:.1}" y1="{by0}" x2="{x:.1}" y2="{by1}" stroke="{}" stroke-width="1"/>"##,
                if major { "#ccc" } else { "#eee" }
            );
            let _ = writeln!(
                s,
                r#"<text x="{x:.1}" y="{}" text-anchor="middle">{}</text>"#,
                by1 + 16.0,
                esc(&label_ns(v))
            );
        }
        e += 1;
    }
    let mut e = 0i32;
    while f64::from(e) <= ax.y1 {
        let y = ax.y(10f64.powi(e));
        let _ = writeln!(
            s,
            r##"<line x1="{bx0}" y1="{y:.1}" x2="{bx1}" y2="{y:.1}" stroke="#ddd" stroke-width="1"/>"##
        );
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{:.1}" text-anchor="end">{}</text>"#,
            bx0 - 6.0,
            y + 4.0,
            10u64.pow(e as u32)
        );
        e += 1;
    }
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">wake-up latency against the intended instant (log scale, {} bins per decade)</text>"#,
        (bx0 + bx1) / 2.0,
        H - 20.0,
        super::report::BINS_PER_DECADE
    );
    let _ = writeln!(
        s,
        r#"<text x="18" y="{}" text-anchor="middle" transform="rotate(-90 18 {})">cycles per bin (log scale)</text>"#,
        (by0 + by1) / 2.0,
        (by0 + by1) / 2.0
    );
}

/// The three histograms, and the legend with each run's percentiles.
fn histograms(s: &mut String, ax: &Axes, runs: &[&RunReport]) {
    let (bx1, by0) = (W - RIGHT, TOP);
    for (i, r) in runs.iter().enumerate() {
        let (name, colour) = (r.name, colour(r.name));
        let d = step_path(ax, &r.wake_latency_histogram);
        if !d.is_empty() {
            let _ = writeln!(
                s,
                r#"<path d="{d}" fill="none" stroke="{colour}" stroke-width="1.6"/>"#
            );
        }
        let ly = by0 + 18.0 + 18.0 * i as f64;
        let lx = bx1 - 330.0;
        let w = &r.wake_latency;
        let _ = writeln!(
            s,
            r#"<line x1="{lx}" y1="{ly}" x2="{}" y2="{ly}" stroke="{colour}" stroke-width="3"/>"#,
            lx + 24.0
        );
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}">{}</text>"#,
            lx + 30.0,
            ly + 4.0,
            esc(&format!(
                "{name}: p50 {:.1} µs, p99 {:.1} µs, max {:.1} µs",
                w.p50 as f64 / 1e3,
                w.p99 as f64 / 1e3,
                w.max as f64 / 1e3
            ))
        );
    }
}
