//! `asi-lift stand --plot FILE.svg|FILE.png`: a picture of a stand scenario, in the run plot's
//! style and formats ([`super::plot`]).
//!
//! Two panels on one time axis:
//! 1. the axis's speed and the safe drive's commanded speed limit, over bands in the colour
//!    of the function's page (grey, green, orange, red: what the student sees under its
//!    button), with the light curtain's broken field;
//! 2. the axis's position and the drive's torque.
//!
//! Drawn from the samples [`rig::stand::run_sampled`] takes after every scan (10 ms), so
//! the same scenario gives the same bytes.

use super::picture::{
    legend, panel, render, tick, two_state, Area, DrawResult, Format, Picture, Swatch,
};
use plotters::prelude::*;
use rig::stand::{HmiState, StandReport, StandSample};

const SPEED: RGBColor = RGBColor(0, 120, 60);
const LIMIT: RGBColor = RGBColor(200, 40, 160);
const CURTAIN: RGBColor = RGBColor(110, 60, 200);
const POSITION: RGBColor = RGBColor(20, 60, 160);
const TORQUE: RGBColor = RGBColor(200, 120, 0);
const GREY: RGBColor = RGBColor(150, 150, 150);
const GREEN: RGBColor = RGBColor(40, 170, 70);
const ORANGE: RGBColor = RGBColor(240, 150, 30);
const RED: RGBColor = RGBColor(220, 30, 30);

/// The lamp's colour of a page state.
fn lamp(state: HmiState) -> RGBColor {
    match state.colour() {
        "green" => GREEN,
        "orange" => ORANGE,
        "red" => RED,
        _ => GREY,
    }
}

/// Draws the stand's run in `format`: the file's bytes.
pub fn draw(rep: &StandReport, samples: &[StandSample], format: Format) -> Result<Vec<u8>, String> {
    render(&StandPicture { rep, samples }, format)
}

struct StandPicture<'a> {
    rep: &'a StandReport,
    samples: &'a [StandSample],
}

impl Picture for StandPicture<'_> {
    fn draw_on<DB: DrawingBackend>(&self, root: &Area<DB>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE)?;
        let title = format!(
            "asi-lift stand: \"{}\", {}, {:.1} s simulated",
            self.rep.scenario,
            self.rep.function,
            self.rep.duration_ms as f64 / 1000.0
        );
        let root = root.titled(&title, ("sans-serif", 22))?;
        let (w, h) = root.dim_in_pixel();
        let (w, h) = (i32::try_from(w)?, i32::try_from(h)?);
        let legend_x = w - i32::try_from(super::picture::LEGEND_W)?;
        let areas = root.split_by_breakpoints([legend_x], [h * 55 / 100]);
        let t_end = (self.rep.duration_ms as f64 / 1000.0).max(1e-3);
        self.speed_panel(&areas[0], &areas[1], t_end)?;
        self.position_panel(&areas[2], &areas[3], t_end)
    }
}

/// The intervals over which `key` keeps one value, as `(from, to, value)` seconds; a sample
/// stands for the scan that ends at its time.
fn runs<T: PartialEq + Copy>(
    samples: &[StandSample],
    key: impl Fn(&StandSample) -> T,
) -> Vec<(f64, f64, T)> {
    let mut out: Vec<(f64, f64, T)> = Vec::new();
    let mut from = 0.0;
    for p in samples {
        let v = key(p);
        match out.last_mut() {
            Some(last) if last.2 == v => last.1 = p.t_s,
            _ => out.push((from, p.t_s, v)),
        }
        from = p.t_s;
    }
    out
}

