//! The subcommands of `asi-lift`, one module each, and the file handling they share: inputs
//! from a file or standard input, outputs that never replace a user's file unless `--force`
//! is given.

pub mod campaign;
pub mod decode;
pub mod encode;
pub mod plot;
pub mod run;
pub mod timing;

use std::io::{BufRead, Read, Write};
use std::path::Path;

/// Exit code of a run that found safety violations.
pub const EXIT_VIOLATIONS: u8 = 3;

/// Writes `text` to standard output; a reader that has gone (`| head`) is no error.
pub fn print_out(text: &str) -> Result<(), String> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
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

pub fn read_input(path: &Path) -> Result<String, String> {
    if path == Path::new("-") {
        let mut s = String::new();
        std::io::stdin()
            .read_to_string(&mut s)
            .map_err(|e| format!("standard input: {e}"))?;
        return Ok(s);
    }
    std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))
}

/// Writes `text` to `path`, never replacing a file the user has unless `force` is given.
pub fn write_output(path: &Path, text: &str, force: bool) -> Result<(), String> {
    let mut out = open_output(path, force)?;
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// Opens `path` for writing (`-` = standard output), never replacing a file the user has
/// unless `force` is given.
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
