//! `asi-lift stand`: the SafeMOTION thesis' teaching stand (rig::stand): a stand scenario run and
//! shown as a student at the stand sees it, or the list of the built-in ones (one per test guide).

use super::output::Outputs;
use super::{picture, print_out, read_input, stand_plot};
use rig::scenario::builtin::Builtin;
use rig::stand::builtin::{find, stand_scenario, STAND_BUILTINS};
use rig::stand::{run_sampled, StandScenario};
use std::path::{Path, PathBuf};

/// What `asi-lift stand` does besides running a scenario.
#[derive(clap::Subcommand)]
pub enum StandAction {
    /// Print a built-in stand scenario as its TOML file, to copy and edit
    /// (`asi-lift stand show ss1 > my-guide.toml`).
    Show {
        /// The scenario's name, as `asi-lift stand` lists it.
        name: String,
    },
}

/// The arguments of `asi-lift stand`.
#[derive(clap::Args)]
pub struct StandArgs {
    /// The stand scenario: a file (TOML, `-` for standard input) or the name of a built-in
    /// one. Without it, the built-in ones are listed.
    pub scenario: Option<PathBuf>,
    /// The form of what is printed.
    #[arg(long, value_enum, default_value_t = super::run::Format::Text)]
    pub format: super::run::Format,
    /// Where the stand's log and page states go: a file, or `-` for standard output.
    #[arg(long, value_name = "FILE|-", default_value = "-")]
    pub report: PathBuf,
    /// Draw the run: the axis's speed and position, the safe speed limit, the torque, the
    /// light curtain and the page's states over time, as SVG (`.svg`) or PNG (`.png`).
    #[arg(long, value_name = "FILE.svg|FILE.png")]
    pub plot: Option<PathBuf>,
    /// Overwrite the report and plot files if they exist.
    #[arg(long)]
    pub force: bool,
}

/// Runs a stand scenario and prints its log and the page's states; the stand only shows,
/// so the exit code is 0 whatever the guide's outcome.
pub fn run(args: StandArgs) -> Result<u8, String> {
    let Some(scenario) = args.scenario else {
        let width = STAND_BUILTINS
            .iter()
            .map(|b| b.name.len())
            .max()
            .unwrap_or(0);
        let mut text = String::new();
        for b in STAND_BUILTINS {
            text.push_str(&format!("{:width$}  {}\n", b.name, b.summary()));
        }
        text.push_str(
            "
asi-lift stand NAME runs one (the SafeMOTION thesis' test guides, appendix A); \
             asi-lift stand show NAME prints it.
",
        );
        print_out(&text)?;
        return Ok(0);
    };
    // Refuse a report file that exists, or that is the scenario itself, before running.
    super::output::clean_up_on_signals()?;
    let mut outs = Outputs::new(args.force);
    if scenario.exists() {
        outs.input("the scenario", &scenario)?;
    }
    let sink = outs.add("--report", &args.report)?;
    let plot_format = args.plot.as_deref().map(picture::format_of).transpose()?;
    let plot_sink = args
        .plot
        .as_deref()
        .map(|p| outs.add("--plot", p))
        .transpose()?;
    let sc = load(&scenario)?;
    let (report, samples) = run_sampled(&sc);
    let body = match args.format {
        super::run::Format::Text => report.to_text(),
        super::run::Format::Json => {
            report
                .to_json()
                .map_err(|e| format!("the report as JSON: {e}"))?
                + "\n"
        }
    };
    outs.write_all(&sink, &body)?;
    if let (Some(plot_sink), Some(format), Some(path)) = (&plot_sink, plot_format, &args.plot) {
        let picture = stand_plot::draw(&report, &samples, format)
            .map_err(|e| format!("--plot {}: {e}", path.display()))?;
        outs.write_all(plot_sink, &picture)?;
    }
    outs.commit()?;
    Ok(0)
}

/// A file if there is one by that name (`-` for standard input), else a built-in scenario.
fn load(scenario: &Path) -> Result<StandScenario, String> {
    let is_file =
        scenario == Path::new("-") || scenario.exists() || scenario.components().count() > 1;
    if is_file {
        let text = read_input(scenario, super::MAX_TOML_BYTES)?;
        return StandScenario::from_toml(&scenario.display().to_string(), &text)
            .map_err(|e| e.to_string());
    }
    stand_scenario(builtin(&scenario.to_string_lossy())?).map_err(|e| e.to_string())
}

/// Prints the built-in stand scenario `name` as its file.
pub fn show(name: &str) -> Result<u8, String> {
    print_out(builtin(name)?.text)?;
    Ok(0)
}

/// The built-in stand scenario `name`, or an error that lists the names.
fn builtin(name: &str) -> Result<&'static Builtin, String> {
    find(name).ok_or_else(|| {
        let names: Vec<&str> = STAND_BUILTINS.iter().map(|b| b.name).collect();
        format!(
            "{name}: no built-in stand scenario of that name (and no file {name} here); there are {}",
            names.join(", ")
        )
    })
}
