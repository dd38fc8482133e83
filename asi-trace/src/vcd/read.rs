//! A small streaming reader of Value Change Dump files (IEEE 1364-2001 §18), as simulators,
//! logic analysers and asi-lift write them: enough to follow one signal of a capture.
//!
//! It reads `$timescale`, `$scope`/`$upscope`, `$var TYPE WIDTH ID NAME [range]`,
//! `$enddefinitions`, the `$dumpvars`/`$dumpall`/`$dumpon`/`$dumpoff` blocks, `#TIME`, and
//! scalar (`1!`), vector (`b0101 !`), real (`r1.25 !`) and string (`sTEXT !`) changes; comments
//! and other commands are skipped. The file is read a line at a time and only the changes of
//! the one variable asked for are handed over, so a dump of a long run with many signals is
//! followed in constant memory. Every error names its line.

use asi_phy::waveform::{excerpt, read_line_bounded, CaptureError};
use core::fmt;
use std::collections::HashSet;
use std::io::BufRead;

/// The commands of IEEE 1364-2001 §18.2: one inside another's arguments means a missing `$end`
/// (an identifier code may begin with `$`, so only these count).
const KEYWORDS: [&str; 12] = [
    "$comment",
    "$date",
    "$enddefinitions",
    "$scope",
    "$timescale",
    "$upscope",
    "$var",
    "$version",
    "$dumpall",
    "$dumpoff",
    "$dumpon",
    "$dumpvars",
];

/// The most variables and the deepest scopes a header may declare: far more than any dump
/// holds, a bound on the memory a header can take, whatever the file.
pub const MAX_VARS: usize = 1 << 20;

/// The deepest nesting of `$scope`s read (see [`MAX_VARS`]).
pub const MAX_SCOPE_DEPTH: usize = 1 << 10;

/// The length of one VCD time unit: `$timescale 10 ns $end` (1, 10 or 100 of s, ms, us, ns,
/// ps or fs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Timescale {
    fs: u64,
}

impl Timescale {
    /// One nanosecond, the simulator's clock; assumed when a file has no `$timescale`.
    pub const NANOSECOND: Timescale = Timescale { fs: 1_000_000 };

    /// Reads `1 ns`, `10ps`, `100 us`, …; `None` for anything else.
    pub fn parse(text: &str) -> Option<Timescale> {
        let t = text.trim();
        let split = t.find(|c: char| !c.is_ascii_digit()).unwrap_or(t.len());
        let (num, unit) = t.split_at(split);
        let m: u64 = match num {
            "1" => 1,
            "10" => 10,
            "100" => 100,
            _ => return None,
        };
        let unit: u64 = match unit.trim() {
            "s" => 1_000_000_000_000_000,
            "ms" => 1_000_000_000_000,
            "us" => 1_000_000_000,
            "ns" => 1_000_000,
            "ps" => 1_000,
            "fs" => 1,
            _ => return None,
        };
        Some(Timescale { fs: m * unit })
    }

    /// One unit in femtoseconds.
    pub const fn femtoseconds(self) -> u64 {
        self.fs
    }

    /// `ticks` units in nanoseconds, rounded to the nearest; `None` past `u64`.
    pub fn to_nanos(self, ticks: u64) -> Option<u64> {
        let fs = ticks as u128 * self.fs as u128;
        u64::try_from((fs + 500_000) / 1_000_000).ok()
    }

    /// `ticks` units in nanoseconds, as a float (for sampling grids).
    pub fn to_nanos_f64(self, ticks: u64) -> f64 {
        ticks as f64 * self.fs as f64 / 1e6
    }
}

impl fmt::Display for Timescale {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let units = [
            (1_000_000_000_000_000, "s"),
            (1_000_000_000_000, "ms"),
            (1_000_000_000, "us"),
            (1_000_000, "ns"),
            (1_000, "ps"),
        ];
        let (div, unit) = units
            .into_iter()
            .find(|(d, _)| self.fs % d == 0)
            .unwrap_or((1, "fs"));
        write!(f, "{} {unit}", self.fs / div)
    }
}

