//! The report as text (an aligned table), JSON and SVG (histograms).

use super::report::TimingReport;
use super::stats::{histogram, Figure, Histogram};
use std::fmt::Write as _;

fn num(v: Option<f64>, decimals: usize) -> String {
    match v {
        Some(x) => format!("{x:.decimals$}"),
        None => "-".into(),
    }
}

impl TimingReport {
    /// The report as an aligned text table.
    pub fn to_text(&self) -> String {
        let mut out = self.heading();
        out.push('\n');
        out.push_str(&table(&self.rows()));
        out.push_str(&self.notes());
        if !self.per_slave.is_empty() {
            let _ = writeln!(out, "\nper slave, over the {} s measured:", self.window_s);
            out.push_str(&crate::report::slave_table_text(&self.per_slave, true));
        }
        out
    }

    /// The table's rows: quantity, analytic value or bound, min, mean, max, unit.
    fn rows(&self) -> Vec<[String; 6]> {
        let mut rows: Vec<[String; 6]> = Vec::new();
        let mut row = |q: &str, f: &Figure, unit: &str, d: usize| {
            let analytic = match (f.analytic, f.bound) {
                (Some(a), _) => num(Some(a), d),
                (None, Some(b)) => format!("≤ {}", num(Some(b), d)),
                _ => "-".into(),
            };
            rows.push([
                q.into(),
                analytic,
                num(f.min, d),
                num(f.mean, d),
                num(f.max, d),
                unit.into(),
            ]);
        };
        row("transaction", &self.transaction_us, "µs", 1);
        row(
            &format!("cycle, thesis: T = (n + 2) · 154 µs, n = {}", self.slaves),
            &Figure::default().analytic(self.thesis_cycle_us),
            "µs",
            1,
        );
        let formula = if self.inclusion_call { 2 } else { 1 };
        row(
            &format!(
                "cycle, model: ({} slots + {formula}) · 154 µs{}",
                self.slots,
                if self.pulse_error_rate > 0.0 {
                    " + repeats"
                } else {
                    ""
                }
            ),
            &self.cycle_us,
            "µs",
            1,
        );
        row("per-slave update period", &self.slave_update_us, "µs", 1);
        row("repeats per cycle", &self.repeats.per_cycle, "", 4);
        row("repeats / transactions", &self.repeats.fraction, "", 5);
        row(
            "repeats (count)",
            &Figure {
                analytic: Some(self.repeats.expected),
                mean: Some(self.repeats.count as f64),
                ..Figure::default()
            },
            "",
            1,
        );
        row(
            "failed after repeat / slave drop-outs",
            &Figure {
                min: Some(self.repeats.failed_after_repeat as f64),
                max: Some(self.repeats.dropouts as f64),
                ..Figure::default()
            },
            "",
            0,
        );
        if let Some(l) = &self.lab {
            row("S-7.3 value period (7 cycles)", &l.analog_value_ms, "ms", 2);
            row(
                "speed set-point refresh (channel 1 of 2)",
                &l.setpoint_refresh_ms,
                "ms",
                2,
            );
            row("floor display word (4 steps)", &l.floor_word_ms, "ms", 2);
            row(
                "cabin display word (7 steps)",
                &l.cabin_display_word_ms,
                "ms",
                2,
            );
            row(
                "cabin panel word (2 × 7 steps)",
                &l.cabin_panel_word_ms,
                "ms",
                2,
            );
            let lat = &l.latencies;
            row(
                "hall press → call registered",
                &lat.press_to_registered_ms,
                "ms",
                2,
            );
            row(
                "call registered → run bit on the bus",
                &lat.registered_to_run_bit_ms,
                "ms",
                2,
            );
            row(
                "hall press → run bit on the bus",
                &lat.press_to_run_bit_ms,
                "ms",
                2,
            );
            row("STOP → EStopOut off", &lat.stop_to_estop_out_ms, "ms", 2);
            row(
                "EStopOut off → K1 open",
                &lat.estop_out_to_k1_open_ms,
                "ms",
                2,
            );
            row("STOP → K1 open", &lat.stop_to_k1_open_ms, "ms", 2);
        }
        rows
    }

