//! `asi-lift run --plot FILE.svg`: a picture of the run drawn with `plotters`.
//!
//! Three panels on one time axis:
//! 1. the cabin position with the floor levels, the vanes' long sensor tracks, the overtravel
//!    trip points, and the passengers' calls: pressed (triangle) and served (circle);
//! 2. the cabin velocity, contactor K1 (closed/open) and the safety trips;
//! 3. the bus's repeats per transaction, in windows of one second.
//!
//! The series are sampled by stepping the rig through its public [`Rig::step_until`] at a
//! fixed simulated step ([`sample_step`]) and reading the plant and the bus between moments;
//! the stepping only pauses the simulation, so the run (and its report) is the same as
//! without `--plot`. The drawing depends on nothing but the samples and the report, so the
//! same scenario gives a byte-identical SVG.

use asi_phy::{SimDuration, SimTime};
use lift_model::LiftConfig;
use plotters::coord::Shift;
use plotters::prelude::*;
use rig::{Report, Rig};

/// The width and height of the picture, pixels.
const SIZE: (u32, u32) = (1400, 1000);
/// The window of the bus error rate.
const BUS_WINDOW_S: f64 = 1.0;
/// The finest sampling step; longer runs get a coarser one (see [`sample_step`]).
const MIN_STEP: SimDuration = SimDuration::from_millis(20);
/// At most about this many samples per run, so that the SVG stays small.
const MAX_SAMPLES: u64 = 5_000;

/// The rig's state at one moment, as the plot shows it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Sample {
    t_s: f64,
    position_mm: f64,
    velocity_mm_s: f64,
    k1: bool,
    /// Bus transactions so far, repeats included.
    transactions: u64,
    /// Repeats so far.
    repeats: u64,
}

impl Sample {
    fn of(rig: &Rig) -> Sample {
        let lift = rig.lift();
        let stats = rig.lab().bus.stats();
        Sample {
            t_s: rig.now().as_secs_f64(),
            position_mm: lift.position_mm(),
            velocity_mm_s: lift.velocity_mm_s(),
            k1: lift.k1_closed(),
            transactions: stats.transactions,
            repeats: stats.repeats,
        }
    }
}

/// The time series of a run, recorded while it runs.
pub struct Samples {
    samples: Vec<Sample>,
    config: LiftConfig,
}

/// The sampling step for a run of `length`: 20 ms, or coarser (whole milliseconds) so that
/// a long run has at most about 5,000 samples.
pub fn sample_step(length: SimDuration) -> SimDuration {
    let ms = length.as_nanos().div_ceil(MAX_SAMPLES * 1_000_000);
    SimDuration::from_millis(ms).max(MIN_STEP)
}

/// Steps `rig` up to (not including) `end`, sampling it every [`sample_step`] and telling
/// `progress` the time reached; the caller finishes the run with [`Rig::run_observed`], which
/// runs the moment at `end` and writes the report.
pub fn record(
    rig: &mut Rig,
    end: SimTime,
    progress: &mut dyn FnMut(SimTime, SimTime),
) -> Samples {
    let step = sample_step(end - SimTime::ZERO);
    let mut samples = vec![Sample::of(rig)];
    let mut next = SimTime::ZERO + step;
    while next < end {
        while rig.step_until(next).is_some() {}
        let s = Sample::of(rig);
        if samples.last().is_none_or(|l| s.t_s > l.t_s) {
            samples.push(s);
        }
        progress(rig.now(), end);
        next += step;
    }
    Samples {
        samples,
        config: rig.lift().config().clone(),
    }
}

impl Samples {
    /// Adds the state at the end of the run from its report (the rig is gone by then).
    pub fn finish(&mut self, rep: &Report) {
        let Some(last) = self.samples.last().copied() else {
            return;
        };
        if rep.simulated_s > last.t_s {
            self.samples.push(Sample {
                t_s: rep.simulated_s,
                position_mm: rep.final_state.position_mm,
                velocity_mm_s: if rep.final_state.moving {
                    last.velocity_mm_s
                } else {
                    0.0
                },
                k1: rep.final_state.contactor_closed,
                transactions: rep.bus.transactions,
                repeats: rep.bus.repeats,
            });
        }
    }

