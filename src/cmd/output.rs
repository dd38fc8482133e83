//! A command's outputs, checked before any work: every file is opened as a temporary file
//! beside its place at once (so a missing directory or a read-only one is reported before a
//! minute of simulation), and renamed into place only when the command has written it all.
//! A refused or failed command leaves no empty or half-written file behind, and never replaces
//! a user's file unless `--force` is given.
//!
//! Two outputs (or an output and an input) that name one file through different spellings
//! (`a.out` and `./a.out`, an absolute path, a symbolic or a hard link) are the same file: the
//! check compares the file's identity (device and inode of an existing file; the canonical
//! directory and name of a new one), not the strings.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use tempfile::NamedTempFile;

/// The temporary files of the outputs being written, for [`clean_up_on_signals`] to remove.
static TEMPS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn temps() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    TEMPS.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Makes SIGINT, SIGTERM and SIGHUP (Ctrl-C, `kill`, a closed terminal) end the command as
/// they would, with the exit status 128 + the signal's number (130, 143, 129), but only after
/// removing the temporary files of its outputs: an interrupted command leaves nothing behind,
/// and the files at the outputs' places keep what they had.
pub fn clean_up_on_signals() -> Result<(), String> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP])
        .map_err(|e| format!("cannot handle signals: {e}"))?;
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            if let Some(signal) = signals.forever().next() {
                // Held to the end: no output is moved into place meanwhile.
                let temps = temps();
                for p in temps.iter() {
                    let _ = std::fs::remove_file(p);
                }
                std::process::exit(128 + signal);
            }
        })
        .map_err(|e| format!("cannot handle signals: {e}"))?;
    Ok(())
}

/// Standard output as an output stream: once its reader has gone, it takes everything quietly
/// and says so through the flag, so that the command stops instead of failing on every write.
struct StdoutSink {
    out: std::io::BufWriter<std::io::Stdout>,
    gone: Arc<AtomicBool>,
}

impl StdoutSink {
    fn check(&self, r: std::io::Result<()>) -> std::io::Result<()> {
        match r {
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
                self.gone.store(true, Ordering::Relaxed);
                Ok(())
            }
            r => r,
        }
    }
}

impl Write for StdoutSink {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.gone.load(Ordering::Relaxed) {
            return Ok(buf.len());
        }
        let r = self.out.write_all(buf);
        self.check(r).map(|()| buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        if self.gone.load(Ordering::Relaxed) {
            return Ok(());
        }
        let r = self.out.flush();
        self.check(r)
    }
}

/// What an existing file is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// A regular file.
    File,
    /// A directory.
    Dir,
    /// A character device (`/dev/null`): written directly, and it takes any number of
    /// writers, so two outputs may name it.
    Device,
    /// A pipe or another special file: written directly, but two outputs would interleave
    /// in it.
    Stream,
}

/// What names a file, whatever the spelling.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Identity {
    /// Standard output (or input): `-`.
    Std,
    /// An existing file: device and inode (links followed), and what it is.
    Inode(u64, u64, Kind),
    /// A file to be made: its canonical directory and its name.
    New(PathBuf),
}

fn identity(path: &Path) -> Result<Identity, String> {
    if path == Path::new("-") {
        return Ok(Identity::Std);
    }
    if let Ok(m) = std::fs::metadata(path) {
        use std::os::unix::fs::{FileTypeExt, MetadataExt};
        let kind = if m.is_file() {
            Kind::File
        } else if m.is_dir() {
            Kind::Dir
        } else if m.file_type().is_char_device() {
            Kind::Device
        } else {
            Kind::Stream
        };
        return Ok(Identity::Inode(m.dev(), m.ino(), kind));
    }
    let (dir, name) = split(path)?;
    let dir = dir
        .canonicalize()
        .map_err(|e| format!("{}: the directory {}: {e}", path.display(), dir.display()))?;
    Ok(Identity::New(dir.join(name)))
}

/// The directory (`.` for a bare name) and the file name of `path`.
fn split(path: &Path) -> Result<(PathBuf, &std::ffi::OsStr), String> {
    let name = path
        .file_name()
        .ok_or_else(|| format!("{}: not a file name", path.display()))?;
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    Ok((dir, name))
}

/// Refuses the output `flag` at `path` when it names one of the `inputs` (flag and path), in
/// any spelling: for an output written directly rather than through [`Outputs`] (a campaign's
/// lines), which `--force` must not let truncate the file the command reads.
pub fn refuse_inputs(flag: &str, path: &Path, inputs: &[(&str, &Path)]) -> Result<(), String> {
    if path == Path::new("-") {
        return Ok(());
    }
    let id = identity(path)?;
    // A character device (`/dev/null`) read and written is no file truncated.
    if matches!(id, Identity::Inode(.., Kind::Device)) {
        return Ok(());
    }
    for &(what, input) in inputs {
        if input == Path::new("-") || identity(input)? != id {
            continue;
        }
        return Err(if input.as_os_str() == path.as_os_str() {
            format!("{what} and {flag} both name {}", path.display())
        } else {
            format!(
                "{what} {} and {flag} {} are the same file",
                input.display(),
                path.display()
            )
        });
    }
    Ok(())
}