impl StandPicture<'_> {
    fn speed_panel<DB: DrawingBackend>(
        &self,
        area: &Area<DB>,
        key: &Area<DB>,
        t_end: f64,
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let top = self
            .samples
            .iter()
            .flat_map(|p| [p.speed.abs(), p.speed_limit.unwrap_or(0.0).abs()])
            .fold(1.0_f64, f64::max)
            * 1.2;
        let bottom = if self.samples.iter().any(|p| p.speed < 0.0) {
            -top
        } else {
            -top * 0.08
        };
        let caption = format!(
            "Axis speed, the safe speed limit and the {} page",
            self.rep.function
        );
        let mut chart = panel(area, &caption).build_cartesian_2d(0.0..t_end, bottom..top)?;
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .x_label_formatter(&tick)
            .y_desc("speed (rev/s)")
            .y_label_formatter(&tick)
            .label_style(("sans-serif", 13))
            .draw()?;
        // The page's state as the lamp shows it, a band over the whole height.
        let states = runs(self.samples, |p| p.hmi);
        chart.draw_series(states.iter().filter_map(|&(a, b, s)| {
            let s = s?;
            Some(Rectangle::new(
                [(a, bottom), (b, top)],
                lamp(s).mix(0.18).filled(),
            ))
        }))?;
        // The broken field, a strip along the top.
        let strip = top - (top - bottom) * 0.04;
        chart.draw_series(
            runs(self.samples, |p| p.field_broken)
                .into_iter()
                .filter(|r| r.2)
                .map(|(a, b, _)| Rectangle::new([(a, strip), (b, top)], CURTAIN.filled())),
        )?;
        for limit in runs(self.samples, |p| p.speed_limit)
            .into_iter()
            .filter_map(|(a, b, l)| Some((a, b, l?)))
        {
            let (a, b, l) = limit;
            // The limit holds both ways; its negative side only where the axis turns back.
            let sides: &[f64] = if bottom < 0.0 && -l >= bottom {
                &[l, -l]
            } else {
                &[l]
            };
            for &v in sides {
                chart.draw_series(std::iter::once(PathElement::new(
                    [(a, v), (b, v)],
                    LIMIT.stroke_width(2),
                )))?;
            }
        }
        chart.draw_series(LineSeries::new(
            self.samples.iter().map(|p| (p.t_s, p.speed)),
            SPEED.stroke_width(2),
        ))?;
        let mut entries = vec![
            (Swatch::Line(SPEED, 2), "axis speed".to_string()),
            (Swatch::Line(LIMIT, 2), "safe speed limit (±)".to_string()),
            (
                Swatch::Band(CURTAIN),
                "light curtain: field broken".to_string(),
            ),
        ];
        let mut seen: Vec<HmiState> = Vec::new();
        for (_, _, s) in &states {
            if let Some(s) = s.filter(|s| !seen.contains(s)) {
                seen.push(s);
                entries.push((Swatch::Band(lamp(s)), format!("page: {s}")));
            }
        }
        if let Some(ms) = self.rep.stopwatch_ms.last() {
            entries.push((Swatch::None, format!("stopwatch: {ms} ms")));
        }
        legend(key, &entries)
    }

    fn position_panel<DB: DrawingBackend>(
        &self,
        area: &Area<DB>,
        key: &Area<DB>,
        t_end: f64,
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (lo, hi) = self.samples.iter().fold((0.0_f64, 1.0_f64), |(lo, hi), p| {
            (lo.min(p.position), hi.max(p.position))
        });
        let pad = (hi - lo) * 0.08;
        let mut chart = panel(area, "Axis position and torque")
            .build_cartesian_2d(0.0..t_end, (lo - pad)..(hi + pad))?
            .set_secondary_coord(0.0..t_end, -0.25..1.6);
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .x_label_formatter(&tick)
            .y_desc("position (rev)")
            .y_label_formatter(&tick)
            .label_style(("sans-serif", 13))
            .draw()?;
        chart
            .configure_secondary_axes()
            .y_desc("torque")
            .y_labels(3)
            .y_label_formatter(&two_state("off", "on"))
            .label_style(("sans-serif", 13))
            .draw()?;
        let mut steps = Vec::with_capacity(self.samples.len() * 2);
        for (a, b, on) in runs(self.samples, |p| p.torque) {
            let y = if on { 1.0 } else { 0.0 };
            steps.extend([(a, y), (b, y)]);
        }
        chart.draw_secondary_series(LineSeries::new(steps, TORQUE.stroke_width(2)))?;
        chart.draw_series(LineSeries::new(
            self.samples.iter().map(|p| (p.t_s, p.position)),
            POSITION.stroke_width(2),
        ))?;
        let trips = self.rep.trips.len();
        legend(
            key,
            &[
                (Swatch::Line(POSITION, 2), "axis position".into()),
                (Swatch::Line(TORQUE, 2), "torque (right axis)".into()),
                (
                    Swatch::None,
                    match trips {
                        0 => "no trip of the safe drive".into(),
                        n => format!("trips of the safe drive: {n}"),
                    },
                ),
            ],
        )
    }
}