/// A variable declared with `$var`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Var {
    /// The type as declared: `wire`, `reg`, `real`, `string`, …
    pub kind: String,
    /// Width in bits.
    pub width: u32,
    /// The identifier code its changes carry (`!`, `%`, …).
    pub id: String,
    /// The reference name (`line_voltage`), without a bit range.
    pub name: String,
    /// The scopes and the name joined by dots: `rig.bus.line_voltage`.
    pub path: String,
    /// The line of its `$var`.
    pub line: usize,
}

impl Var {
    /// `true` for a real-valued variable (`real`, `realtime`, `shortreal`).
    pub fn is_real(&self) -> bool {
        matches!(self.kind.as_str(), "real" | "realtime" | "shortreal")
    }

    /// `true` for a string variable (a GTKWave extension).
    pub fn is_string(&self) -> bool {
        self.kind == "string"
    }

    /// `true` if `wanted` names this variable: its full path, its reference name, or the
    /// trailing scopes of its path (`bus.line_voltage`).
    pub fn is_named(&self, wanted: &str) -> bool {
        self.path == wanted
            || self.name == wanted
            || self
                .path
                .strip_suffix(wanted)
                .is_some_and(|head| head.ends_with('.'))
    }
}

impl fmt::Display for Var {
    /// `rig.bus.line_voltage (real)`, `rig.bus.line (wire)`, `rig.image (wire, 8 bits)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.width == 1 || self.is_real() || self.is_string() {
            write!(f, "{} ({})", self.path, self.kind)
        } else {
            write!(f, "{} ({}, {} bits)", self.path, self.kind, self.width)
        }
    }
}

/// The value of one change record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value<'a> {
    /// A scalar: `0`, `1`, `x` or `z` (lower case).
    Bit(char),
    /// A vector's digits after the `b`, as written.
    Vector(&'a str),
    /// A real value.
    Real(f64),
    /// A string value (its text is not kept).
    Text,
}

/// One change record of the variable being followed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Change<'a> {
    /// The line of its value.
    pub line: usize,
    /// Its time in units of the file's [`Timescale`].
    pub time: u64,
    /// The value.
    pub value: Value<'a>,
    /// `true` inside a `$dumpvars`, `$dumpall`, `$dumpon` or `$dumpoff` block: a statement of
    /// the variable's current value rather than a change.
    pub dump: bool,
}

/// A VCD file whose header has been read; [`VcdReader::for_each_change`] reads the rest.
pub struct VcdReader<R> {
    tokens: Tokens<R>,
    timescale: Timescale,
    vars: Vec<Var>,
    ids: HashSet<String>,
}

