//! A program's source text, places in it ([`Span`]), and what is wrong at a place
//! ([`Diagnostic`]), rendered as a PLC programmer's tools render it: `file:line:column`, the
//! source line and a caret under the place, and the cause.

use std::fmt;

/// The largest source asi-lift reads: far beyond any PLC program (the thesis's lift program
/// is a few hundred lines), and small enough that every pass over it stays quick.
pub const MAX_SOURCE_BYTES: usize = 4 << 20;

/// The most characters of a line a rendered diagnostic shows.
pub const SHOWN_LINE: usize = 160;

/// The most errors a source gets: a hostile or garbled file is refused without a flood.
pub const MAX_ERRORS: usize = 100;

/// A place in a source: bytes `start..end` of its text.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Span {
    /// The first byte.
    pub start: u32,
    /// One past the last byte.
    pub end: u32,
}

impl Span {
    /// Bytes `start..end`.
    pub fn new(start: usize, end: usize) -> Span {
        // A source is at most `MAX_SOURCE_BYTES`, so every offset fits.
        let clamp = |n: usize| u32::try_from(n).unwrap_or(u32::MAX);
        Span {
            start: clamp(start),
            end: clamp(end.max(start)),
        }
    }

    /// From the start of `self` to the end of `other`.
    pub fn to(self, other: Span) -> Span {
        Span {
            start: self.start.min(other.start),
            end: self.end.max(other.end),
        }
    }
}

/// A program's source: one file, or several compiled together (a program with the libraries
/// it uses), each with its name (as the user gave it) and its text. The files' texts follow
/// one another in one text, so that a place ([`Span`]) names its file too.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Source {
    name: String,
    text: String,
    /// The byte offset of each line's start.
    lines: Vec<usize>,
    /// Each file's name and the byte offset of its start in `text`, in order.
    files: Vec<(String, usize)>,
}

impl Source {
    /// The source `text`, named `name` in messages.
    pub fn new(name: impl Into<String>, text: impl Into<String>) -> Source {
        let name = name.into();
        Source::with_text(name.clone(), text.into(), vec![(name, 0)])
    }

    /// Several files compiled as one program, in the order given (libraries first, say): a
    /// place in any of them is rendered with its own file's name, line and column. The
    /// first file names the whole.
    pub fn files<N: Into<String>, T: AsRef<str>>(
        files: impl IntoIterator<Item = (N, T)>,
    ) -> Source {
        let mut text = String::new();
        let mut starts = Vec::new();
        for (name, t) in files {
            if !starts.is_empty() {
                // A line break between two files: no line is shared.
                text.push('\n');
            }
            starts.push((name.into(), text.len()));
            text.push_str(t.as_ref());
        }
        if starts.is_empty() {
            starts.push((String::new(), 0));
        }
        Source::with_text(starts[0].0.clone(), text, starts)
    }

    fn with_text(name: String, text: String, files: Vec<(String, usize)>) -> Source {
        let mut lines = vec![0];
        lines.extend(
            text.bytes()
                .enumerate()
                .filter(|&(_, b)| b == b'\n')
                .map(|(i, _)| i + 1),
        );
        Source {
            name,
            text,
            lines,
            files,
        }
    }

    /// The name (the first file's).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Each file's name and its byte range in [`Source::text`], in order.
    pub fn file_ranges(&self) -> impl Iterator<Item = (&str, std::ops::Range<usize>)> + '_ {
        self.files.iter().enumerate().map(|(i, (n, start))| {
            let end = self
                .files
                .get(i + 1)
                .map_or(self.text.len(), |(_, next)| next - 1);
            (n.as_str(), *start..end)
        })
    }

    /// The name of the file that holds byte `offset`.
    pub fn file_at(&self, offset: u32) -> &str {
        let i = self
            .files
            .partition_point(|(_, s)| *s <= offset as usize)
            .max(1);
        &self.files[i - 1].0
    }

    /// The line within its file of the text's line `line` (both 1-based).
    fn file_line(&self, offset: usize, line: usize) -> usize {
        let i = self.files.partition_point(|(_, s)| *s <= offset).max(1);
        let start = self.files[i - 1].1;
        line - self.lines.partition_point(|&s| s < start)
    }

    /// The text.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The line (1-based, within its file), the column (1-based, in characters) and the
    /// text of the line at byte `offset`.
    pub fn locate(&self, offset: u32) -> (usize, usize, &str) {
        let offset = (offset as usize).min(self.text.len());
        let line = self.lines.partition_point(|&s| s <= offset).max(1);
        let file_line = self.file_line(offset, line);
        let start = self.lines[line - 1];
        let end = self.text[start..]
            .find('\n')
            .map_or(self.text.len(), |n| start + n);
        let line_text = self.text.get(start..end).unwrap_or("");
        let line_text = line_text.strip_suffix('\r').unwrap_or(line_text);
        let column = self
            .text
            .get(start..offset)
            .map_or(1, |s| s.chars().count() + 1);
        (file_line, column, line_text)
    }

    /// `diagnostic` as a PLC programmer's tools print it (see [`Diagnostic`]). A line longer
    /// than [`SHOWN_LINE`] characters is shown around the place, cut with `…`.
    pub fn render(&self, d: &Diagnostic) -> String {
        let (line, column, text) = self.locate(d.span.start);
        let chars = text.chars().count();
        let width = self
            .text
            .get(d.span.start as usize..d.span.end as usize)
            .map_or(1, |s| s.chars().take_while(|&c| c != '\n').count())
            .clamp(1, chars.saturating_sub(column - 1).max(1));
        // The part of the line shown: all of it, or a window around the place.
        let (from, to) = if chars <= SHOWN_LINE {
            (0, chars)
        } else {
            let from = (column - 1).saturating_sub(SHOWN_LINE / 2);
            (from, (from + SHOWN_LINE).min(chars))
        };
        let head = if from > 0 { "…" } else { "" };
        let tail = if to < chars { "…" } else { "" };
        let shown: String = text.chars().skip(from).take(to - from).collect();
        // The caret runs under the place, within the part shown, and is at least one wide; a
        // tab before it is kept so that it lines up as the line does.
        let lead: String = head
            .chars()
            .map(|_| ' ')
            .chain(text.chars().skip(from).take(column - 1 - from).map(|c| {
                if c == '\t' {
                    '\t'
                } else {
                    ' '
                }
            }))
            .collect();
        let width = width.min(to.saturating_sub(column - 1).max(1));
        format!(
            "{}:{line}:{column}: {}: {}\n{head}{shown}{tail}\n{lead}{}",
            self.file_at(d.span.start),
            d.severity,
            d.message,
            "^".repeat(width)
        )
    }

    /// Every diagnostic, rendered, one after another with a blank line between.
    pub fn render_all(&self, ds: &[Diagnostic]) -> String {
        ds.iter()
            .map(|d| self.render(d))
            .collect::<Vec<_>>()
            .join("\n\n")
    }
}

