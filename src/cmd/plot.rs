//! `asi-lift run --plot FILE.svg|FILE.png`: a picture of the run drawn with `plotters`.
//!
//! Three panels on one time axis:
//! 1. the cabin position with the floor levels, the vanes' long sensor tracks, the overtravel
//!    trip points, and the passengers' calls: pressed (triangle) and served (circle);
//! 2. the cabin velocity, contactor K1 (closed/open) and the safety trips;
//! 3. with the safe drive (`[drive] safe = true`), each of its functions the run requested:
//!    when its control bit was FALSE (requested), when its status was TRUE (safe state
//!    reached), and its trips;
//! 4. the bus's repeats per transaction, in windows of one second;
//! 5. with traffic templates (`[[traffic]]`), the distribution of the passengers' waiting and
//!    journey times: the share of them (cumulative, %) done within each time, hall call
//!    waits, cabin call waits and journeys, with the 95 % line the 95th percentile meets.
//!
//! The series are sampled by stepping the rig through its public [`Rig::step_until`] at a
//! fixed simulated step ([`sample_step`]) and reading the plant and the bus between moments;
//! the stepping only pauses the simulation, so the run (and its report) is the same as
//! without `--plot`. The drawing depends on nothing but the samples and the report, so the
//! same scenario gives a byte-identical SVG, or PNG: the PNG's text is set in a font built
//! into the command, not in one found on the machine.
//!
//! One drawing (`draw_on`) serves both formats ([`super::picture`]).

use super::picture::{
    legend, panel, render, tick, two_state, Area, DrawResult, Format, Picture, Swatch, LEGEND_W,
};
use asi_phy::{SimDuration, SimTime};
use lift_model::LiftConfig;
use plotters::prelude::*;
use rig::{Report, Rig};
use safety::drive::Function;

/// The window of the bus error rate.
const BUS_WINDOW_S: f64 = 1.0;
/// The finest sampling step; longer runs get a coarser one (see [`sample_step`]).
pub const MIN_STEP: SimDuration = SimDuration::from_millis(20);
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
    /// The safe drive's functions, if the lift has one.
    drive: Option<DriveBits>,
}

/// The safe drive's functions at one moment: bit `Function::index` set when requested
/// (control bit FALSE) and when its safe state is reached (status TRUE).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct DriveBits {
    requested: u32,
    reached: u32,
}

impl DriveBits {
    fn of(d: &rig::waves::DriveSample) -> DriveBits {
        let mask = |on: &dyn Fn(Function) -> bool| {
            Function::ALL
                .iter()
                .filter(|&&f| on(f))
                .fold(0u32, |m, f| m | 1 << f.index())
        };
        DriveBits {
            requested: mask(&|f| d.control.requested(f)),
            reached: mask(&|f| d.status.of(f)),
        }
    }
}