    /// Repeats per transaction (in %) in consecutive windows of [`BUS_WINDOW_S`], as
    /// `(window start, window end, rate)`; a window without transactions has rate 0.
    fn bus_rate(&self) -> Vec<(f64, f64, f64)> {
        let mut out = Vec::new();
        let Some(first) = self.samples.first() else {
            return out;
        };
        let mut start = *first;
        let mut boundary = first.t_s + BUS_WINDOW_S;
        for (i, s) in self.samples.iter().enumerate() {
            let last = i + 1 == self.samples.len();
            if s.t_s >= boundary || (last && s.t_s > start.t_s) {
                let tx = s.transactions - start.transactions;
                let rep = s.repeats - start.repeats;
                let rate = if tx == 0 {
                    0.0
                } else {
                    rep as f64 / tx as f64 * 100.0
                };
                out.push((start.t_s, s.t_s, rate));
                start = *s;
                while boundary <= s.t_s {
                    boundary += BUS_WINDOW_S;
                }
            }
        }
        out
    }
}

/// A call button's floor: `cabin:3`, `hall-up:2` → 3, 2.
fn button_floor(button: &str) -> Option<u8> {
    button.rsplit_once(':')?.1.parse().ok()
}

/// Draws the run as SVG.
pub fn draw(samples: &Samples, rep: &Report) -> Result<String, String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        draw_on(&root, samples, rep).map_err(|e| format!("drawing the plot: {e}"))?;
        root.present()
            .map_err(|e| format!("drawing the plot: {e}"))?;
    }
    Ok(svg)
}

type DrawResult = Result<(), Box<dyn std::error::Error>>;

const FLOOR: RGBColor = RGBColor(90, 90, 90);
const VANE: RGBColor = RGBColor(120, 170, 230);
const POSITION: RGBColor = RGBColor(20, 60, 160);
const VELOCITY: RGBColor = RGBColor(0, 120, 60);
const K1: RGBColor = RGBColor(200, 120, 0);
const TRIP: RGBColor = RGBColor(210, 20, 20);
const PRESSED: RGBColor = RGBColor(150, 0, 150);
const SERVED: RGBColor = RGBColor(0, 150, 150);
const BUS: RGBColor = RGBColor(100, 60, 20);

fn draw_on(root: &DrawingArea<SVGBackend<'_>, Shift>, s: &Samples, rep: &Report) -> DrawResult {
    root.fill(&WHITE)?;
    let title = format!(
        "asi-lift run: scenario \"{}\", seed {}, {:.1} s simulated",
        rep.scenario, rep.seed, rep.simulated_s
    );
    let root = root.titled(&title, ("sans-serif", 22))?;
    let h = i32::try_from(root.dim_in_pixel().1)?;
    let panels = root.split_by_breakpoints::<i32, i32, _, _>([], [h * 46 / 100, h * 77 / 100]);
    let t_end = s
        .samples
        .last()
        .map_or(rep.simulated_s, |l| l.t_s)
        .max(1e-3);
    position_panel(&panels[0], s, rep, t_end)?;
    velocity_panel(&panels[1], s, rep, t_end)?;
    bus_panel(&panels[2], s, rep, t_end)?;
    Ok(())
}

