//! A PLC programmer's own Structured Text program as the lift's controller: the file named
//! by a scenario's `[controller] program` or by `--controller`, read and compiled once, then
//! put in the built-in program's place by [`crate::Rig::new`] on every rig of the scenario
//! (each run of a campaign, each restart of a live run, each fork of a copy).

use controller::structured::StProgram;
use std::fmt;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The largest program file read: a lift program is some kB, so a larger one (`/dev/zero`,
/// a capture given by mistake) is refused before it fills memory.
pub const MAX_PROGRAM_BYTES: u64 = 4 << 20;

/// A Structured Text program, read and compiled: the file's path as given (relative to the
/// working directory, or made so from the scenario file's directory), its text, and the
/// compiled program each rig starts from.
#[derive(Clone)]
pub struct ProgramFile {
    path: PathBuf,
    text: Arc<str>,
    /// The libraries compiled with it (function blocks, types and globals it uses, such as
    /// the lab's handshakes in `controllers/lab.st`): each file's path, as given, and text.
    libraries: Vec<(PathBuf, Arc<str>)>,
    compiled: Arc<StProgram>,
}

impl ProgramFile {
    /// The program in the file at `path`, read (at most [`MAX_PROGRAM_BYTES`], UTF-8) and
    /// compiled together with the libraries in the files `libraries`. The error names the
    /// file and says why; a program that does not compile is refused with every error at
    /// once, each as `file:line:column` with its line and a caret.
    pub fn read(path: &Path, libraries: &[PathBuf]) -> Result<ProgramFile, String> {
        let read = |p: &Path| -> Result<String, String> {
            let name = p.display().to_string();
            let file = std::fs::File::open(p).map_err(|e| format!("{name}: {e}"))?;
            read_text(&name, file, MAX_PROGRAM_BYTES)
        };
        let libs = libraries
            .iter()
            .map(|l| Ok((l.clone(), read(l)?)))
            .collect::<Result<Vec<_>, String>>()?;
        ProgramFile::from_texts(path, &read(path)?, &libs)
    }

    /// The program `text`, named by `path` in its messages and in the report, compiled alone.
    pub fn from_text(path: &Path, text: &str) -> Result<ProgramFile, String> {
        ProgramFile::from_texts(path, text, &[])
    }

    /// The program `text` (named by `path`) compiled together with the `libraries` (each a
    /// file's path and text).
    pub fn from_texts(
        path: &Path,
        text: &str,
        libraries: &[(PathBuf, String)],
    ) -> Result<ProgramFile, String> {
        let name = path.display().to_string();
        let lib_names: Vec<String> = libraries
            .iter()
            .map(|(p, _)| p.display().to_string())
            .collect();
        let libs: Vec<(&str, &str)> = lib_names
            .iter()
            .zip(libraries)
            .map(|(n, (_, t))| (n.as_str(), t.as_str()))
            .collect();
        let compiled = StProgram::compile_with(&libs, &name, text).map_err(|e| {
            format!(
                "{name}: the program is refused ({} error{}):\n{}",
                e.count,
                if e.count == 1 { "" } else { "s" },
                e.rendered.trim_end()
            )
        })?;
        Ok(ProgramFile {
            path: path.to_owned(),
            text: text.into(),
            libraries: libraries
                .iter()
                .map(|(p, t)| (p.clone(), Arc::from(t.as_str())))
                .collect(),
            compiled: Arc::new(compiled),
        })
    }

    /// The libraries' paths, as given.
    pub fn libraries(&self) -> impl Iterator<Item = &Path> {
        self.libraries.iter().map(|(p, _)| p.as_path())
    }

    /// The file's path, as given.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The program as a controller at its first scan, scanned every `scan`.
    pub fn controller(&self, scan: asi_phy::SimDuration) -> StProgram {
        (*self.compiled).clone().with_scan(scan)
    }
}

impl PartialEq for ProgramFile {
    /// The same files with the same texts (the compiled program follows from them).
    fn eq(&self, other: &ProgramFile) -> bool {
        self.path == other.path && self.text == other.text && self.libraries == other.libraries
    }
}

impl fmt::Debug for ProgramFile {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ProgramFile")
            .field("path", &self.path)
            .field("bytes", &self.text.len())
            .field(
                "libraries",
                &self.libraries.iter().map(|(p, _)| p).collect::<Vec<_>>(),
            )
            .finish()
    }
}

/// The whole of `input` (named `name` in messages) as text, at most `max` bytes: a longer one
/// is refused, having read no more than that. Text that is not UTF-8 is refused at the line
/// and column of its first bad byte.
pub fn read_text(name: &str, mut input: impl Read, max: u64) -> Result<String, String> {
    let mut bytes = Vec::new();
    input
        .by_ref()
        .take(max + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("{name}: {e}"))?;
    if bytes.len() as u64 > max {
        return Err(format!(
            "{name}: larger than {} MiB, which is more than such a file holds: is it the right file?",
            max >> 20
        ));
    }
    String::from_utf8(bytes).map_err(|e| {
        let good = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = good.iter().filter(|b| **b == b'\n').count() + 1;
        let line_start = good.iter().rposition(|b| *b == b'\n').map_or(0, |i| i + 1);
        let column = String::from_utf8_lossy(&good[line_start..]).chars().count() + 1;
        let byte = e.as_bytes()[good.len()];
        format!(
            "{name}:{line}:{column}: not UTF-8 text (byte 0x{byte:02X}); the file must be UTF-8"
        )
    })
}
