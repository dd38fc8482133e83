//! A Sample Change Dump writer (IEEE 1364 §18) for GTKWave and Surfer.
//!
//! Variables are declared first (scope, name, kind); then changes arrive in any order within a
//! window and [`VcdWriter::flush_until`] writes those up to a time, sorted by time (changes at
//! one time keep the order they were given in). A change that repeats a variable's value is
//! dropped, except for variables declared with `every_record` (the AS-i pulse wire: every pulse
//! is a record, even two pulses of one polarity). The time unit is 1 ns, the simulator's clock.

use std::io::{self, Write};

/// What a variable holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VarKind {
    /// A wire of `width` bits (1 = scalar).
    Wire(u32),
    /// A real number.
    Real,
    /// A string (GTKWave and Surfer show it as text); spaces become underscores.
    Text,
}

/// A value of a variable.
#[derive(Clone, Debug, PartialEq)]
pub enum Sample {
    /// A scalar or vector value (low `width` bits).
    Bits(u64),
    /// All bits unknown (`x`): no value, e.g. no response.
    Unknown,
    /// A real number.
    Real(f64),
    /// A string.
    Text(String),
}

impl From<bool> for Sample {
    fn from(b: bool) -> Sample {
        Sample::Bits(b as u64)
    }
}

/// A declared variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct VarId(usize);

#[derive(Clone, Debug)]
struct Var {
    scope: Vec<&'static str>,
    name: &'static str,
    kind: VarKind,
    code: String,
    every_record: bool,
    last: Option<Sample>,
}

/// Writes a VCD file.
pub struct VcdWriter<W: Write> {
    out: W,
    vars: Vec<Var>,
    pending: Vec<(u64, VarId, Sample)>,
    header_done: bool,
    time: Option<u64>,
    flushed_to: u64,
}

impl<W: Write> VcdWriter<W> {
    /// A writer to `out`; nothing is written until the first flush.
    pub fn new(out: W) -> VcdWriter<W> {
        VcdWriter {
            out,
            vars: Vec::new(),
            pending: Vec::new(),
            header_done: false,
            time: None,
            flushed_to: 0,
        }
    }