impl Sample {
    fn of(rig: &Rig) -> Sample {
        let lift = rig.lift();
        let stats = rig.lab().bus().stats();
        Sample {
            t_s: rig.now().as_secs_f64(),
            position_mm: lift.position_mm(),
            velocity_mm_s: lift.velocity_mm_s(),
            k1: lift.k1_closed(),
            transactions: stats.transactions,
            repeats: stats.repeats,
            drive: rig.drive_sample().map(|d| DriveBits::of(&d)),
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
/// `progress` the time reached (a `Break` stops the sampling); the caller finishes the run with [`Rig::run_observed`], which
/// runs the moment at `end` and writes the report.
pub fn record(
    rig: &mut Rig,
    end: SimTime,
    progress: &mut dyn FnMut(SimTime, SimTime) -> std::ops::ControlFlow<()>,
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
        if progress(rig.now(), end).is_break() {
            break;
        }
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
                drive: last.drive,
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
pub fn button_floor(button: &str) -> Option<u8> {
    button.rsplit_once(':')?.1.parse().ok()
}

/// Draws the run in `format`: the file's bytes.
pub fn draw(samples: &Samples, rep: &Report, format: Format) -> Result<Vec<u8>, String> {
    render(&RunPicture { samples, rep }, format)
}

/// The run's picture.
struct RunPicture<'a> {
    samples: &'a Samples,
    rep: &'a Report,
}

impl Picture for RunPicture<'_> {
    fn draw_on<DB: DrawingBackend>(&self, root: &Area<DB>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        draw_on(root, self.samples, self.rep)
    }
}

const FLOOR: RGBColor = RGBColor(90, 90, 90);
const VANE: RGBColor = RGBColor(120, 170, 230);
const POSITION: RGBColor = RGBColor(20, 60, 160);
const VELOCITY: RGBColor = RGBColor(0, 120, 60);
const K1: RGBColor = RGBColor(200, 120, 0);
const TRIP: RGBColor = RGBColor(210, 20, 20);
const PRESSED: RGBColor = RGBColor(150, 0, 150);
const WAIT: RGBColor = RGBColor(220, 170, 220);
const SERVED: RGBColor = RGBColor(0, 150, 150);
const BUS: RGBColor = RGBColor(100, 60, 20);
const HALL_WAIT: RGBColor = RGBColor(150, 0, 150);
const CABIN_WAIT: RGBColor = RGBColor(0, 150, 150);
const JOURNEY: RGBColor = RGBColor(20, 60, 160);

/// The whole picture, on either backend: the title, the panels and their legends.
fn draw_on<DB: DrawingBackend>(root: &Area<DB>, s: &Samples, rep: &Report) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let title = format!(
        "asi-lift run: scenario \"{}\", seed {}, {:.1} s simulated",
        rep.scenario, rep.seed, rep.simulated_s
    );
    let root = root.titled(&title, ("sans-serif", 22))?;
    let (w, h) = root.dim_in_pixel();
    let (w, h) = (i32::try_from(w)?, i32::try_from(h)?);
    let t_end = s
        .samples
        .last()
        .map_or(rep.simulated_s, |l| l.t_s)
        .max(1e-3);
    let legend_x = w - i32::try_from(LEGEND_W)?;
    let traffic = rep.traffic.as_ref().filter(|t| !t.trips.is_empty());
    let drive = s.samples.iter().any(|p| p.drive.is_some());
    match (drive, traffic) {
        (true, None) => {
            let rows = [h * 36 / 100, h * 60 / 100, h * 82 / 100];
            let areas = root.split_by_breakpoints([legend_x], rows);
            position_panel(&areas[0], &areas[1], s, rep, t_end)?;
            velocity_panel(&areas[2], &areas[3], s, rep, t_end)?;
            drive_panel(&areas[4], &areas[5], s, rep, t_end)?;
            bus_panel(&areas[6], &areas[7], s, rep, t_end)?;
        }
        (false, None) => {
            let areas = root.split_by_breakpoints([legend_x], [h * 46 / 100, h * 77 / 100]);
            position_panel(&areas[0], &areas[1], s, rep, t_end)?;
            velocity_panel(&areas[2], &areas[3], s, rep, t_end)?;
            bus_panel(&areas[4], &areas[5], s, rep, t_end)?;
        }
        (true, Some(t)) => {
            let rows = [h * 30 / 100, h * 48 / 100, h * 64 / 100, h * 78 / 100];
            let areas = root.split_by_breakpoints([legend_x], rows);
            position_panel(&areas[0], &areas[1], s, rep, t_end)?;
            velocity_panel(&areas[2], &areas[3], s, rep, t_end)?;
            drive_panel(&areas[4], &areas[5], s, rep, t_end)?;
            bus_panel(&areas[6], &areas[7], s, rep, t_end)?;
            traffic_panel(&areas[8], &areas[9], t)?;
        }
        (false, Some(t)) => {
            let rows = [h * 38 / 100, h * 60 / 100, h * 76 / 100];
            let areas = root.split_by_breakpoints([legend_x], rows);
            position_panel(&areas[0], &areas[1], s, rep, t_end)?;
            velocity_panel(&areas[2], &areas[3], s, rep, t_end)?;
            bus_panel(&areas[4], &areas[5], s, rep, t_end)?;
            traffic_panel(&areas[6], &areas[7], t)?;
        }
    }
    Ok(())
}

/// Panel 1: cabin position, floors, vanes, overtravel, calls.
fn position_panel<DB: DrawingBackend>(
    area: &Area<DB>,
    key: &Area<DB>,
    s: &Samples,
    rep: &Report,
    t_end: f64,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let cfg = &s.config;
    let top_level = f64::from(cfg.floors - 1) * cfg.floor_pitch_mm;
    let trip_bottom = -cfg.trip_beyond_floor_mm;
    let trip_top = top_level + cfg.trip_beyond_floor_mm;
    let (lo, hi) = s
        .samples
        .iter()
        .fold((trip_bottom, trip_top), |(lo, hi), p| {
            (lo.min(p.position_mm), hi.max(p.position_mm))
        });
    let (lo, hi) = (lo - 60.0, hi + 60.0);
    let mut chart = panel(area, "Cabin position, floors, vanes and calls")
        .build_cartesian_2d(0.0..t_end, lo..hi)?;
    chart
        .configure_mesh()
        .disable_y_mesh()
        .x_desc("time (s)")
        .x_label_formatter(&tick)
        .y_desc("cabin above floor 1 (mm)")
        .y_label_formatter(&tick)
        .label_style(("sans-serif", 13))
        .draw()?;
    let half = cfg.long_track_half_mm;
    for floor in 1..=cfg.floors {
        let Some(level) = cfg.floor_level_mm(floor) else {
            continue;
        };
        chart.draw_series([Rectangle::new(
            [(0.0, level - half), (t_end, level + half)],
            VANE.mix(0.25).filled(),
        )])?;
        chart.draw_series(LineSeries::new(
            [(0.0, level), (t_end, level)],
            FLOOR.stroke_width(1),
        ))?;
        chart.draw_series([Text::new(
            format!("floor {floor}"),
            (t_end * 0.005, level + half + 8.0),
            ("sans-serif", 13).into_font().color(&FLOOR),
        )])?;
    }
    for trip in [trip_bottom, trip_top] {
        chart.draw_series(DashedLineSeries::new(
            [(0.0, trip), (t_end, trip)],
            8,
            5,
            TRIP.stroke_width(2),
        ))?;
    }
    let calls: Vec<(f64, Option<f64>, f64)> = rep
        .passengers
        .iter()
        .filter_map(|p| {
            let level = cfg.floor_level_mm(button_floor(&p.button)?)?;
            Some((p.pressed_at_s, p.served_at_s, level))
        })
        .collect();
    // The wait: from the press to the cabin's stop (or the end of the run), along the floor.
    chart.draw_series(calls.iter().map(|&(t, served, level)| {
        PathElement::new(
            [(t, level), (served.unwrap_or(t_end), level)],
            WAIT.stroke_width(3),
        )
    }))?;
    chart.draw_series(LineSeries::new(
        s.samples.iter().map(|p| (p.t_s, p.position_mm)),
        POSITION.stroke_width(2),
    ))?;
    chart.draw_series(calls.iter().filter_map(|&(_, served, level)| {
        served.map(|t| Circle::new((t, level), 7, SERVED.stroke_width(2)))
    }))?;
    chart.draw_series(
        calls
            .iter()
            .map(|&(t, _, level)| TriangleMarker::new((t, level), 8, PRESSED.filled())),
    )?;
    let unserved = calls.iter().filter(|c| c.1.is_none()).count();
    legend(
        key,
        &[
            (Swatch::Line(POSITION, 2), "cabin position".into()),
            (Swatch::Line(FLOOR, 1), "floor level".into()),
            (
                Swatch::Band(VANE),
                format!("vane, long sensor track (±{half:.0} mm)"),
            ),
            (
                Swatch::Dashed(TRIP),
                format!(
                    "overtravel trip ({:.0} mm past end floor)",
                    cfg.trip_beyond_floor_mm
                ),
            ),
            (
                Swatch::Triangle(PRESSED),
                format!("call pressed, at its floor ({})", calls.len()),
            ),
            (Swatch::Line(WAIT, 3), "waiting for the cabin".into()),
            (
                Swatch::Ring(SERVED),
                if unserved == 0 {
                    "call served (cabin stopped)".into()
                } else {
                    format!(
                        "call served ({} of {})",
                        calls.len() - unserved,
                        calls.len()
                    )
                },
            ),
        ],
    )
}

/// Panel 2: velocity, K1, safety trips.
fn velocity_panel<DB: DrawingBackend>(
    area: &Area<DB>,
    key: &Area<DB>,
    s: &Samples,
    rep: &Report,
    t_end: f64,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let vmax = s
        .samples
        .iter()
        .fold(50.0_f64, |m, p| m.max(p.velocity_mm_s.abs()))
        * 1.15;
    let mut chart = panel(area, "Cabin velocity, contactor K1 and safety trips")
        .build_cartesian_2d(0.0..t_end, -vmax..vmax)?
        .set_secondary_coord(0.0..t_end, -0.25..1.6);
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .x_label_formatter(&tick)
        .y_desc("velocity, up positive (mm/s)")
        .y_label_formatter(&tick)
        .label_style(("sans-serif", 13))
        .draw()?;
    chart
        .configure_secondary_axes()
        .y_desc("contactor K1")
        .y_labels(3)
        .y_label_formatter(&two_state("open", "closed"))
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
    chart.draw_secondary_series(LineSeries::new(steps, K1.stroke_width(2)))?;
    chart.draw_series(LineSeries::new(
        s.samples.iter().map(|p| (p.t_s, p.velocity_mm_s)),
        VELOCITY.stroke_width(2),
    ))?;
    // What tripped, as the summary counts it; K1 opening shows in its own line.
    let trips: Vec<_> = rep.safety.causes().collect();
    chart.draw_series(trips.iter().map(|trip| {
        PathElement::new(
            [(trip.at_s, -vmax), (trip.at_s, vmax)],
            TRIP.stroke_width(2),
        )
    }))?;
    legend(
        key,
        &[
            (Swatch::Line(VELOCITY, 2), "cabin velocity".into()),
            (Swatch::Line(K1, 2), "K1, drive power (right axis)".into()),
            (
                Swatch::Mark(TRIP),
                match trips.len() {
                    0 => "safety trip (none)".into(),
                    n => format!("safety trip ({n})"),
                },
            ),
        ],
    )
}

const REQUESTED: RGBColor = RGBColor(250, 200, 120);
const REACHED: RGBColor = RGBColor(40, 150, 60);

/// The intervals over which `on` holds for a sample, merged, as `(from, to)` seconds.
fn spans(s: &Samples, on: impl Fn(&Sample) -> bool) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    for w in s.samples.windows(2) {
        if !on(&w[0]) {
            continue;
        }
        match out.last_mut() {
            Some(last) if last.1 == w[0].t_s => last.1 = w[1].t_s,
            _ => out.push((w[0].t_s, w[1].t_s)),
        }
    }
    out
}

