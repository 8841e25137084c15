//! The `--report FILE.html` page: one self-contained HTML file (inline
//! SVG, no scripts, no external resources) a person opens in a browser.
//!
//! It shows the answer and the held-out gap, then for every signal that
//! carries the gap (all signals when none does): the real data against
//! the nominal sim and the sim with the chosen effects, and the scaled
//! residual of both over time with the localised window shaded; last the
//! effects added in order and the ranking of every candidate. The page
//! knows only [`Model`] and the engine's [`Selection`], so every plant
//! (the arm, a drive) gets the same page; a plant may add [`Curve`]s of
//! its own (the arm: what a person's arm's fitted effects mean, a
//! passive torque against the joint angle, …), drawn after the residuals.
//!
//! The SVG is written here rather than by a plotting crate: the page then
//! needs no font files at build or run time and is byte-for-byte
//! reproducible. Long series are thinned to at most [`POINTS`] points per
//! line (every k-th sample).

use crate::engine::Selection;
use crate::locate::Location;
use crate::model::{Model, Series};
use crate::residual::scaled;
use std::fmt::Write;

/// Most points drawn per line.
pub const POINTS: usize = 1200;
const WIDTH: f64 = 900.0;
const HEIGHT: f64 = 220.0;
const MARGIN: (f64, f64, f64, f64) = (70.0, 20.0, 28.0, 34.0); // left, right, top, bottom

/// Escapes text for HTML and SVG.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// One line of a chart.
struct Line<'a> {
    label: &'a str,
    colour: &'a str,
    values: Vec<f64>,
}

/// A "nice" tick step for a span.
fn tick_step(span: f64) -> f64 {
    let raw = span / 5.0;
    let power = 10f64.powf(raw.log10().floor());
    let fraction = raw / power;
    let nice = if fraction < 1.5 {
        1.0
    } else if fraction < 3.5 {
        2.0
    } else if fraction < 7.5 {
        5.0
    } else {
        10.0
    };
    nice * power
}

/// An SVG line chart of `lines` against time, `shade` [s] shaded.
fn chart(
    title: &str,
    unit: &str,
    times: &[f64],
    lines: &[Line],
    shade: Option<(f64, f64)>,
) -> String {
    chart_against(title, unit, "t [s]", times, lines, shade)
}

/// An SVG line chart of `lines` against `times` (the abscissa, labelled
/// `abscissa`), `shade` shaded.
fn chart_against(
    title: &str,
    unit: &str,
    abscissa: &str,
    times: &[f64],
    lines: &[Line],
    shade: Option<(f64, f64)>,
) -> String {
    let finite = |v: &&f64| v.is_finite();
    let (t0, t1) = (
        times.first().copied().unwrap_or(0.0),
        times.last().copied().unwrap_or(1.0),
    );
    let all = lines.iter().flat_map(|l| l.values.iter()).filter(finite);
    let (mut lo, mut hi) = all.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(*v), b.max(*v))
    });
    if !(lo.is_finite() && hi.is_finite()) {
        (lo, hi) = (0.0, 1.0);
    }
    if hi - lo < 1e-12 {
        (lo, hi) = (lo - 0.5, hi + 0.5);
    }
    let (left, right, top, bottom) = MARGIN;
    let x = |t: f64| left + (t - t0) / (t1 - t0).max(1e-12) * (WIDTH - left - right);
    let y = |v: f64| top + (hi - v) / (hi - lo) * (HEIGHT - top - bottom);
    let mut svg = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" viewBox="0 0 {WIDTH} {HEIGHT}" font-family="sans-serif" font-size="11">"#
    );
    let _ = write!(
        svg,
        r#"<text x="{left}" y="16" font-weight="bold">{}</text>"#,
        escape(title)
    );
    if let Some((a, b)) = shade {
        let _ = write!(
            svg,
            "<rect x=\"{:.1}\" y=\"{top}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"#fde7c8\"/>",
            x(a),
            (x(b) - x(a)).max(1.0),
            HEIGHT - top - bottom
        );
    }
    let _ = write!(
        svg,
        r##"<rect x="{left}" y="{top}" width="{:.1}" height="{:.1}" fill="none" stroke="#888"/>"##,
        WIDTH - left - right,
        HEIGHT - top - bottom
    );
    let step = tick_step(hi - lo);
    let mut v = (lo / step).ceil() * step;
    while v <= hi {
        let _ = write!(
            svg,
            r##"<text x="{:.1}" y="{:.1}" text-anchor="end">{}</text><line x1="{left}" x2="{:.1}" y1="{:.1}" y2="{:.1}" stroke="#eee"/>"##,
            left - 4.0,
            y(v) + 4.0,
            format_tick(v, step),
            WIDTH - right,
            y(v),
            y(v)
        );
        v += step;
    }
    let step = tick_step(t1 - t0);
    let mut t = (t0 / step).ceil() * step;
    while t <= t1 {
        let _ = write!(
            svg,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            x(t),
            HEIGHT - bottom + 14.0,
            format_tick(t, step)
        );
        t += step;
    }
    let _ = write!(
        svg,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="end">{}</text><text x="12" y="{:.1}" transform="rotate(-90 12 {:.1})" text-anchor="middle">{}</text>"#,
        WIDTH - right,
        HEIGHT - 4.0,
        escape(abscissa),
        HEIGHT / 2.0,
        HEIGHT / 2.0,
        escape(unit)
    );
    let stride = times.len().div_ceil(POINTS).max(1);
    for (i, line) in lines.iter().enumerate() {
        let points: Vec<String> = times
            .iter()
            .zip(&line.values)
            .step_by(stride)
            .filter(|(_, v)| v.is_finite())
            .map(|(t, v)| format!("{:.1},{:.1}", x(*t), y(*v)))
            .collect();
        let _ = write!(
            svg,
            r#"<polyline fill="none" stroke="{}" stroke-width="1.2" points="{}"/><text x="{:.1}" y="16" fill="{}">{}</text>"#,
            line.colour,
            points.join(" "),
            WIDTH - right - 150.0 * (lines.len() - i) as f64,
            line.colour,
            escape(line.label)
        );
    }
    svg + "</svg>"
}