/// One output being written.
struct Pending {
    flag: &'static str,
    /// Where it goes in the end (symbolic links resolved, so a link keeps pointing at it).
    place: PathBuf,
    /// As the user wrote it, for messages.
    shown: PathBuf,
    target: Target,
    /// Not written whole: left out at the commit.
    discarded: bool,
}

/// How an output file is written.
enum Target {
    /// A temporary file beside the place, renamed into place at the commit.
    Temp(NamedTempFile),
    /// A device or a pipe (`/dev/null`, a FIFO): written directly, it holds no file to lose.
    Stream(File),
}

/// The outputs of one command: add them all, then write, then [`Outputs::commit`].
pub struct Outputs {
    force: bool,
    /// Set once standard output's reader has gone.
    stdout_gone: Arc<AtomicBool>,
    seen: Vec<(&'static str, PathBuf, Identity)>,
    pending: Vec<Pending>,
}

/// Where an added output goes.
pub enum Sink {
    /// Standard output.
    Stdout,
    /// The index of a file among the pending ones.
    File(usize),
}

impl Outputs {
    /// No outputs yet; `force` lets a file that exists be replaced.
    pub fn new(force: bool) -> Outputs {
        Outputs {
            force,
            stdout_gone: Arc::default(),
            seen: Vec::new(),
            pending: Vec::new(),
        }
    }

    /// An input that no output may name (the scenario file, the capture).
    pub fn input(&mut self, flag: &'static str, path: &Path) -> Result<(), String> {
        if path == Path::new("-") {
            return Ok(());
        }
        let id = identity(path)?;
        self.seen.push((flag, path.to_path_buf(), id));
        Ok(())
    }