impl<R: BufRead> VcdReader<R> {
    /// Reads the header of `input`, up to and including `$enddefinitions $end`.
    pub fn new(input: R) -> Result<VcdReader<R>, CaptureError> {
        let mut tokens = Tokens::new(input);
        let mut timescale = None;
        let mut vars = Vec::new();
        let mut scopes: Vec<String> = Vec::new();
        // The command being read: its keyword, its line and its arguments.
        let mut cmd: Option<(String, usize, Vec<String>)> = None;
        let mut seen = false;
        let err = |line, cause: String| Err(CaptureError { line, cause });
        loop {
            let Some((line, tok)) = tokens.next()? else {
                let line = tokens.line.max(1);
                return match cmd {
                    Some((kw, at, _)) => err(
                        line,
                        format!(
                            "the file ends inside `{}` of line {at}: it has no `$end`",
                            excerpt(&kw)
                        ),
                    ),
                    None if !seen => err(line, "the file is empty".into()),
                    None => err(
                        line,
                        "the header has no `$enddefinitions`: the file ends before any value"
                            .into(),
                    ),
                };
            };
            seen = true;
            let Some((kw, at, args)) = cmd.as_mut() else {
                if tok.starts_with('$') {
                    cmd = Some((tok.to_owned(), line, Vec::new()));
                    continue;
                }
                let cause = if tok.starts_with('#') {
                    format!("`{}`: a time before `$enddefinitions`", excerpt(tok))
                } else {
                    format!("`{}` is no VCD command (they start with `$`)", excerpt(tok))
                };
                return err(line, cause);
            };
            if tok != "$end" {
                // The free text of comments and of the header's dates is not kept.
                if !matches!(kw.as_str(), "$comment" | "$date" | "$version") {
                    if KEYWORDS.contains(&tok) {
                        return err(
                            line,
                            format!(
                                "`{tok}` inside `{}` of line {at}: it has no `$end`",
                                excerpt(kw)
                            ),
                        );
                    }
                    if args.len() < 16 {
                        args.push(tok.to_owned());
                    }
                }
                continue;
            }
            let at = *at;
            match kw.as_str() {
                "$timescale" => {
                    let text = args.join(" ");
                    timescale = Some(Timescale::parse(&text).ok_or_else(|| CaptureError {
                        line: at,
                        cause: format!(
                            "`$timescale {}`: expected 1, 10 or 100 of s, ms, us, ns, ps or fs",
                            excerpt(&text)
                        ),
                    })?);
                }
                "$scope" => match args.last() {
                    _ if scopes.len() >= MAX_SCOPE_DEPTH => {
                        return err(
                            at,
                            format!("`$scope` nested deeper than {MAX_SCOPE_DEPTH}: not a dump"),
                        )
                    }
                    Some(name) => scopes.push(name.clone()),
                    None => return err(at, "`$scope` without a name".into()),
                },
                "$upscope" => {
                    scopes.pop().ok_or_else(|| CaptureError {
                        line: at,
                        cause: "`$upscope` without an open `$scope`".into(),
                    })?;
                }
                "$var" => {
                    if vars.len() >= MAX_VARS {
                        return err(at, format!("more than {MAX_VARS} `$var`s: not a dump"));
                    }
                    let [kind, width, id, name, ..] = args.as_slice() else {
                        return err(at, "`$var` needs TYPE WIDTH ID NAME before `$end`".into());
                    };
                    let width: u32 = width.parse().map_err(|_| CaptureError {
                        line: at,
                        cause: format!("`$var` width `{}` is not a number", excerpt(width)),
                    })?;
                    let mut path = scopes.join(".");
                    if !path.is_empty() {
                        path.push('.');
                    }
                    path.push_str(name);
                    vars.push(Var {
                        kind: kind.clone(),
                        width,
                        id: id.clone(),
                        name: name.clone(),
                        path,
                        line: at,
                    });
                }
                "$enddefinitions" => break,
                _ => {}
            }
            cmd = None;
        }
        let ids = vars.iter().map(|v| v.id.clone()).collect();
        Ok(VcdReader {
            tokens,
            timescale: timescale.unwrap_or(Timescale::NANOSECOND),
            vars,
            ids,
        })
    }

    /// The file's time unit.
    pub fn timescale(&self) -> Timescale {
        self.timescale
    }

    /// The variables declared in the header, in order.
    pub fn vars(&self) -> &[Var] {
        &self.vars
    }