fn format_tick(value: f64, step: f64) -> String {
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    // A tick at zero may come out of the arithmetic as −0 or −1e−17.
    let value = if value.abs() < step * 1e-6 {
        0.0
    } else {
        value
    };
    format!("{value:.decimals$}")
}

/// A location in words: signals, time window, band.
fn place(location: &Location) -> String {
    let mut text = match location.t_start.zip(location.t_end) {
        Some((a, b)) => format!(
            "{} from {a:.2} s to {b:.2} s",
            escape(&location.signals.join(", "))
        ),
        None => "nothing beyond the measurement noise".to_string(),
    };
    if let Some([lo, hi]) = location.band_hz {
        let _ = write!(text, ", periodic, {lo:.2}-{hi:.2} Hz");
    }
    text
}

/// A plant's own chart of a fitted effect: what its parameters mean, as
/// a curve against a physical quantity (not time).
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    /// Title, with the fitted parameters.
    pub title: String,
    /// What the curve means, in a sentence under the chart.
    pub caption: String,
    /// Abscissa label with its unit ("elbow angle q2 [rad]").
    pub abscissa: String,
    /// Ordinate unit.
    pub unit: String,
    /// Abscissa values.
    pub xs: Vec<f64>,
    /// (label, values at `xs`) of each line.
    pub lines: Vec<(String, Vec<f64>)>,
}

/// What one report page shows: the plant's model of the scored (held-out)
/// data and the engine's selection made on it.
#[derive(Clone, Copy)]
pub struct Subject<'a> {
    /// The model whose data were scored (the held-out side).
    pub model: &'a dyn Model,
    /// The engine's answer, predictions included.
    pub selection: &'a Selection,
    /// The log file(s) diagnosed, as the page names them.
    pub source: &'a str,
    /// How the data were held out, in words.
    pub held_out: &'a str,
    /// The plant's own findings, shown as a table under the gap (label,
    /// text): the arm's corrected lengths beside the kernel's estimate
    /// and the unexplained part; empty for none.
    pub facts: &'a [(String, String)],
    /// The plant's charts of its fitted effects (empty for none).
    pub curves: &'a [Curve],
}

