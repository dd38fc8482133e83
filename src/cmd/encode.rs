//! `asi-lift encode`: a master call or slave response on its way to the line.

use super::output::Outputs;
use super::print_out;
use asi_phy::waveform::WaveformConfig;
use asi_trace::encode::{describe, parse_call, waveform_csv};
use std::path::{Path, PathBuf};

/// The arguments of `asi-lift encode`.
#[derive(clap::Args)]
pub struct EncodeArgs {
    /// The call and its arguments, e.g. `dexg 5 1010`.
    #[arg(required = true, num_args = 1..)]
    pub call: Vec<String>,
    /// Write the line voltage as `time,voltage` CSV to this file (`-` for standard output).
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Overwrite the CSV file if it exists.
    #[arg(long)]
    pub force: bool,
    /// Pulse amplitude in volts.
    #[arg(long, default_value_t = 2.5)]
    pub amplitude: f32,
    /// RMS of added white noise in volts.
    #[arg(long, default_value_t = 0.0)]
    pub noise_rms: f32,
    /// Seed of the noise.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

/// Shows the call's bits, levels and pulses, or writes its line voltage.
pub fn run(args: EncodeArgs) -> Result<u8, String> {
    let EncodeArgs {
        call,
        csv,
        force,
        amplitude,
        noise_rms,
        seed,
    } = args;
    let t = parse_call(&call).map_err(|e| e.to_string())?;
    match csv {
        None => print_out(&describe(t))?,
        Some(path) => {
            let cfg = {
                let mut cfg = WaveformConfig::default();
                cfg.amplitude = amplitude;
                cfg.noise_rms = noise_rms;
                cfg.seed = seed;
                cfg
            };
            super::output::clean_up_on_signals()?;
            let mut outs = Outputs::new(force);
            let sink = outs.add("--csv", &path)?;
            let text = waveform_csv(t, &cfg).map_err(|e| e.to_string())?;
            outs.write_all(&sink, &text)?;
            outs.commit()?;
            if path != Path::new("-") {
                print_out(&format!("{}wrote       {}\n", describe(t), path.display()))?;
            }
        }
    }
    Ok(0)
}