    /// What was run: the bus, the noise, the window; on the lab bus the samples.
    fn heading(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "asi-lift timing: {}, pulse error rate {}, seed {}, {} s measured: {} cycles, {} transactions",
            self.bus, self.pulse_error_rate, self.seed, self.window_s, self.cycles, self.transactions
        );
        if let Some(l) = &self.lab {
            let _ = writeln!(
                out,
                "latencies: {} hall calls and {} STOPs at random moments; PLC scan {} ms, safety scan {} ms, STOP delay {} ms{}{}",
                l.latencies.hall.len(),
                l.latencies.stop.len(),
                l.plc_scan_ms,
                l.safety_scan_ms,
                l.stop_delay_ms,
                match l.latencies.operator_resets {
                    0 => String::new(),
                    n => format!(
                        "\n{n} trip(s) not caused by a sample (Safety-at-Work monitor under line noise) reset by the operator"
                    ),
                },
                l.latencies
                    .incomplete
                    .as_ref()
                    .map(|s| format!("\nwarning: {s}"))
                    .unwrap_or_default()
            );
        }
        out
    }

    /// The error model's evaluation and why the model does not apply, where it does not.
    fn notes(&self) -> String {
        let mut out = String::new();
        if let Some(m) = &self.error_model {
            let _ = writeln!(
                out,
                "\nerror model: a pulse comes through with c = (1 − p/4)^4 = {:.6}; a transaction of \
                 m + s pulses fails with q = 1 − c^(m+s) (here {:.1} pulses, q = {:.4} on average) \
                 and is repeated once.\nrepeats: {} counted, {:.1} ± {:.1} expected; mean cycle \
                 {:.2} µs simulated, {}.",
                m.pulse_clean,
                m.mean_pulses,
                m.mean_fail_probability,
                self.repeats.count,
                self.repeats.expected,
                self.repeats.standard_error,
                self.cycle_us.mean.unwrap_or(0.0),
                match self.cycle_us.analytic {
                    Some(a) => format!(
                        "{a:.2} ± {:.2} µs expected",
                        m.cycle_mean_standard_error_us
                    ),
                    None => "no model value (see below)".into(),
                }
            );
        }
        if let Some(note) = &self.model_note {
            let _ = writeln!(out, "\nmodel: {note}.");
        }
        out
    }

    /// The report as JSON.
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string_pretty(self)
    }

    /// An SVG with histograms of the cycle time and of each latency.
    pub fn to_svg(&self) -> String {
        let mut panels: Vec<(String, Histogram, &str)> = vec![(
            format!("cycle time, {}", self.bus),
            self.cycle_histogram.clone(),
            "µs",
        )];
        if let Some(l) = &self.lab {
            let lat = &l.latencies;
            let series: [(&str, Vec<f64>); 5] = [
                (
                    "hall press → call registered",
                    lat.hall.iter().map(|s| s.registered_ms).collect(),
                ),
                (
                    "call registered → run bit on the bus",
                    lat.hall.iter().map(|s| s.run_bit_ms).collect(),
                ),
                (
                    "hall press → run bit on the bus",
                    lat.hall
                        .iter()
                        .map(|s| s.registered_ms + s.run_bit_ms)
                        .collect(),
                ),
                (
                    "STOP → EStopOut off",
                    lat.stop.iter().map(|s| s.estop_out_ms).collect(),
                ),
                (
                    "STOP → K1 open",
                    lat.stop
                        .iter()
                        .map(|s| s.estop_out_ms + s.k1_open_ms)
                        .collect(),
                ),
            ];
            for (name, v) in series {
                if !v.is_empty() {
                    panels.push((
                        format!("{name} ({} samples)", v.len()),
                        histogram(&v, 0.001, 30),
                        "ms",
                    ));
                }
            }
        }
        svg(&panels)
    }
}

