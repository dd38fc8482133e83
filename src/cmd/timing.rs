//! `asi-lift timing`: the bus and reaction times, computed and simulated side by side.

use super::output::Outputs;
use super::print_out;
use asi_phy::SimDuration;
use rig::timing::{
    analysable_error_rate, analyse, BusChoice, TimingOptions, MAX_DURATION, MAX_SAMPLES,
};
use std::path::PathBuf;

/// The arguments of `asi-lift timing`.
#[derive(clap::Args)]
pub struct TimingArgs {
    /// The bus: `lab` (the lab lift, whole rig), a number 1..31 of standard slaves, or
    /// `62ab` (62 A/B slaves).
    #[arg(long, default_value = "lab", value_parser = parse_bus)]
    pub bus: BusChoice,
    /// Plain I/O modules added to the lab bus at its free addresses (0..20).
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub extra_slaves: Option<u8>,
    /// Probability that a pulse on the line is corrupted (0 <= P < 1).
    #[arg(
        long,
        value_name = "P",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub error_rate: f64,
    /// Seed of the line noise and of the press moments.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,
    /// Simulated measurement window of the bus statistics (e.g. 60s, 2min).
    #[arg(
        long,
        value_name = "DURATION",
        default_value = "60s",
        allow_hyphen_values = true
    )]
    pub duration: String,
    /// Latency samples of each chain (lab bus).
    #[arg(
        long,
        value_name = "K",
        default_value_t = 100,
        allow_negative_numbers = true
    )]
    pub samples: u32,
    /// Time this IEC 61131-3 Structured Text program as the PLC on the lab bus instead of the
    /// built-in one; the latency study needs a program that tells its state, floor, target
    /// and calls through the agreed variables (`controllers/lift.st` does).
    #[arg(long, value_name = "FILE.st")]
    pub controller: Option<PathBuf>,
    /// Compile the program of `--controller` together with this library (e.g.
    /// `controllers/lab.st`). Repeatable.
    #[arg(long, value_name = "FILE.st")]
    pub library: Vec<PathBuf>,
    /// Write the report as JSON instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Also write an SVG with histograms of the cycle time and of the latencies.
    #[arg(long, value_name = "FILE")]
    pub svg: Option<PathBuf>,
    /// Overwrite the SVG file if it exists.
    #[arg(long)]
    pub force: bool,
}

fn parse_bus(s: &str) -> Result<BusChoice, String> {
    s.parse()
}

/// Runs the analysis and prints its report.
pub fn run(args: TimingArgs) -> Result<u8, String> {
    let TimingArgs {
        bus,
        extra_slaves,
        error_rate,
        seed,
        duration,
        samples,
        controller,
        library,
        json,
        svg,
        force,
    } = args;
    let mut opts = timing_options(bus, extra_slaves, error_rate, seed, &duration, samples)?;
    match (&controller, &opts.bus) {
        (Some(path), BusChoice::Lab { .. }) => {
            opts.program = Some(super::run::load_program(path, &library)?);
        }
        (Some(_), _) => {
            return Err("--controller: a program is timed on the lab bus only (--bus lab)".into())
        }
        (None, _) if !library.is_empty() => {
            return Err(
                "--library: a library goes with a program: give --controller FILE.st too".into(),
            )
        }
        (None, _) => {}
    }
    // Refuse an existing SVG before spending the simulation on it.
    super::output::clean_up_on_signals()?;
    let mut outs = Outputs::new(force);
    for input in controller.iter().chain(&library) {
        outs.input("the program", input)?;
    }
    let svg_out = match &svg {
        Some(path) => Some((path, outs.add("--svg", path)?)),
        None => None,
    };
    let rep = analyse(&opts).map_err(|e| e.to_string())?;
    if json {
        let text = rep
            .to_json()
            .map_err(|e| format!("the report as JSON: {e}"))?;
        print_out(&(text + "\n"))?;
    } else {
        print_out(&rep.to_text())?;
    }
    if let Some((path, sink)) = &svg_out {
        outs.write_all(sink, rep.to_svg())?;
        outs.commit()?;
        if !json {
            print_out(&format!("SVG written to {}\n", path.display()))?;
        }
    }
    Ok(0)
}

/// The timing options from the command line, each bad value named by its argument.
fn timing_options(
    bus: BusChoice,
    extra_slaves: Option<u8>,
    error_rate: f64,
    seed: u64,
    duration: &str,
    samples: u32,
) -> Result<TimingOptions, String> {
    let bus = match (bus, extra_slaves) {
        (BusChoice::Lab { .. }, Some(extra)) if extra > 20 => {
            return Err(format!(
                "--extra-slaves: {extra}: the lab bus has 20 free addresses (0..20)"
            ))
        }
        (BusChoice::Lab { .. }, Some(extra)) => BusChoice::Lab { extra },
        (_, Some(_)) => {
            return Err("--extra-slaves applies to --bus lab only".into());
        }
        (b, None) => b,
    };
    analysable_error_rate(error_rate)
        .map_err(|rule| format!("--error-rate: {error_rate}: {rule}"))?;
    let duration: SimDuration = duration.parse().map_err(|e| format!("--duration: {e}"))?;
    if duration.is_zero() || duration > MAX_DURATION {
        return Err(format!(
            "--duration: {duration}: must be more than 0 and at most 1 h"
        ));
    }
    if samples > MAX_SAMPLES {
        return Err(format!("--samples: {samples}: at most {MAX_SAMPLES}"));
    }
    Ok({
        let mut cfg = TimingOptions::default();
        cfg.bus = bus;
        cfg.pulse_error_rate = error_rate;
        cfg.seed = seed;
        cfg.duration = duration;
        cfg.samples = samples;
        cfg
    })
}