/// Panel 3 (with the safe drive): each function the run requested, one row each.
fn drive_panel<DB: DrawingBackend>(
    area: &Area<DB>,
    key: &Area<DB>,
    s: &Samples,
    rep: &Report,
    t_end: f64,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let ever = s
        .samples
        .iter()
        .filter_map(|p| p.drive)
        .fold(0u32, |m, d| m | d.requested | d.reached);
    let rows: Vec<Function> = Function::ALL
        .into_iter()
        .filter(|f| ever & 1 << f.index() != 0)
        .collect();
    let n = rows.len().max(1) as f64;
    let mut chart = panel(
        area,
        "Safe drive: functions requested and safe states reached",
    )
    .build_cartesian_2d(0.0..t_end, 0.0..n)?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .x_label_formatter(&tick)
        .y_labels(0)
        .disable_y_mesh()
        .label_style(("sans-serif", 13))
        .draw()?;
    for (k, f) in rows.iter().enumerate() {
        // The first function on top.
        let y = n - 1.0 - k as f64;
        let bit = 1u32 << f.index();
        let requested = spans(s, |p| p.drive.is_some_and(|d| d.requested & bit != 0));
        let reached = spans(s, |p| p.drive.is_some_and(|d| d.reached & bit != 0));
        chart.draw_series(
            requested
                .into_iter()
                .map(|(a, b)| Rectangle::new([(a, y + 0.15), (b, y + 0.85)], REQUESTED.filled())),
        )?;
        chart.draw_series(
            reached
                .into_iter()
                .map(|(a, b)| Rectangle::new([(a, y + 0.32), (b, y + 0.68)], REACHED.filled())),
        )?;
        chart.draw_series([Text::new(
            f.to_string(),
            (t_end * 0.005, y + 0.78),
            ("sans-serif", 13).into_font(),
        )])?;
    }
    let trips = rep.safety.drive.as_ref().map_or(&[][..], |d| &d.trips[..]);
    chart.draw_series(
        trips
            .iter()
            .map(|t| PathElement::new([(t.at_s, 0.0), (t.at_s, n)], TRIP.stroke_width(2))),
    )?;
    let mut entries = vec![
        (
            Swatch::Band(REQUESTED),
            "requested (control bit FALSE)".to_string(),
        ),
        (
            Swatch::Band(REACHED),
            "safe state reached (status TRUE)".into(),
        ),
        (
            Swatch::Mark(TRIP),
            match trips.len() {
                0 => "trip: torque off (none)".into(),
                k => format!("trip: torque off ({k})"),
            },
        ),
    ];
    if rows.is_empty() {
        entries.push((Swatch::None, "no function was requested".into()));
    }
    legend(key, &entries)
}