/// The report page of one diagnosis (any plant: the arm, a drive).
pub fn page(subject: &Subject) -> String {
    let Subject {
        model,
        selection,
        source,
        held_out,
        facts,
        curves,
    } = *subject;
    let predictions = &selection.predictions;
    let empty = Series::with_capacity(model.signals().len(), 0);
    let nominal = predictions.nominal.as_ref().unwrap_or(&empty);
    let chosen = predictions.chosen.as_ref().unwrap_or(nominal);
    let (before, after) = (scaled(model, nominal), scaled(model, chosen));
    let times = model.times();
    let location = &selection.location;
    let shade = location.t_start.zip(location.t_end);
    let named: Vec<usize> = if location.signals.is_empty() {
        (0..model.signals().len()).collect()
    } else {
        location
            .signals
            .iter()
            .filter_map(|n| model.signals().iter().position(|s| s.name == n))
            .collect()
    };
    let effects = if selection.effects.is_empty() {
        "none".to_string()
    } else {
        let names: Vec<&str> = selection
            .effects
            .iter()
            .map(|e| e.effect.as_str())
            .collect();
        names.join(" + ")
    };
    let gap = &selection.gap;
    let mut html = String::from(
        "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>limb diagnose</title>\
         <style>body{font-family:sans-serif;max-width:960px;margin:1em auto}\
         table{border-collapse:collapse}td,th{padding:2px 8px;border-bottom:1px solid #ddd;text-align:right}\
         td:first-child,th:first-child{text-align:left}</style></head><body>",
    );
    let _ = write!(
        html,
        "<h1>Sim-to-real gap: {}</h1><p>Log <code>{}</code>. Held out: {}.</p>\
         <p>Held-out gap ({}) {:.4} &rarr; {:.4}: shrink {:.1} %.</p>",
        escape(&effects),
        escape(source),
        escape(held_out),
        escape(&gap.metric),
        gap.before,
        gap.after,
        100.0 * gap.shrink
    );
    let _ = write!(
        html,
        "<p>Where the nominal sim's gap lies: {}{}.</p><p>What the chosen effects leave: {}",
        place(location),
        if shade.is_some() { " (shaded)" } else { "" },
        place(&selection.remaining)
    );
    html += ".</p>";
    if !facts.is_empty() {
        html += "<table>";
        for (label, text) in facts {
            let _ = write!(
                html,
                "<tr><td>{}</td><td>{}</td></tr>",
                escape(label),
                escape(text)
            );
        }
        html += "</table>";
    }
    html += "<h2>Sim against real</h2>";
    // A legend entry has about 150 px.
    let with = if effects.len() <= 20 {
        format!("sim + {effects}")
    } else {
        "sim + chosen effects".to_string()
    };
    for &s in &named {
        let signal = model.signals()[s];
        html += &chart(
            signal.name,
            signal.unit,
            times,
            &[
                Line {
                    label: "real",
                    colour: "#222",
                    values: model.observed().column(s),
                },
                Line {
                    label: "nominal sim",
                    colour: "#d62728",
                    values: nominal.column(s),
                },
                Line {
                    label: &with,
                    colour: "#1f77b4",
                    values: chosen.column(s),
                },
            ],
            shade,
        );
    }
    let (scale, unit) = if model.noise_floor() > 0.0 {
        ("in units of the noise σ", "σ")
    } else {
        (
            "relative to each signal's RMS; the noise is unknown",
            "÷ RMS",
        )
    };
    let _ = write!(html, "<h2>Residuals over time (real − sim, {scale})</h2>");
    for &s in &named {
        let signal = model.signals()[s];
        html += &chart(
            &format!("{} residual", signal.name),
            unit,
            times,
            &[
                Line {
                    label: "nominal sim",
                    colour: "#d62728",
                    values: before.column(s),
                },
                Line {
                    label: &with,
                    colour: "#1f77b4",
                    values: after.column(s),
                },
            ],
            shade,
        );
    }
    if !curves.is_empty() {
        html += "<h2>What the fitted effects mean</h2>";
    }
    const COLOURS: [&str; 4] = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd"];
    for curve in curves {
        let lines: Vec<Line> = curve
            .lines
            .iter()
            .zip(COLOURS.iter().cycle())
            .map(|((label, values), colour)| Line {
                label,
                colour,
                values: values.clone(),
            })
            .collect();
        html += &chart_against(
            &curve.title,
            &curve.unit,
            &curve.abscissa,
            &curve.xs,
            &lines,
            None,
        );
        let _ = write!(html, "<p>{}</p>", escape(&curve.caption));
    }
    html += "<h2>Effects added, in order</h2><table><tr><th>effect</th>\
             <th>held-out gap after</th><th>fitted parameters (refitted with all added)</th></tr>";
    for e in &selection.effects {
        let _ = write!(
            html,
            "<tr><td>{}</td><td>{:.4}</td><td>{}</td></tr>",
            escape(&e.effect),
            e.held_out_after,
            escape(&e.parameters_text())
        );
    }
    if selection.effects.is_empty() {
        html += "<tr><td>none</td><td></td><td>no candidate earns its parameters</td></tr>";
    }
    html += "</table><h2>Ranking of every candidate (first selection step)</h2><table><tr><th>effect</th>\
             <th>held-out criterion</th><th>gap explained</th><th>held-out gap after</th>\
             <th>fitted parameters</th></tr>";
    let first = selection.steps.first().map_or(&[][..], |s| &s.ranking[..]);
    for r in first {
        let _ = write!(
            html,
            "<tr><td>{}</td><td>{:.1}</td><td>{:.1} %</td><td>{:.4}</td><td>{}</td></tr>",
            escape(&r.effect),
            r.criterion,
            100.0 * r.score,
            r.held_out_after,
            escape(&r.parameters_text())
        );
    }
    html + "</table></body></html>\n"
}