    /// Reads the value changes to the end of the file, calling `f` with every change of the
    /// variable with identifier code `id`. Changes of other variables are checked for syntax,
    /// time order and a declared identifier, and dropped. Stops at the first error, of the
    /// file or of `f`.
    pub fn for_each_change(
        self,
        id: &str,
        mut f: impl FnMut(Change<'_>) -> Result<(), CaptureError>,
    ) -> Result<(), CaptureError> {
        let VcdReader {
            mut tokens, ids, ..
        } = self;
        let err = |line, cause: String| Err(CaptureError { line, cause });
        let mut time = 0u64;
        let mut time_line = None;
        // An open dump block or a skipped command: its keyword and line.
        let mut block: Option<(String, usize)> = None;
        let mut skip: Option<(String, usize)> = None;
        // A vector, real or string value waiting for its identifier: its first letter, its
        // line, and its text (kept in one buffer).
        let mut pending: Option<(u8, usize)> = None;
        let mut text = String::new();
        while let Some((line, tok)) = tokens.next()? {
            if skip.is_some() {
                if tok == "$end" {
                    skip = None;
                }
                continue;
            }
            let first = tok.as_bytes()[0].to_ascii_lowercase();
            // After a vector, real or string value comes its identifier code, whatever its
            // first character (`$` and `#` are codes too).
            let (value, code, at) = if let Some((kind, at)) = pending.take() {
                let value = match kind {
                    b'b' => Value::Vector(&text),
                    b'r' => match text.parse::<f64>() {
                        Ok(v) => Value::Real(v),
                        Err(_) if tok != id => Value::Real(f64::NAN),
                        Err(_) => {
                            return err(at, format!("`r{}` is not a real number", excerpt(&text)))
                        }
                    },
                    _ => Value::Text,
                };
                (value, tok, at)
            } else {
                match first {
                    b'$' => {
                        match tok {
                            "$end" => {
                                if block.take().is_none() {
                                    return err(line, "`$end` without a command to end".into());
                                }
                            }
                            "$dumpvars" | "$dumpall" | "$dumpon" | "$dumpoff" => {
                                block = Some((tok.to_owned(), line));
                            }
                            _ => skip = Some((tok.to_owned(), line)),
                        }
                        continue;
                    }
                    b'#' => {
                        let Ok(t) = tok[1..].parse::<u64>() else {
                            return err(
                                line,
                                format!("`{}` is not a time (#, then digits)", excerpt(tok)),
                            );
                        };
                        if let (true, Some(prev)) = (t < time, time_line) {
                            return err(
                                line,
                                format!("time #{t} goes back: #{time} was at line {prev}"),
                            );
                        }
                        time = t;
                        time_line = Some(line);
                        continue;
                    }
                    b'0' | b'1' | b'x' | b'z' => {
                        if tok.len() == 1 {
                            return err(line, format!("the value `{tok}` has no identifier code"));
                        }
                        (Value::Bit(first as char), &tok[1..], line)
                    }
                    b'b' | b'r' | b's' => {
                        text.clear();
                        text.push_str(&tok[1..]);
                        pending = Some((first, line));
                        continue;
                    }
                    _ => {
                        return err(
                            line,
                            format!(
                                "`{}` is no value change, time (#…) or command ($…)",
                                excerpt(tok)
                            ),
                        )
                    }
                }
            };
            if code == id {
                f(Change {
                    line: at,
                    time,
                    value,
                    dump: block.is_some(),
                })?;
            } else if !ids.contains(code) {
                return err(
                    line,
                    format!(
                        "unknown identifier code `{}`: no `$var` declares it",
                        excerpt(code)
                    ),
                );
            }
        }
        let end = tokens.line.max(1);
        if let Some((kind, at)) = pending {
            return err(
                at,
                format!(
                    "the file ends after the value `{}{}`, before its identifier code",
                    kind as char,
                    excerpt(&text)
                ),
            );
        }
        if let Some((kw, at)) = block.or(skip) {
            return err(
                end,
                format!(
                    "the file ends inside `{}` of line {at}: it has no `$end`",
                    excerpt(&kw)
                ),
            );
        }
        Ok(())
    }
}

/// The whitespace-separated tokens of a text, a line at a time, with their line numbers.
struct Tokens<R> {
    input: R,
    buf: String,
    pos: usize,
    /// The number of the line in `buf` (1-based; 0 before the first).
    line: usize,
}

impl<R: BufRead> Tokens<R> {
    fn new(input: R) -> Tokens<R> {
        Tokens {
            input,
            buf: String::new(),
            pos: 0,
            line: 0,
        }
    }