/// Panel 4: repeats per transaction.
fn bus_panel<DB: DrawingBackend>(
    area: &Area<DB>,
    key: &Area<DB>,
    s: &Samples,
    rep: &Report,
    t_end: f64,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let rate = s.bus_rate();
    let max = rate.iter().fold(0.0_f64, |m, r| m.max(r.2));
    let ymax = if max > 0.0 { max * 1.2 } else { 1.0 };
    let mut chart = panel(area, "AS-i bus: repeats per transaction")
        .build_cartesian_2d(0.0..t_end, 0.0..ymax)?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .x_label_formatter(&tick)
        .y_desc("repeats (% of transactions)")
        .y_label_formatter(&tick)
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
    legend(
        key,
        &[
            (
                Swatch::Line(BUS, 2),
                format!("repeats per {BUS_WINDOW_S:.0} s window"),
            ),
            (Swatch::None, format!("in all: {} repeats", rep.bus.repeats)),
            (
                Swatch::None,
                format!("in {} transactions", rep.bus.transactions),
            ),
        ],
    )
}

/// Panel 5: the distribution of the traffic passengers' waiting and journey times, as the
/// share done within each time (an empirical CDF: a step of 1/n at each answered time).
fn traffic_panel<DB: DrawingBackend>(
    area: &Area<DB>,
    key: &Area<DB>,
    t: &rig::report::traffic::TrafficReport,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let since = |from: f64, to: Option<f64>| to.map(|to| to - from);
    let series: [(&str, RGBColor, &rig::report::traffic::Times, Vec<f64>); 3] = [
        (
            "hall call waits",
            HALL_WAIT,
            &t.waiting.hall,
            t.trips
                .iter()
                .filter_map(|p| since(p.hall_pressed_s, p.hall_answered_s))
                .collect(),
        ),
        (
            "cabin call waits",
            CABIN_WAIT,
            &t.waiting.cabin,
            t.trips
                .iter()
                .filter_map(|p| since(p.cabin_pressed_s?, p.delivered_s))
                .collect(),
        ),
        (
            "journeys",
            JOURNEY,
            &t.journey,
            t.trips
                .iter()
                .filter_map(|p| since(p.hall_pressed_s, p.delivered_s))
                .collect(),
        ),
    ];
    let xmax = series
        .iter()
        .flat_map(|(_, _, _, v)| v.iter().copied())
        .fold(0.0_f64, f64::max)
        .max(1.0)
        * 1.05;
    let mut chart = panel(
        area,
        "traffic: passengers done within a time (cumulative, % of those answered)",
    )
    .build_cartesian_2d(0.0..xmax, 0.0..102.0)?;
    chart
        .configure_mesh()
        .x_desc("waiting or journey time (s)")
        .x_label_formatter(&tick)
        .y_desc("passengers (%)")
        .y_label_formatter(&tick)
        .y_labels(5)
        .label_style(("sans-serif", 13))
        .draw()?;
    chart.draw_series(DashedLineSeries::new(
        [(0.0, 95.0), (xmax, 95.0)],
        6,
        4,
        FLOOR.stroke_width(1),
    ))?;
    let mut entries = Vec::new();
    for (name, colour, times, mut v) in series {
        v.sort_by(f64::total_cmp);
        let n = v.len() as f64;
        let mut steps = vec![(0.0, 0.0)];
        for (i, &x) in v.iter().enumerate() {
            steps.push((x, 100.0 * i as f64 / n));
            steps.push((x, 100.0 * (i + 1) as f64 / n));
        }
        chart.draw_series(LineSeries::new(steps, colour.stroke_width(2)))?;
        let f = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.1}"));
        entries.push((Swatch::Line(colour, 2), format!("{name} ({})", times.count)));
        entries.push((
            Swatch::None,
            format!(
                "  mean {}, p95 {}, max {} s",
                f(times.mean_s),
                f(times.p95_s),
                f(times.max_s)
            ),
        ));
    }
    entries.push((Swatch::Dashed(FLOOR), "95 %: the 95th percentile".into()));
    entries.push((
        Swatch::None,
        format!("{} passengers, {} delivered", t.passengers, t.delivered),
    ));
    entries.push((
        Swatch::None,
        format!(
            "handling capacity {:.1} per 5 min",
            t.handling_capacity.mean_per_5min
        ),
    ));
    legend(key, &entries)
}