/// Panel 1: cabin position, floors, vanes, overtravel, calls.
fn position_panel(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    s: &Samples,
    rep: &Report,
    t_end: f64,
) -> DrawResult {
    let cfg = &s.config;
    let top_level = f64::from(cfg.floors - 1) * cfg.floor_pitch_mm;
    let trip_bottom = -cfg.trip_beyond_floor_mm;
    let trip_top = top_level + cfg.trip_beyond_floor_mm;
    let (lo, hi) = s.samples.iter().fold((trip_bottom, trip_top), |(lo, hi), p| {
        (lo.min(p.position_mm), hi.max(p.position_mm))
    });
    let (lo, hi) = (lo - 60.0, hi + 60.0);
    let mut chart = ChartBuilder::on(area)
        .margin(10)
        .margin_right(30)
        .caption(
            "Cabin position, floors, vanes and calls",
            ("sans-serif", 18),
        )
        .x_label_area_size(35)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..t_end, lo..hi)?;
    chart
        .configure_mesh()
        .disable_y_mesh()
        .x_desc("time (s)")
        .y_desc("cabin position above floor 1 (mm)")
        .label_style(("sans-serif", 13))
        .draw()?;
    for floor in 1..=cfg.floors {
        let Some(level) = cfg.floor_level_mm(floor) else {
            continue;
        };
        let half = cfg.long_track_half_mm;
        let band = chart.draw_series([Rectangle::new(
            [(0.0, level - half), (t_end, level + half)],
            VANE.mix(0.25).filled(),
        )])?;
        if floor == 1 {
            band.label(format!("vane long sensor track (±{half:.0} mm)"))
                .legend(|(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 20, y + 5)], VANE.mix(0.25).filled())
                });
        }
        let line = chart.draw_series(LineSeries::new(
            [(0.0, level), (t_end, level)],
            FLOOR.stroke_width(1),
        ))?;
        if floor == 1 {
            line.label("floor level")
                .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], FLOOR));
        }
        chart.draw_series([Text::new(
            format!("floor {floor}"),
            (t_end * 0.005, level + half + 8.0),
            ("sans-serif", 13).into_font().color(&FLOOR),
        )])?;
    }
    for (i, trip) in [trip_bottom, trip_top].into_iter().enumerate() {
        let series = chart.draw_series(DashedLineSeries::new(
            [(0.0, trip), (t_end, trip)],
            8,
            5,
            TRIP.stroke_width(2),
        ))?;
        if i == 0 {
            series
                .label(format!(
                    "overtravel trip ({:.0} mm beyond the end floors)",
                    cfg.trip_beyond_floor_mm
                ))
                .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], TRIP.stroke_width(2)));
        }
    }
    chart
        .draw_series(LineSeries::new(
            s.samples.iter().map(|p| (p.t_s, p.position_mm)),
            POSITION.stroke_width(2),
        ))?
        .label("cabin position")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], POSITION.stroke_width(2)));
    let calls: Vec<(f64, Option<f64>, f64)> = rep
        .passengers
        .iter()
        .filter_map(|p| {
            let level = cfg.floor_level_mm(button_floor(&p.button)?)?;
            Some((p.pressed_at_s, p.served_at_s, level))
        })
        .collect();
    chart
        .draw_series(calls.iter().filter_map(|&(_, served, level)| {
            served.map(|t| Circle::new((t, level), 7, SERVED.stroke_width(2)))
        }))?
        .label("call served (cabin stopped for it)")
        .legend(|(x, y)| Circle::new((x + 10, y), 6, SERVED.stroke_width(2)));
    chart
        .draw_series(
            calls
                .iter()
                .map(|&(t, _, level)| TriangleMarker::new((t, level), 8, PRESSED.filled())),
        )?
        .label("call pressed (at the called floor)")
        .legend(|(x, y)| TriangleMarker::new((x + 10, y), 7, PRESSED.filled()));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// Panel 2: velocity, K1, safety trips.