    /// The next token and its line; `None` at the end of the input.
    fn next(&mut self) -> Result<Option<(usize, &str)>, CaptureError> {
        loop {
            let bytes = self.buf.as_bytes();
            if let Some(start) = bytes[self.pos..]
                .iter()
                .position(|b| !b.is_ascii_whitespace())
            {
                let start = self.pos + start;
                let end = bytes[start..]
                    .iter()
                    .position(|b| b.is_ascii_whitespace())
                    .map_or(bytes.len(), |n| start + n);
                self.pos = end;
                return Ok(Some((self.line, &self.buf[start..end])));
            }
            let mut bytes = core::mem::take(&mut self.buf).into_bytes();
            bytes.clear();
            let line = self.line + 1;
            // A line past the bound (a binary file, `/dev/zero`) is refused, not held.
            let n = read_line_bounded(&mut self.input, &mut bytes, line)?;
            if n == 0 {
                return Ok(None);
            }
            self.line = line;
            self.pos = 0;
            self.buf = String::from_utf8(bytes).map_err(|_| CaptureError {
                line,
                cause: "not text (invalid UTF-8)".into(),
            })?;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The changes of `id` in `text` as (line, time, value, dump).
    fn changes(text: &str, id: &str) -> Result<Vec<(usize, u64, String, bool)>, CaptureError> {
        let r = VcdReader::new(text.as_bytes())?;
        let mut got = Vec::new();
        r.for_each_change(id, |c| {
            let v = match c.value {
                Value::Bit(b) => b.to_string(),
                Value::Vector(v) => format!("b{v}"),
                Value::Real(v) => format!("r{v}"),
                Value::Text => "s".into(),
            };
            got.push((c.line, c.time, v, c.dump));
            Ok(())
        })?;
        Ok(got)
    }

    const HEADER: &str = "$date today $end\n\
        $timescale 10 ns $end\n\
        $comment one signal of each kind $end\n\
        $scope module rig $end\n\
        $scope module bus $end\n\
        $var wire 1 ! line $end\n\
        $var real 64 \" line_voltage $end\n\
        $upscope $end\n\
        $var wire 8 # image [7:0] $end\n\
        $var string 1 $ note $end\n\
        $upscope $end\n\
        $enddefinitions $end\n";

    #[test]
    fn reads_the_header() {
        let r = VcdReader::new(HEADER.as_bytes()).expect("header");
        assert_eq!(r.timescale(), Timescale::parse("10ns").expect("ts"));
        let names: Vec<String> = r.vars().iter().map(|v| v.to_string()).collect();
        assert_eq!(
            names,
            [
                "rig.bus.line (wire)",
                "rig.bus.line_voltage (real)",
                "rig.image (wire, 8 bits)",
                "rig.note (string)"
            ]
        );
        let v = &r.vars()[1];
        assert_eq!(
            (v.id.as_str(), v.name.as_str(), v.line),
            ("\"", "line_voltage", 7)
        );
        assert!(v.is_real() && v.is_named("line_voltage") && v.is_named("bus.line_voltage"));
        assert!(v.is_named("rig.bus.line_voltage") && !v.is_named("voltage"));
    }

    #[test]
    fn hands_over_the_changes_of_one_variable() {
        let text = format!(
            "{HEADER}$dumpvars 1! r0 \" b00000000 # sidle $ $end\n\
             #5 0! r-1.5 \"\n\
             b1010 # sready $\n\
             $comment a note #3 is no time $end\n\
             #7\n1! 1!\n"
        );
        assert_eq!(
            changes(&text, "!").expect("ok"),
            [
                (13, 0, "1".into(), true),
                (14, 5, "0".into(), false),
                (18, 7, "1".into(), false),
                (18, 7, "1".into(), false)
            ]
        );
        assert_eq!(
            changes(&text, "\"").expect("ok"),
            [(13, 0, "r0".into(), true), (14, 5, "r-1.5".into(), false)]
        );
        assert_eq!(
            changes(&text, "#").expect("ok")[1],
            (15, 5, "b1010".into(), false)
        );
    }

    #[test]
    fn timescales() {
        for (text, fs) in [
            ("1 s", 1_000_000_000_000_000),
            ("100ms", 100_000_000_000_000),
            ("10 us", 10_000_000_000),
            ("1ns", 1_000_000),
            ("100 ps", 100_000),
            ("1 fs", 1),
        ] {
            let ts = Timescale::parse(text).expect(text);
            assert_eq!(ts.femtoseconds(), fs, "{text}");
            assert_eq!(Timescale::parse(&ts.to_string()), Some(ts), "{text}");
        }
        for bad in ["2 ns", "1 min", "ns", "10", "1000 ps"] {
            assert_eq!(Timescale::parse(bad), None, "{bad}");
        }
        let ps = Timescale::parse("100 ps").expect("ts");
        assert_eq!(ps.to_nanos(15), Some(2), "1.5 ns rounds up");
        assert_eq!(Timescale::parse("1 s").expect("s").to_nanos(u64::MAX), None);
    }

    #[test]
    fn every_error_names_its_line() {
        let cases: [(&str, &str, usize, &str); 10] = [
            (" \n\n", "!", 2, "the file is empty"),
            (
                "time,voltage\n0,1\n",
                "!",
                1,
                "`time,voltage` is no VCD command",
            ),
            (
                "$timescale 1 ns $end\n$var wire 1 ! a $end\n#0 1!\n",
                "!",
                3,
                "`#0`: a time before `$enddefinitions`",
            ),
            (
                "$timescale 1 ns $end\n$var wire 1 ! a $end\n",
                "!",
                2,
                "no `$enddefinitions`",
            ),
            (
                "$timescale 3 ns $end\n$enddefinitions $end\n",
                "!",
                1,
                "`$timescale 3 ns`",
            ),
            (
                "$var wire 1 ! a\n$enddefinitions $end\n",
                "!",
                2,
                "`$enddefinitions` inside `$var` of line 1: it has no `$end`",
            ),
            (
                "$var wire 1 ! a $end $enddefinitions $end\n#10 1!\n#20 0!\n#15 1!\n",
                "!",
                4,
                "time #15 goes back: #20 was at line 3",
            ),
            (
                "$var wire 1 ! a $end $enddefinitions $end\n#10 1!\n#20 0?\n",
                "!",
                3,
                "unknown identifier code `?`",
            ),
            (
                "$var real 64 ! a $end $enddefinitions $end\n#10 r1.5 !\n#20 r2.5\n",
                "!",
                3,
                "before its identifier code",
            ),
            (
                "$var wire 1 ! a $end $enddefinitions $end\n$dumpvars 1!\n#20 0!\n",
                "!",
                3,
                "inside `$dumpvars` of line 2",
            ),
        ];
        for (text, id, line, cause) in cases {
            let e = changes(text, id).expect_err(text);
            assert_eq!(e.line, line, "{text}: {e}");
            assert!(e.cause.contains(cause), "{text}: {e}");
        }
        let bad = b"$var wire 1 ! a $end\n$enddefinitions $end\n#1 \xff\xfe!\n";
        let e = VcdReader::new(&bad[..])
            .and_then(|r| r.for_each_change("!", |_| Ok(())))
            .expect_err("not UTF-8");
        assert_eq!((e.line, e.cause.as_str()), (3, "not text (invalid UTF-8)"));
    }

    #[test]
    fn a_header_past_its_bounds_is_refused() {
        let deep = "$scope module a $end\n".repeat(MAX_SCOPE_DEPTH + 1);
        let e = VcdReader::new(deep.as_bytes()).err().expect("too deep");
        assert_eq!(e.line, MAX_SCOPE_DEPTH + 1);
        assert!(e.cause.contains("nested deeper than 1024"), "{e}");
        let many = "$var wire 1 ! a $end\n".repeat(MAX_VARS + 1);
        let e = VcdReader::new(many.as_bytes()).err().expect("too many");
        assert_eq!(e.line, MAX_VARS + 1);
        assert!(e.cause.contains("more than 1048576 `$var`s"), "{e}");
    }

    #[test]
    fn a_line_past_the_bound_is_refused_and_a_long_token_quoted_short() {
        // `/dev/zero`: one endless line, read only up to the bound.
        let zeros = std::io::BufReader::new(std::io::repeat(0));
        let e = VcdReader::new(zeros).err().expect("endless line");
        assert_eq!(e.line, 1);
        assert!(e.cause.contains("longer than 1 MiB"), "{e}");
        // A huge value after the header: named, not echoed.
        let text = format!(
            "$var real 64 ! a $end $enddefinitions $end\n#1 r{} !\n",
            "7x".repeat(200_000)
        );
        let e = changes(&text, "!").expect_err("not a number");
        assert_eq!(e.line, 2);
        assert!(e.cause.len() < 200, "{} bytes", e.cause.len());
        assert!(e.cause.contains("7x7x…` is not a real number"), "{e}");
    }
}