/// The rows as an aligned table under its header: text columns left, numbers right.
fn table(rows: &[[String; 6]]) -> String {
    let header = ["quantity", "analytic", "min", "mean", "max", "unit"];
    let width = |i: usize| {
        rows.iter()
            .map(|r| r[i].chars().count())
            .chain([header[i].chars().count()])
            .max()
            .unwrap_or(0)
    };
    let w: Vec<usize> = (0..6).map(width).collect();
    let mut out = String::new();
    let mut line = |cells: [&str; 6]| {
        let mut s = String::new();
        for (i, c) in cells.iter().enumerate() {
            let pad = w[i].saturating_sub(c.chars().count());
            if i == 0 || i == 5 {
                s.push_str(c);
                if i == 0 {
                    s.push_str(&" ".repeat(pad));
                }
            } else {
                s.push_str(&" ".repeat(pad));
                s.push_str(c);
            }
            if i < 5 {
                s.push_str("  ");
            }
        }
        out.push_str(s.trim_end());
        out.push('\n');
    };
    line(header);
    for r in rows {
        line([&r[0], &r[1], &r[2], &r[3], &r[4], &r[5]]);
    }
    out
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Hand-written SVG: one panel per histogram, stacked.
fn svg(panels: &[(String, Histogram, &str)]) -> String {
    const W: f64 = 760.0;
    const PH: f64 = 170.0;
    const LEFT: f64 = 60.0;
    const RIGHT: f64 = 20.0;
    let height = PH * panels.len() as f64 + 10.0;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{height}" viewBox="0 0 {W} {height}" font-family="sans-serif" font-size="11">"#
    );
    let _ = writeln!(s, r#"<rect width="{W}" height="{height}" fill="white"/>"#);
    for (k, (title, h, unit)) in panels.iter().enumerate() {
        let top = PH * k as f64 + 10.0;
        let plot_top = top + 22.0;
        let plot_h = PH - 60.0;
        let base = plot_top + plot_h;
        let plot_w = W - LEFT - RIGHT;
        let _ = writeln!(
            s,
            r#"<text x="{LEFT}" y="{:.1}" font-size="13" font-weight="bold">{}</text>"#,
            top + 12.0,
            esc(title)
        );
        let peak = h.counts.iter().copied().max().unwrap_or(0).max(1);
        let n = h.counts.len().max(1);
        let bw = plot_w / n as f64;
        for (i, &c) in h.counts.iter().enumerate() {
            if c == 0 {
                continue;
            }
            let bh = plot_h * c as f64 / peak as f64;
            let _ = writeln!(
                s,
                r##"<rect x="{:.2}" y="{:.2}" width="{:.2}" height="{:.2}" fill="#4a7ab5"><title>{:.3}..{:.3} {unit}: {c}</title></rect>"##,
                LEFT + bw * i as f64 + 0.5,
                base - bh,
                (bw - 1.0).max(0.5),
                bh,
                h.lo + h.width * i as f64,
                h.lo + h.width * (i + 1) as f64,
            );
        }
        let _ = writeln!(
            s,
            r#"<line x1="{LEFT}" y1="{base:.1}" x2="{:.1}" y2="{base:.1}" stroke="black"/>"#,
            W - RIGHT
        );
        let _ = writeln!(
            s,
            r#"<line x1="{LEFT}" y1="{plot_top:.1}" x2="{LEFT}" y2="{base:.1}" stroke="black"/>"#
        );
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="end">{peak}</text>"#,
            LEFT - 4.0,
            plot_top + 8.0
        );
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{base:.1}" text-anchor="end">0</text>"#,
            LEFT - 4.0
        );
        let hi = h.lo + h.width * n as f64;
        let _ = writeln!(
            s,
            r#"<text x="{LEFT}" y="{:.1}">{:.3} {unit}</text>"#,
            base + 14.0,
            h.lo
        );
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="end">{:.3} {unit}</text>"#,
            W - RIGHT,
            base + 14.0,
            hi
        );
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">count per bin of {:.3} {unit}</text>"#,
            LEFT + plot_w / 2.0,
            base + 14.0,
            h.width
        );
    }
    s.push_str("</svg>\n");
    s
}
