//! The picture of an exploration (`explore --svg`, `explore summarize --svg`): fault kind ×
//! instant, each fork a cell coloured by its verdict, above the cabin's position in the run
//! without faults. Hand-written SVG: rectangles, one polyline and text, so that the lines of
//! merged shards draw the same picture byte for byte.

use rig::explore::{ForkLine, Verdict};
use std::fmt::Write as _;

/// The colour of a verdict (colour-blind safe: Okabe and Ito's palette).
fn colour(v: Verdict) -> &'static str {
    match v {
        Verdict::InService => "#009E73",
        Verdict::NeedsPerson => "#E69F00",
        Verdict::OutOfService => "#999999",
        Verdict::Violation => "#D55E00",
        Verdict::Panic => "#CC79A7",
    }
}

/// The picture of `lines` (in index order).
pub fn svg(lines: &[ForkLine]) -> String {
    const W: f64 = 1400.0;
    const LEFT: f64 = 170.0;
    const RIGHT: f64 = 20.0;
    const TOP: f64 = 40.0;
    const ROW: f64 = 16.0;
    const POS_H: f64 = 200.0;
    let mut kinds: Vec<&str> = Vec::new();
    for l in lines {
        if !kinds.contains(&l.fault.as_str()) {
            kinds.push(&l.fault);
        }
    }
    let mut instants: Vec<(f64, f64)> = lines.iter().map(|l| (l.at_s, l.position_mm)).collect();
    instants.sort_by(|a, b| a.0.total_cmp(&b.0));
    instants.dedup_by(|a, b| a.0 == b.0);
    let (t0, t1) = match (instants.first(), instants.last()) {
        (Some(a), Some(b)) => (a.0, b.0),
        _ => (0.0, 0.0),
    };
    let step = instants
        .windows(2)
        .map(|w| w[1].0 - w[0].0)
        .fold(f64::INFINITY, f64::min);
    let step = if step.is_finite() { step } else { 1.0 };
    let span = (t1 - t0 + step).max(1e-9);
    let plot_w = W - LEFT - RIGHT;
    let x = |t: f64| LEFT + (t - t0) / span * plot_w;
    let cell = (step / span * plot_w).max(0.5);
    let grid_h = ROW * kinds.len() as f64;
    let pos_top = TOP + grid_h + 30.0;
    let h = pos_top + POS_H + 60.0;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{h}" viewBox="0 0 {W} {h}" font-family="sans-serif" font-size="11">"#
    );
    let _ = writeln!(s, r#"<rect width="{W}" height="{h}" fill="white"/>"#);
    let title = lines.first().map_or("", |l| l.scenario.as_str());
    let _ = writeln!(
        s,
        r#"<text x="{LEFT}" y="20" font-size="14">Every fault at every moment: {} ({} forks)</text>"#,
        escape(title),
        lines.len()
    );
    // The legend, top right.
    let mut lx = W - RIGHT - 5.0 * 110.0;
    for v in Verdict::ALL {
        let _ = writeln!(
            s,
            r#"<rect x="{lx}" y="10" width="10" height="10" fill="{}"/><text x="{}" y="19">{}</text>"#,
            colour(v),
            lx + 14.0,
            v.name()
        );
        lx += 110.0;
    }
    for (r, k) in kinds.iter().enumerate() {
        let y = TOP + ROW * r as f64;
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" text-anchor="end">{}</text>"#,
            LEFT - 6.0,
            y + ROW - 4.0,
            escape(k)
        );
    }
    for l in lines {
        let Some(r) = kinds.iter().position(|k| *k == l.fault) else {
            continue;
        };
        let _ = writeln!(
            s,
            r#"<rect x="{:.2}" y="{}" width="{cell:.2}" height="{}" fill="{}"><title>{} at {} s: {}</title></rect>"#,
            x(l.at_s),
            TOP + ROW * r as f64,
            ROW - 1.0,
            colour(l.verdict),
            escape(&l.fault),
            l.at_s,
            l.verdict.name()
        );
    }
    // The cabin's position in the run without faults.
    let (lo, hi) = instants
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (_, p)| {
            (lo.min(*p), hi.max(*p))
        });
    let (lo, hi) = if lo.is_finite() && hi > lo {
        (lo, hi)
    } else {
        (lo.min(0.0) - 1.0, hi.max(0.0) + 1.0)
    };
    let y = |p: f64| pos_top + POS_H - (p - lo) / (hi - lo) * POS_H;
    let _ = writeln!(
        s,
        r##"<rect x="{LEFT}" y="{pos_top}" width="{plot_w}" height="{POS_H}" fill="none" stroke="#cccccc"/>"##
    );
    let points: Vec<String> = instants
        .iter()
        .map(|(t, p)| format!("{:.2},{:.2}", x(*t) + cell / 2.0, y(*p)))
        .collect();
    let _ = writeln!(
        s,
        r#"<polyline points="{}" fill="none" stroke="black" stroke-width="1.5"/>"#,
        points.join(" ")
    );
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="end">{hi:.0} mm</text><text x="{}" y="{}" text-anchor="end">{lo:.0} mm</text>"#,
        LEFT - 6.0,
        pos_top + 10.0,
        LEFT - 6.0,
        pos_top + POS_H
    );
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="end">cabin (no fault)</text>"#,
        LEFT - 6.0,
        pos_top + POS_H / 2.0
    );
    // The time axis: ten ticks.
    for i in 0..=10 {
        let t = t0 + (t1 - t0) * f64::from(i) / 10.0;
        let _ = writeln!(
            s,
            r#"<text x="{:.2}" y="{}" text-anchor="middle">{t:.1} s</text>"#,
            x(t) + cell / 2.0,
            pos_top + POS_H + 18.0
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">instant of the fault</text>"#,
        LEFT + plot_w / 2.0,
        pos_top + POS_H + 40.0
    );
    s.push_str("</svg>\n");
    s
}

fn escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
