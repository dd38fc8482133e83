//! The `asi-lift` command: argument parsing ([`Cli`], [`run`]) and one module per subcommand
//! ([`cmd`]). The simulation lives in the `rig` library, the files in `asi-trace`.
//!
//! A library only so that the command's tests (`src/cli_tests.rs`) can call its parts, and the
//! command is compiled once for the binary and the tests; not an API for other programs.

pub mod cmd;

use clap::{CommandFactory, Parser, Subcommand};

/// asi-lift: the AS-Interface laboratory lift, simulated to the bit and to the millisecond.
#[derive(Parser)]
#[command(version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the lab lift: the AS-i bus, the lift, the PLC program and the safety logic on one
    /// simulated clock, driven by a scenario file (the built-in demo without one).
    Run(cmd::run::RunArgs),
    /// List the built-in scenarios (one line each), or print one as TOML to copy and edit.
    Scenarios {
        #[command(subcommand)]
        action: Option<cmd::scenarios::ScenariosAction>,
    },
    /// Show how a master call or slave response travels on the line: bits, Manchester levels,
    /// APM pulses; optionally write its line voltage as CSV.
    ///
    /// Calls by their ZMD mnemonic: dexg ADDR VALUE, wpar ADDR VALUE, adra NEW, wid1 VALUE,
    /// dela|res|rdio|rdid|rid1|rid2|rdst ADDR, br01, resp VALUE. ADDR is 0..31 with an optional
    /// A/B suffix (7B); VALUE is four binary digits (1010), 0b1010 or 0..15.
    Encode(cmd::encode::EncodeArgs),
    /// Decode a capture of the line into telegrams, through the comparator and the seven
    /// receiver checks.
    ///
    /// A capture is an oscilloscope's CSV (`time,voltage` in seconds and volts; a header line
    /// and `#` comments allowed) or a VCD with the line voltage (a real signal) or the
    /// demodulated line (a 1-bit wire, idle high: every record is one pulse, 0 negative, 1
    /// positive). Prints one line per telegram: time in seconds in the capture's own time
    /// base, type (request, response, unknown), bits ST..EB, call, address, info or data, and
    /// the failed checks; then a summary. A capture without telegrams says "no telegrams
    /// found" and exits with 0.
    Decode(cmd::decode::DecodeArgs),
    /// Run the lab lift live, on the wall clock, behind a virtual AS-i gateway that speaks
    /// Modbus TCP (the asi-lift guide, chapter "Live mode and your own controller"): a client watches the built-in controller, or with
    /// `--controller external` is the PLC itself. Ctrl-C or `--until` ends the run and writes
    /// the report.
    Serve(cmd::serve::ServeArgs),
    /// Timing analysis (the asi-lift guide, chapter "Timing"): transaction and cycle time, per-slave update period,
    /// repeats, handshake word times and end-to-end latencies, analytic and simulated side by
    /// side, compared with the textbook cycle time T = (n + 2) · 154 µs.
    Timing(cmd::timing::TimingArgs),
    /// The teaching stand of the SafeMOTION thesis (the asi-lift guide, chapter "The teaching stand"): a
    /// servo axis whose safe drive (STO, SOS, SS1, SS2, SLS, SLI, SDI) is requested by a
    /// light curtain. Runs a stand scenario (a file or a built-in name: one per test guide)
    /// and prints what a student sees: the HMI page's states, the stopwatch, torque and
    /// speed, with times.
    /// Without an argument it lists the built-in ones; `stand show NAME` prints one as its
    /// file, to copy and edit.
    #[command(args_conflicts_with_subcommands = true)]
    Stand {
        #[command(subcommand)]
        action: Option<cmd::stand::StandAction>,
        #[command(flatten)]
        args: cmd::stand::StandArgs,
    },
    /// Run many random valid scenarios on the whole rig (the asi-lift guide, chapter
    /// "Campaigns"): one JSON
    /// line per run, every failure shrunk to a scenario file that reproduces it; or merge
    /// result files with `campaign summarize`.
    #[command(args_conflicts_with_subcommands = true)]
    Campaign {
        #[command(subcommand)]
        action: Option<cmd::campaign::CampaignAction>,
        #[command(flatten)]
        args: cmd::campaign::CampaignArgs,
    },
    /// Inject every fault of the catalogue at every instant of a grid over a scenario (the
    /// asi-lift guide, chapter "The fault explorer"): the run is forked at each instant, each
    /// fork runs to its verdict (back in service, a safe stop that needs a person, a violation,
    /// a panic); one JSON line per fork, the FMEA sheet of fault kind × lift phase; or merge
    /// result files with `explore summarize`.
    #[command(args_conflicts_with_subcommands = true)]
    Explore {
        #[command(subcommand)]
        action: Option<cmd::explore::ExploreAction>,
        #[command(flatten)]
        args: cmd::explore::ExploreArgs,
    },
    /// Print the shell completion script for bash, zsh, fish, elvish or powershell
    /// (`asi-lift completions bash > ~/.local/share/bash-completion/completions/asi-lift`).
    Completions(cmd::completions::CompletionsArgs),
    /// Print the manual page in roff (`asi-lift man | man -l -`), or write one page per
    /// subcommand into a directory with `--out DIR`.
    Man(cmd::man::ManArgs),
}

/// Runs the command `cli`: its exit code, or the message of the error that stopped it.
pub fn run(cli: Cli) -> Result<u8, String> {
    match cli.command {
        Command::Run(args) => cmd::run::run(args),
        Command::Scenarios { action } => cmd::scenarios::run(action),
        Command::Encode(args) => cmd::encode::run(args),
        Command::Decode(args) => cmd::decode::run(args),
        Command::Timing(args) => cmd::timing::run(args),
        Command::Serve(args) => cmd::serve::run(args),
        Command::Stand { action, args } => match action {
            None => cmd::stand::run(args),
            Some(cmd::stand::StandAction::Show { name }) => cmd::stand::show(&name),
        },
        Command::Campaign { action, args } => match action {
            None => cmd::campaign::run(args),
            Some(cmd::campaign::CampaignAction::Summarize { files, json }) => {
                cmd::campaign::summarize_files(&files, json)
            }
        },
        Command::Explore { action, args } => match action {
            None => cmd::explore::run(args),
            Some(cmd::explore::ExploreAction::Summarize {
                files,
                json,
                svg,
                force,
            }) => cmd::explore::summarize_files(&files, json, svg.as_deref(), force),
        },
        Command::Completions(args) => cmd::completions::run(args, Cli::command()),
        Command::Man(args) => cmd::man::run(args, Cli::command()),
    }
}