    /// Declares a variable in `scope` (outermost first), e.g. `["rig", "bus"]`.
    pub fn var(&mut self, scope: &[&'static str], name: &'static str, kind: VarKind) -> VarId {
        self.declare(scope, name, kind, false)
    }

    /// Declares a variable whose every record is written, even one that repeats the value.
    pub fn var_every_record(
        &mut self,
        scope: &[&'static str],
        name: &'static str,
        kind: VarKind,
    ) -> VarId {
        self.declare(scope, name, kind, true)
    }

    fn declare(
        &mut self,
        scope: &[&'static str],
        name: &'static str,
        kind: VarKind,
        every_record: bool,
    ) -> VarId {
        let id = VarId(self.vars.len());
        self.vars.push(Var {
            scope: scope.to_vec(),
            name,
            kind,
            code: id_code(id.0),
            every_record,
            last: None,
        });
        id
    }

    /// Records that `var` takes `value` at `t_ns` (written at the next flush that reaches it).
    /// A change earlier than the last flush is written at the flush time.
    pub fn change(&mut self, t_ns: u64, var: VarId, value: Sample) {
        self.pending.push((t_ns.max(self.flushed_to), var, value));
    }

    /// A writer that goes on from where this one stands into `out` (a copy of a run given
    /// outputs of its own): the same variables, the changes not yet written, and the values
    /// written so far, which its output states after the header (a `$dumpvars` at the last
    /// time written), so that it is a whole VCD of what follows. Every record it writes after
    /// them is one this writer would write.
    pub fn continue_into<V: Write>(&self, out: V) -> VcdWriter<V> {
        VcdWriter {
            out,
            vars: self.vars.clone(),
            pending: self.pending.clone(),
            header_done: false,
            time: self.time,
            flushed_to: self.flushed_to,
        }
    }

    /// Writes every recorded change up to and including `t_ns`, in time order.
    pub fn flush_until(&mut self, t_ns: u64) -> io::Result<()> {
        self.header()?;
        // Stable: changes at one time keep their order.
        self.pending.sort_by_key(|(t, _, _)| *t);
        let n = self.pending.partition_point(|(t, _, _)| *t <= t_ns);
        let due: Vec<_> = self.pending.drain(..n).collect();
        for (t, var, value) in due {
            self.write_change(t, var, value)?;
        }
        self.flushed_to = self.flushed_to.max(t_ns);
        Ok(())
    }

    /// Writes everything and the closing time stamp `end_ns`; returns the output.
    pub fn finish(mut self, end_ns: u64) -> io::Result<W> {
        self.flush_until(u64::MAX)?;
        if self.time.is_none_or(|t| t < end_ns) {
            writeln!(self.out, "#{end_ns}")?;
        }
        self.out.flush()?;
        Ok(self.out)
    }

    fn header(&mut self) -> io::Result<()> {
        if self.header_done {
            return Ok(());
        }
        self.header_done = true;
        let o = &mut self.out;
        writeln!(o, "$comment asi-lift: the AS-i lab lift, simulated $end")?;
        writeln!(o, "$timescale 1 ns $end")?;
        let mut open: Vec<&'static str> = Vec::new();
        let mut order: Vec<usize> = (0..self.vars.len()).collect();
        order.sort_by(|a, b| self.vars[*a].scope.cmp(&self.vars[*b].scope));
        for i in order {
            let v = &self.vars[i];
            let common = open
                .iter()
                .zip(&v.scope)
                .take_while(|(a, b)| a == b)
                .count();
            for _ in common..open.len() {
                writeln!(o, "$upscope $end")?;
            }
            open.truncate(common);
            for s in &v.scope[common..] {
                writeln!(o, "$scope module {s} $end")?;
                open.push(s);
            }
            let (ty, width) = match v.kind {
                VarKind::Wire(w) => ("wire", w),
                VarKind::Real => ("real", 64),
                VarKind::Text => ("string", 1),
            };
            match v.kind {
                VarKind::Wire(w) if w > 1 => writeln!(
                    o,
                    "$var {ty} {width} {} {} [{}:0] $end",
                    v.code,
                    v.name,
                    w - 1
                )?,
                _ => writeln!(o, "$var {ty} {width} {} {} $end", v.code, v.name)?,
            }
        }
        for _ in &open {
            writeln!(o, "$upscope $end")?;
        }
        writeln!(o, "$enddefinitions $end")?;
        // A writer that goes on from another ([`VcdWriter::continue_into`]): the values
        // written so far.
        if let Some(t) = self.time {
            writeln!(self.out, "#{t}")?;
            writeln!(self.out, "$dumpvars")?;
            for i in 0..self.vars.len() {
                if let Some(value) = self.vars[i].last.clone() {
                    self.write_value(VarId(i), &value)?;
                }
            }
            writeln!(self.out, "$end")?;
        }
        Ok(())
    }

    fn write_change(&mut self, t: u64, var: VarId, value: Sample) -> io::Result<()> {
        let v = &self.vars[var.0];
        if !v.every_record && v.last.as_ref() == Some(&value) {
            return Ok(());
        }
        if self.time != Some(t) {
            writeln!(self.out, "#{t}")?;
            self.time = Some(t);
        }
        self.write_value(var, &value)?;
        self.vars[var.0].last = Some(value);
        Ok(())
    }

    /// Writes the record of `var` taking `value`.
    fn write_value(&mut self, var: VarId, value: &Sample) -> io::Result<()> {
        let v = &self.vars[var.0];
        let o = &mut self.out;
        match (value, v.kind) {
            (Sample::Bits(b), VarKind::Wire(1)) => writeln!(o, "{}{}", b & 1, v.code),
            (Sample::Unknown, VarKind::Wire(1)) => writeln!(o, "x{}", v.code),
            (Sample::Bits(b), VarKind::Wire(w)) => {
                let digits: String = (0..w)
                    .rev()
                    .map(|i| if b >> i & 1 == 1 { '1' } else { '0' })
                    .collect();
                writeln!(o, "b{digits} {}", v.code)
            }
            (Sample::Unknown, VarKind::Wire(_)) => writeln!(o, "bx {}", v.code),
            (Sample::Real(x), _) => writeln!(o, "r{x} {}", v.code),
            (Sample::Text(s), _) => {
                let s: String = s
                    .chars()
                    .map(|c| if c.is_whitespace() { '_' } else { c })
                    .collect();
                writeln!(o, "s{s} {}", v.code)
            }
            (Sample::Unknown, _) => writeln!(o, "s? {}", v.code),
            (Sample::Bits(b), _) => writeln!(o, "r{b} {}", v.code),
        }
    }
}

/// The short identifier code of variable `i`: printable ASCII `!`..`~`, base 94.
fn id_code(mut i: usize) -> String {
    let mut s = String::new();
    loop {
        s.push((b'!' + (i % 94) as u8) as char);
        i /= 94;
        if i == 0 {
            return s;
        }
        i -= 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn id_codes_are_distinct_and_printable() {
        let codes: Vec<String> = (0..10_000).map(id_code).collect();
        let set: std::collections::HashSet<&String> = codes.iter().collect();
        assert_eq!(set.len(), codes.len());
        assert_eq!(codes[0], "!");
        assert_eq!(codes[93], "~");
        assert_eq!(codes[94], "!!");
        assert!(codes
            .iter()
            .all(|c| c.bytes().all(|b| (b'!'..=b'~').contains(&b))));
    }

    #[test]
    fn writes_a_header_and_changes_in_time_order() {
        let mut w = VcdWriter::new(Vec::new());
        let k1 = w.var(&["rig", "plant"], "k1", VarKind::Wire(1));
        let pos = w.var(&["rig", "plant"], "cabin_position_mm", VarKind::Real);
        let req = w.var(&["rig", "bus"], "request", VarKind::Wire(14));
        let line = w.var_every_record(&["rig", "bus"], "manchester", VarKind::Wire(1));
        let st = w.var(&["rig"], "state", VarKind::Text);
        w.change(0, st, Sample::Text("init down".into()));
        w.change(20, k1, true.into());
        w.change(5, req, Sample::Bits(0b00001010101001));
        w.change(5, line, false.into());
        w.change(8, line, false.into());
        w.change(10, pos, Sample::Real(650.5));
        w.change(30, k1, true.into());
        w.flush_until(25).expect("write");
        w.change(40, req, Sample::Unknown);
        let text = String::from_utf8(w.finish(50).expect("write")).expect("utf-8");
        let want = "\
$comment asi-lift: the AS-i lab lift, simulated $end
$timescale 1 ns $end
$scope module rig $end
$var string 1 % state $end
$scope module bus $end
$var wire 14 # request [13:0] $end
$var wire 1 $ manchester $end
$upscope $end
$scope module plant $end
$var wire 1 ! k1 $end
$var real 64 \" cabin_position_mm $end
$upscope $end
$upscope $end
$enddefinitions $end
#0
sinit_down %
#5
b00001010101001 #
0$
#8
0$
#10
r650.5 \"
#20
1!
#40
bx #
#50
";
        assert_eq!(text, want);
    }

    /// A writer continued at any point writes its header, the values written so far at the
    /// last time written, and then exactly what the original writes from there.
    #[test]
    fn a_continued_writer_states_the_values_and_goes_on_as_the_original() {
        let run = |split: Option<usize>| -> (String, Option<(usize, String)>) {
            let mut w = VcdWriter::new(Vec::new());
            let k1 = w.var(&["rig"], "k1", VarKind::Wire(1));
            let pos = w.var(&["rig"], "pos", VarKind::Real);
            let line = w.var_every_record(&["rig"], "line", VarKind::Wire(1));
            let st = w.var(&["rig"], "state", VarKind::Text);
            let mut copy = None;
            for i in 0..12u64 {
                if split == Some(i as usize) {
                    let written = w.out.len();
                    copy = Some((written, w.continue_into(Vec::new())));
                }
                let t = i * 10;
                w.change(t, line, (i % 3 == 0).into());
                w.change(t + 5, pos, Sample::Real((i / 4) as f64));
                w.change(t + 2, k1, (i >= 6).into());
                if i == 7 {
                    w.change(t, st, Sample::Text("run up".into()));
                }
                if let Some((_, c)) = copy.as_mut() {
                    c.change(t, line, (i % 3 == 0).into());
                    c.change(t + 5, pos, Sample::Real((i / 4) as f64));
                    c.change(t + 2, k1, (i >= 6).into());
                    if i == 7 {
                        c.change(t, st, Sample::Text("run up".into()));
                    }
                }
                if i % 2 == 1 {
                    w.flush_until(t).expect("write");
                    if let Some((_, c)) = copy.as_mut() {
                        c.flush_until(t).expect("write");
                    }
                }
            }
            let copied = copy.map(|(n, c)| {
                (
                    n,
                    String::from_utf8(c.finish(130).expect("write")).expect("utf-8"),
                )
            });
            (
                String::from_utf8(w.finish(130).expect("write")).expect("utf-8"),
                copied,
            )
        };
        let (whole, _) = run(None);
        for split in [1, 4, 8, 11] {
            let (original, copy) = run(Some(split));
            assert_eq!(original, whole);
            let (written, copy) = copy.expect("a copy");
            if written == 0 {
                // Nothing written yet: the copy is the whole file.
                assert_eq!(copy, whole, "split at {split}");
                continue;
            }
            let (header, _) = whole
                .split_once("$enddefinitions $end\n")
                .expect("a header");
            let rest = copy
                .strip_prefix(header)
                .and_then(|r| r.strip_prefix("$enddefinitions $end\n"))
                .expect("the same header");
            let (dump, body) = rest.split_once("$end\n").expect("a $dumpvars block");
            assert_eq!(body, &whole[written..], "split at {split}");
            let last_time = whole[..written]
                .lines()
                .rev()
                .find(|l| l.starts_with('#'))
                .expect("a time written");
            let mut lines = dump.lines();
            assert_eq!(lines.next(), Some(last_time), "split at {split}");
            assert_eq!(lines.next(), Some("$dumpvars"), "split at {split}");
            // Each value stated is the variable's last record before the split.
            for record in lines {
                let code = record.rsplit_once(' ').map_or(&record[1..], |(_, c)| c);
                let last = whole[..written]
                    .lines()
                    .rev()
                    .filter(|l| !l.starts_with('#') && !l.starts_with('$'))
                    .find(|l| l.rsplit_once(' ').map_or(&l[1..], |(_, c)| c) == code);
                assert_eq!(last, Some(record), "split at {split}");
            }
        }
        // The worked case: split after the first flush, which wrote up to time 10 (line 1 at 0,
        // k1 0 at 2, pos 0 at 5, line 0 at 10): the values in the order declared.
        let (_, copy) = run(Some(2));
        let (_, copy) = copy.expect("a copy");
        let dump = copy.split_once("$enddefinitions $end\n").expect("header").1;
        assert!(
            dump.starts_with("#10\n$dumpvars\n0!\nr0 \"\n0#\n$end\n"),
            "{dump}"
        );
    }
}
