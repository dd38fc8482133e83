//! `asi-lift man`: the manual pages, generated from the command's own definition
//! (clap_mangen), so that they always have every subcommand and option its `--help` has.

use super::output::Outputs;
use super::print_out;
use std::path::{Path, PathBuf};

/// Arguments of `asi-lift man`.
#[derive(clap::Args)]
pub struct ManArgs {
    /// Write every page into this directory, one for the command and one for each subcommand
    /// (asi-lift.1, asi-lift-run.1, ...), instead of printing the command's page.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Replace pages that exist in the directory.
    #[arg(long, requires = "out")]
    pub force: bool,
}

/// Prints the page of `cmd` (the whole `asi-lift` command), or writes every page into
/// `args.out`.
pub fn run(args: ManArgs, cmd: clap::Command) -> Result<u8, String> {
    // The `help` subcommand is clap's, documented by every page's options: no page of its own.
    let mut cmd = cmd.disable_help_subcommand(true);
    // Built once, so that every subcommand knows its full name (asi-lift-scenarios-show).
    cmd.build();
    match args.out {
        None => print_out(&page(&cmd)?)?,
        Some(dir) => write_pages(&cmd, &dir, args.force)?,
    }
    Ok(0)
}

/// The page of `cmd` in roff.
fn page(cmd: &clap::Command) -> Result<String, String> {
    let mut roff = Vec::new();
    clap_mangen::Man::new(cmd.clone())
        .render(&mut roff)
        .map_err(|e| format!("manual page: {e}"))?;
    String::from_utf8(roff).map_err(|e| format!("manual page: {e}"))
}

/// `cmd` and every subcommand that is not hidden, depth first.
fn all_commands<'a>(cmd: &'a clap::Command, into: &mut Vec<&'a clap::Command>) {
    into.push(cmd);
    for sub in cmd.get_subcommands().filter(|s| !s.is_hide_set()) {
        all_commands(sub, into);
    }
}

/// Writes the pages into `dir` (created if missing) as one output: none replaces a file that
/// exists without `force`, and a refused or failed write leaves none behind.
fn write_pages(cmd: &clap::Command, dir: &Path, force: bool) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("--out {}: {e}", dir.display()))?;
    let mut commands = Vec::new();
    all_commands(cmd, &mut commands);
    let mut outs = Outputs::new(force);
    let mut pages = Vec::new();
    for c in commands {
        let man = clap_mangen::Man::new(c.clone());
        let sink = outs.add("--out", &dir.join(man.get_filename()))?;
        pages.push((sink, page(c)?));
    }
    for (sink, text) in &pages {
        outs.write_all(sink, text)?;
    }
    outs.commit()
}
