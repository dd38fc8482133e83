//! The subcommands of `asi-lift`, one module each, and the file handling they share: inputs
//! from a file or standard input, outputs that never replace a user's file unless `--force`
//! is given ([`output`]).

pub mod campaign;
pub mod completions;
pub mod decode;
pub mod encode;
pub mod explore;
mod explore_svg;
pub mod man;
pub mod output;
pub mod picture;
pub mod plot;
pub mod run;
pub mod scenarios;
pub mod serve;
pub mod stand;
mod stand_plot;
pub mod timing;

use std::io::{BufRead, Write};
use std::path::Path;

/// Exit code of a run that found safety violations.
pub const EXIT_VIOLATIONS: u8 = 3;

/// Writes `text` to standard output; a reader that has gone (`| head`) is no error.
pub fn print_out(text: &str) -> Result<(), String> {
    write_out(text.as_bytes())
}

/// Writes `data` to standard output; a reader that has gone (`| head`) is no error.
pub fn write_out(data: &[u8]) -> Result<(), String> {
    let mut out = std::io::stdout().lock();
    match out.write_all(data).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(format!("standard output: {e}"))
        }
        _ => Ok(()),
    }
}

/// A file (`-` = standard input) to read line by line, and its name for messages.
pub fn open_input(path: &Path) -> Result<(String, Box<dyn BufRead>), String> {
    if path == Path::new("-") {
        return Ok(("standard input".into(), Box::new(std::io::stdin().lock())));
    }
    let name = path.display().to_string();
    let f = std::fs::File::open(path).map_err(|e| format!("{name}: {e}"))?;
    Ok((name, Box::new(std::io::BufReader::new(f))))
}

/// The largest TOML input read (a scenario, a stand scenario, a campaign profile): they are a
/// few kB, so a larger one (`/dev/zero`, a capture given by mistake) is refused before it
/// fills memory.
pub const MAX_TOML_BYTES: u64 = 16 << 20;

/// The largest campaign result file `campaign summarize` reads (a few hundred bytes a run:
/// some million runs).
pub const MAX_RESULTS_BYTES: u64 = 1 << 30;

/// The whole of a text file (`-` = standard input), at most `max` bytes: a longer one is
/// refused, having read no more than that. Text that is not UTF-8 is refused at the line and
/// column of its first bad byte.
pub fn read_input(path: &Path, max: u64) -> Result<String, String> {
    if path == Path::new("-") {
        rig::scenario::program::read_text("standard input", std::io::stdin().lock(), max)
    } else {
        let name = path.display().to_string();
        let f = std::fs::File::open(path).map_err(|e| format!("{name}: {e}"))?;
        rig::scenario::program::read_text(&name, f, max)
    }
}

/// Opens `path` for writing (`-` = standard output), never replacing a file the user has
/// unless `force` is given. For a stream written as it goes (a campaign's lines, which are
/// worth keeping when the campaign is stopped); whole outputs go through [`output::Outputs`].
pub fn open_output(path: &Path, force: bool) -> Result<Box<dyn Write>, String> {
    if path == Path::new("-") {
        return Ok(Box::new(std::io::BufWriter::new(std::io::stdout())));
    }
    let mut options = std::fs::OpenOptions::new();
    options.write(true);
    if force {
        options.create(true).truncate(true);
    } else {
        options.create_new(true);
    }
    let f = options.open(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::AlreadyExists => {
            format!("{} exists; pass --force to overwrite it", path.display())
        }
        _ => format!("{}: {e}", path.display()),
    })?;
    Ok(Box::new(std::io::BufWriter::new(f)))
}