/// How bad.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Severity {
    /// The program is refused.
    Error,
}

impl fmt::Display for Severity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Severity::Error => "error",
        })
    }
}

/// What is wrong at a place of a source.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    /// Where.
    pub span: Span,
    /// How bad.
    pub severity: Severity,
    /// The cause, in words.
    pub message: String,
}

impl Diagnostic {
    /// An error at `span`.
    pub fn error(span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            span,
            severity: Severity::Error,
            message: message.into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_place_is_rendered_with_its_line_and_a_caret() {
        let s = Source::new("lift.st", "PROGRAM P\n  x := 1 +;\nEND_PROGRAM\n");
        let at = s.text().find('+').expect("plus");
        let d = Diagnostic::error(Span::new(at, at + 1), "an operand is missing after `+`");
        assert_eq!(
            s.render(&d),
            "lift.st:2:10: error: an operand is missing after `+`\n  x := 1 +;\n         ^"
        );
    }

    #[test]
    fn columns_count_characters_and_tabs_line_up() {
        let s = Source::new("a.st", "x\n\t(* ä *) y := 1;\r\n");
        let at = s.text().find('y').expect("y");
        assert_eq!(s.locate(at as u32), (2, 10, "\t(* ä *) y := 1;"));
        let d = Diagnostic::error(Span::new(at, at + 1), "unknown");
        assert!(s.render(&d).ends_with("\n\t        ^"), "{}", s.render(&d));
    }

    #[test]
    fn a_long_line_is_shown_around_the_place() {
        let line = format!("{}?{}", "a".repeat(500), "b".repeat(500));
        let s = Source::new("long.st", line);
        let d = Diagnostic::error(Span::new(500, 501), "here");
        let r = s.render(&d);
        let shown = r.lines().nth(1).expect("the line");
        assert_eq!(shown.chars().count(), SHOWN_LINE + 2);
        let caret = r.lines().nth(2).expect("the caret");
        let at = shown.chars().position(|c| c == '?').expect("the place");
        assert_eq!(caret.chars().position(|c| c == '^'), Some(at));
    }

    #[test]
    fn a_place_in_one_of_several_files_names_that_file_and_its_own_line() {
        let s = Source::files([
            ("lab.st", "FUNCTION_BLOCK A\nEND_FUNCTION_BLOCK\n"),
            ("lift.st", "PROGRAM P\n  x := 1 +;\nEND_PROGRAM"),
        ]);
        let at = s.text().find('+').expect("plus");
        let d = Diagnostic::error(Span::new(at, at + 1), "an operand is missing after `+`");
        assert_eq!(
            s.render(&d),
            "lift.st:2:10: error: an operand is missing after `+`\n  x := 1 +;\n         ^"
        );
        let a = s.text().find('A').expect("A");
        assert_eq!(s.file_at(a as u32), "lab.st");
        assert_eq!(s.locate(a as u32).0, 1);
        let ranges: Vec<_> = s.file_ranges().collect();
        assert_eq!(
            &s.text()[ranges[1].1.clone()],
            "PROGRAM P\n  x := 1 +;\nEND_PROGRAM"
        );
        assert_eq!(
            &s.text()[ranges[0].1.clone()],
            "FUNCTION_BLOCK A\nEND_FUNCTION_BLOCK\n"
        );
    }

    #[test]
    fn the_end_of_the_text_is_a_place_too() {
        let s = Source::new("a.st", "PROGRAM");
        let d = Diagnostic::error(Span::new(7, 7), "END_PROGRAM is missing");
        assert_eq!(
            s.render(&d),
            "a.st:1:8: error: END_PROGRAM is missing\nPROGRAM\n       ^"
        );
    }
}