fn velocity_panel(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    s: &Samples,
    rep: &Report,
    t_end: f64,
) -> DrawResult {
    let vmax = s
        .samples
        .iter()
        .fold(50.0_f64, |m, p| m.max(p.velocity_mm_s.abs()))
        * 1.15;
    let mut chart = ChartBuilder::on(area)
        .margin(10)
        .margin_right(30)
        .caption(
            "Cabin velocity, contactor K1 and safety trips",
            ("sans-serif", 18),
        )
        .x_label_area_size(35)
        .y_label_area_size(70)
        .right_y_label_area_size(60)
        .build_cartesian_2d(0.0..t_end, -vmax..vmax)?
        .set_secondary_coord(0.0..t_end, -0.25..1.6);
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc("velocity, up positive (mm/s)")
        .label_style(("sans-serif", 13))
        .draw()?;
    chart
        .configure_secondary_axes()
        .y_desc("K1")
        .y_labels(3)
        .y_label_formatter(&|v: &f64| {
            if v.abs() < 1e-9 {
                "open".to_string()
            } else if (v - 1.0).abs() < 1e-9 {
                "closed".to_string()
            } else {
                String::new()
            }
        })
        .label_style(("sans-serif", 13))
        .draw()?;
    let k1 = |b: bool| if b { 1.0 } else { 0.0 };
    let mut steps = Vec::with_capacity(s.samples.len() * 2);
    for (i, p) in s.samples.iter().enumerate() {
        if i > 0 {
            steps.push((p.t_s, k1(s.samples[i - 1].k1)));
        }
        steps.push((p.t_s, k1(p.k1)));
    }
    steps.dedup();
    chart
        .draw_secondary_series(LineSeries::new(steps, K1.stroke_width(2)))?
        .label("K1 (right axis)")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], K1.stroke_width(2)));
    chart
        .draw_series(LineSeries::new(
            s.samples.iter().map(|p| (p.t_s, p.velocity_mm_s)),
            VELOCITY.stroke_width(2),
        ))?
        .label("cabin velocity")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], VELOCITY.stroke_width(2)));
    let trips = chart.draw_series(rep.safety.trips.iter().map(|trip| {
        PathElement::new(
            [(trip.at_s, -vmax), (trip.at_s, vmax)],
            TRIP.stroke_width(2),
        )
    }))?;
    if !rep.safety.trips.is_empty() {
        trips
            .label(format!("safety trip ({})", rep.safety.trips.len()))
            .legend(|(x, y)| PathElement::new([(x + 10, y - 6), (x + 10, y + 6)], TRIP.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// Panel 3: repeats per transaction.
fn bus_panel(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    s: &Samples,
    rep: &Report,
    t_end: f64,
) -> DrawResult {
    let rate = s.bus_rate();
    let max = rate.iter().fold(0.0_f64, |m, r| m.max(r.2));
    let ymax = if max > 0.0 { max * 1.2 } else { 1.0 };
    let mut chart = ChartBuilder::on(area)
        .margin(10)
        .margin_right(30)
        .caption(
            format!(
                "Bus repeats per transaction, per {BUS_WINDOW_S:.0} s window ({} repeats in {} transactions)",
                rep.bus.repeats, rep.bus.transactions
            ),
            ("sans-serif", 18),
        )
        .x_label_area_size(35)
        .y_label_area_size(70)
        .right_y_label_area_size(60)
        .build_cartesian_2d(0.0..t_end, 0.0..ymax)?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc("repeats (%)")
        .y_labels(5)
        .label_style(("sans-serif", 13))
        .draw()?;
    let mut steps = Vec::with_capacity(rate.len() * 2);
    for &(a, b, r) in &rate {
        steps.push((a, r));
        steps.push((b, r));
    }
    chart.draw_series(LineSeries::new(steps, BUS.stroke_width(2)))?;
    if max == 0.0 {
        chart.draw_series([Text::new(
            "no repeats: every transaction succeeded at the first try",
            (t_end * 0.01, ymax * 0.5),
            ("sans-serif", 14).into_font().color(&BUS),
        )])?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sampling_step_keeps_long_runs_small() {
        assert_eq!(sample_step(SimDuration::from_secs(80)), MIN_STEP);
        assert_eq!(sample_step(SimDuration::from_secs(100)), MIN_STEP);
        assert_eq!(
            sample_step(SimDuration::from_secs(600)),
            SimDuration::from_millis(120)
        );
    }

    #[test]
    fn a_button_names_its_floor() {
        assert_eq!(button_floor("cabin:3"), Some(3));
        assert_eq!(button_floor("hall-down:4"), Some(4));
        assert_eq!(button_floor("cabin"), None);
    }
}