    /// Checks the output `flag` at `path` (`-` = standard output) and, for a file, opens its
    /// temporary file beside it now. Refused: a second output to standard output, a file that
    /// another output or an input names, a file that exists without `force`, a place that
    /// cannot be written.
    pub fn add(&mut self, flag: &'static str, path: &Path) -> Result<Sink, String> {
        let id = identity(path)?;
        // A character device takes what each writer gives it (`/dev/null` its share of
        // everything): only a file or a pipe cannot serve two.
        let shared = matches!(id, Identity::Inode(.., Kind::Device));
        if let Some((other, other_path, _)) = self.seen.iter().find(|(_, _, i)| *i == id && !shared)
        {
            return Err(if id == Identity::Std {
                format!("{other} and {flag} both want standard output: give one a file")
            } else if other_path.as_os_str() == path.as_os_str() {
                format!("{other} and {flag} both name {}", path.display())
            } else {
                format!(
                    "{other} {} and {flag} {} are the same file",
                    other_path.display(),
                    path.display()
                )
            });
        }
        self.seen.push((flag, path.to_path_buf(), id.clone()));
        let place = match id {
            Identity::Std => return Ok(Sink::Stdout),
            Identity::Inode(.., Kind::Dir) => {
                return Err(format!("{flag} {}: a directory", path.display()));
            }
            Identity::Inode(.., Kind::Stream | Kind::Device) => {
                let f = std::fs::OpenOptions::new()
                    .write(true)
                    .open(path)
                    .map_err(|e| format!("{flag} {}: {e}", path.display()))?;
                self.pending.push(Pending {
                    flag,
                    place: path.to_path_buf(),
                    shown: path.to_path_buf(),
                    target: Target::Stream(f),
                    discarded: false,
                });
                return Ok(Sink::File(self.pending.len() - 1));
            }
            Identity::Inode(.., Kind::File) => {
                if !self.force {
                    return Err(format!(
                        "{flag} {} exists; pass --force to overwrite it",
                        path.display()
                    ));
                }
                path.canonicalize()
                    .map_err(|e| format!("{flag} {}: {e}", path.display()))?
            }
            Identity::New(place) => place,
        };
        let (dir, _) = split(&place)?;
        // Created as any new file is, 0666 less the umask (not the temporary file's 0600): the
        // output is the user's file once in place.
        let temp = tempfile::Builder::new()
            .prefix(".asi-lift-")
            .suffix(".part")
            .permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666))
            .tempfile_in(&dir)
            .map_err(|e| format!("{flag} {}: cannot write there: {e}", path.display()))?;
        temps().push(temp.path().to_path_buf());
        self.pending.push(Pending {
            flag,
            place,
            shown: path.to_path_buf(),
            target: Target::Temp(temp),
            discarded: false,
        });
        Ok(Sink::File(self.pending.len() - 1))
    }

    /// A writer for `sink`, buffered.
    pub fn writer(&self, sink: &Sink) -> Result<Box<dyn Write + Send>, String> {
        match sink {
            Sink::Stdout => Ok(Box::new(StdoutSink {
                out: std::io::BufWriter::new(std::io::stdout()),
                gone: Arc::clone(&self.stdout_gone),
            })),
            Sink::File(i) => {
                let p = &self.pending[*i];
                let file = match &p.target {
                    Target::Temp(t) => t.as_file(),
                    Target::Stream(f) => f,
                };
                let f: File = file
                    .try_clone()
                    .map_err(|e| format!("{} {}: {e}", p.flag, p.shown.display()))?;
                Ok(Box::new(std::io::BufWriter::new(f)))
            }
        }
    }

    /// The file of `sink` itself, unbuffered, for a writer that starts it again (a live run's
    /// trace when the run restarts); standard output has none.
    pub fn file(&self, sink: &Sink) -> Result<File, String> {
        let Sink::File(i) = sink else {
            return Err("standard output is no file to start again".into());
        };
        let p = &self.pending[*i];
        let file = match &p.target {
            Target::Temp(t) => t.as_file(),
            Target::Stream(f) => f,
        };
        file.try_clone()
            .map_err(|e| format!("{} {}: {e}", p.flag, p.shown.display()))
    }

    /// `true` once the reader of standard output has gone (`| head`): a command should stop
    /// and end quietly.
    pub fn stdout_gone(&self) -> bool {
        self.stdout_gone.load(Ordering::Relaxed)
    }

    /// Writes all of `data` (text, or a picture's bytes) to `sink` (standard output: a reader
    /// that has gone is no error).
    pub fn write_all(&self, sink: &Sink, data: impl AsRef<[u8]>) -> Result<(), String> {
        let data = data.as_ref();
        match sink {
            Sink::Stdout => super::write_out(data),
            Sink::File(i) => {
                let p = &self.pending[*i];
                let mut w = self.writer(sink)?;
                w.write_all(data)
                    .and_then(|()| w.flush())
                    .map_err(|e| format!("{} {}: {e}", p.flag, p.shown.display()))
            }
        }
    }

    /// Drops the output of `sink` that could not be written whole: its temporary file goes,
    /// and whatever was at its place stays. Returns how to name it in a message (`--trace
    /// t.jsonl`); `None` for standard output, which cannot be taken back.
    pub fn discard(&mut self, sink: &Sink) -> Option<String> {
        let Sink::File(i) = sink else {
            return None;
        };
        let p = &mut self.pending[*i];
        // At the commit its temporary file is deleted instead of renamed.
        p.discarded = true;
        Some(format!("{} {}", p.flag, p.shown.display()))
    }

    /// When the run could not write its trace or waveforms whole (`error`, the report's
    /// `output_error`), keeps every one of `sinks` out of place and returns the message the
    /// command ends with, naming them; `None` when all went well.
    pub fn keep_out_unwritten(
        &mut self,
        error: Option<&str>,
        sinks: &[(&'static str, Option<&Sink>)],
    ) -> Option<String> {
        let e = error?;
        let names: Vec<String> = sinks
            .iter()
            .filter_map(|&(flag, sink)| {
                let sink = sink?;
                Some(self.discard(sink).unwrap_or_else(|| format!("{flag} -")))
            })
            .collect();
        Some(format!(
            "{}: cannot write: {e}; the report is written, the trace and waveforms are not",
            names.join(", ")
        ))
    }

    /// Moves every file into place. Without `force`, a file that appeared at a place while the
    /// command ran is kept, and this output is reported instead of replacing it.
    pub fn commit(mut self) -> Result<(), String> {
        for p in std::mem::take(&mut self.pending) {
            let Target::Temp(temp) = p.target else {
                continue;
            };
            // A signal now waits until this file is in place or gone.
            let mut temps = temps();
            temps.retain(|t| t != temp.path());
            if p.discarded {
                // Dropped, the temporary file is deleted; the place keeps what it had.
                drop(temp);
                continue;
            }
            // A file replaced keeps its mode.
            if let Ok(m) = std::fs::metadata(&p.place) {
                temp.as_file()
                    .set_permissions(m.permissions())
                    .map_err(|e| format!("{} {}: {e}", p.flag, p.shown.display()))?;
            }
            temp.as_file()
                .sync_data()
                .map_err(|e| format!("{} {}: {e}", p.flag, p.shown.display()))?;
            let result = if self.force {
                temp.persist(&p.place).map(|_| ())
            } else {
                temp.persist_noclobber(&p.place).map(|_| ())
            };
            result.map_err(|e| {
                format!(
                    "{} {}: {}; the output is lost",
                    p.flag,
                    p.shown.display(),
                    e.error
                )
            })?;
        }
        Ok(())
    }
}

impl Drop for Outputs {
    /// The temporary files not moved into place go.
    fn drop(&mut self) {
        let mut temps = temps();
        for p in &self.pending {
            if let Target::Temp(t) = &p.target {
                // Deleted here, under the lock, so that a signal finds it listed or gone.
                let _ = std::fs::remove_file(t.path());
                temps.retain(|x| x != t.path());
            }
        }
    }
}
