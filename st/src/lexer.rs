//! Structured Text's tokens (IEC 61131-3, 3rd edition, §6.1–6.3 and §7.3): keywords and
//! identifiers (case-insensitive), numbers (decimal, `2#`, `8#`, `16#`, with `_`), reals,
//! durations (`T#1s500ms`, `TIME#…`), strings, direct variables (`%IX1.2`, `%QW4`),
//! operators, and comments (`(* … *)`, `/* … */`, `// …`).

use crate::source::{Diagnostic, Span};

/// A keyword.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(missing_docs)]
pub enum Kw {
    Program,
    EndProgram,
    Function,
    EndFunction,
    FunctionBlock,
    EndFunctionBlock,
    Var,
    VarInput,
    VarOutput,
    VarInOut,
    VarTemp,
    VarGlobal,
    VarExternal,
    EndVar,
    Constant,
    Retain,
    NonRetain,
    At,
    Type,
    EndType,
    Struct,
    EndStruct,
    Array,
    Of,
    If,
    Then,
    Elsif,
    Else,
    EndIf,
    Case,
    EndCase,
    For,
    To,
    By,
    Do,
    EndFor,
    While,
    EndWhile,
    Repeat,
    Until,
    EndRepeat,
    Exit,
    Continue,
    Return,
    And,
    Or,
    Xor,
    Not,
    Mod,
    True,
    False,
}

/// Every keyword and how it is spelt.
const KEYWORDS: &[(&str, Kw)] = &[
    ("PROGRAM", Kw::Program),
    ("END_PROGRAM", Kw::EndProgram),
    ("FUNCTION", Kw::Function),
    ("END_FUNCTION", Kw::EndFunction),
    ("FUNCTION_BLOCK", Kw::FunctionBlock),
    ("END_FUNCTION_BLOCK", Kw::EndFunctionBlock),
    ("VAR", Kw::Var),
    ("VAR_INPUT", Kw::VarInput),
    ("VAR_OUTPUT", Kw::VarOutput),
    ("VAR_IN_OUT", Kw::VarInOut),
    ("VAR_TEMP", Kw::VarTemp),
    ("VAR_GLOBAL", Kw::VarGlobal),
    ("VAR_EXTERNAL", Kw::VarExternal),
    ("END_VAR", Kw::EndVar),
    ("CONSTANT", Kw::Constant),
    ("RETAIN", Kw::Retain),
    ("NON_RETAIN", Kw::NonRetain),
    ("AT", Kw::At),
    ("TYPE", Kw::Type),
    ("END_TYPE", Kw::EndType),
    ("STRUCT", Kw::Struct),
    ("END_STRUCT", Kw::EndStruct),
    ("ARRAY", Kw::Array),
    ("OF", Kw::Of),
    ("IF", Kw::If),
    ("THEN", Kw::Then),
    ("ELSIF", Kw::Elsif),
    ("ELSE", Kw::Else),
    ("END_IF", Kw::EndIf),
    ("CASE", Kw::Case),
    ("END_CASE", Kw::EndCase),
    ("FOR", Kw::For),
    ("TO", Kw::To),
    ("BY", Kw::By),
    ("DO", Kw::Do),
    ("END_FOR", Kw::EndFor),
    ("WHILE", Kw::While),
    ("END_WHILE", Kw::EndWhile),
    ("REPEAT", Kw::Repeat),
    ("UNTIL", Kw::Until),
    ("END_REPEAT", Kw::EndRepeat),
    ("EXIT", Kw::Exit),
    ("CONTINUE", Kw::Continue),
    ("RETURN", Kw::Return),
    ("AND", Kw::And),
    ("OR", Kw::Or),
    ("XOR", Kw::Xor),
    ("NOT", Kw::Not),
    ("MOD", Kw::Mod),
    ("TRUE", Kw::True),
    ("FALSE", Kw::False),
];

impl Kw {
    /// The keyword spelt `word` (any case).
    pub fn of(word: &str) -> Option<Kw> {
        KEYWORDS
            .iter()
            .find(|(s, _)| s.eq_ignore_ascii_case(word))
            .map(|&(_, k)| k)
    }

    /// How the standard spells it.
    pub fn text(self) -> &'static str {
        KEYWORDS
            .iter()
            .find(|&&(_, k)| k == self)
            .map_or("?", |&(s, _)| s)
    }
}

/// An operator or punctuation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(missing_docs)]
pub enum Sym {
    Assign,
    Arrow,
    Eq,
    Ne,
    Lt,
    Le,
    Gt,
    Ge,
    Plus,
    Minus,
    Star,
    Slash,
    Power,
    Amp,
    LParen,
    RParen,
    LBracket,
    RBracket,
    Comma,
    Semi,
    Colon,
    Dot,
    DotDot,
    Hash,
}

impl Sym {
    /// How it is written.
    pub fn text(self) -> &'static str {
        match self {
            Sym::Assign => ":=",
            Sym::Arrow => "=>",
            Sym::Eq => "=",
            Sym::Ne => "<>",
            Sym::Lt => "<",
            Sym::Le => "<=",
            Sym::Gt => ">",
            Sym::Ge => ">=",
            Sym::Plus => "+",
            Sym::Minus => "-",
            Sym::Star => "*",
            Sym::Slash => "/",
            Sym::Power => "**",
            Sym::Amp => "&",
            Sym::LParen => "(",
            Sym::RParen => ")",
            Sym::LBracket => "[",
            Sym::RBracket => "]",
            Sym::Comma => ",",
            Sym::Semi => ";",
            Sym::Colon => ":",
            Sym::Dot => ".",
            Sym::DotDot => "..",
            Sym::Hash => "#",
        }
    }
}

/// The memory area of a direct variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Area {
    /// `%I`: inputs.
    Input,
    /// `%Q`: outputs.
    Output,
    /// `%M`: memory.
    Memory,
}

/// The size of a direct variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Size {
    /// `X` (or none): a bit.
    Bit,
    /// `B`: a byte.
    Byte,
    /// `W`: a word.
    Word,
    /// `D`: a double word.
    Double,
    /// `L`: a long word.
    Long,
}

impl Size {
    /// The size its letter `c` names (`X`, `B`, `W`, `D`, `L`, any case).
    fn of(c: u8) -> Option<Size> {
        Some(match c.to_ascii_uppercase() {
            b'X' => Size::Bit,
            b'B' => Size::Byte,
            b'W' => Size::Word,
            b'D' => Size::Double,
            b'L' => Size::Long,
            _ => return None,
        })
    }
}

/// A direct variable: `%` area, size and the address's numbers (`%IX2.3`: input bit 3 of
/// word 2).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Direct {
    /// The area.
    pub area: Area,
    /// The size.
    pub size: Size,
    /// The numbers, outermost first.
    pub path: Vec<u32>,
}

impl std::fmt::Display for Direct {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let area = match self.area {
            Area::Input => 'I',
            Area::Output => 'Q',
            Area::Memory => 'M',
        };
        let size = match self.size {
            Size::Bit => 'X',
            Size::Byte => 'B',
            Size::Word => 'W',
            Size::Double => 'D',
            Size::Long => 'L',
        };
        let path: Vec<String> = self.path.iter().map(u32::to_string).collect();
        write!(f, "%{area}{size}{}", path.join("."))
    }
}

/// A token.
#[derive(Clone, Debug, PartialEq)]
pub enum Tok {
    /// An identifier, as written.
    Ident(String),
    /// A keyword.
    Kw(Kw),
    /// An integer literal's magnitude (decimal or based).
    Int(u64),
    /// A real literal.
    Real(f64),
    /// A duration literal (`T#…`, `TIME#…`), nanoseconds.
    Time(i64),
    /// A string literal's characters.
    Str(String),
    /// A direct variable.
    Direct(Direct),
    /// A partial access after a `.`: `%X3` (bit 3), `%B1`, `%W0`, `%D0`.
    Partial(Size, u32),
    /// An operator or punctuation.
    Sym(Sym),
    /// Something that is no token (reported already).
    Bad,
    /// The end of the source.
    Eof,
}

impl Tok {
    /// The token as a message names it.
    pub fn describe(&self) -> String {
        match self {
            Tok::Ident(s) => format!("`{s}`"),
            Tok::Kw(k) => format!("`{}`", k.text()),
            Tok::Int(n) => format!("the number {n}"),
            Tok::Real(r) => format!("the number {r}"),
            Tok::Time(_) => "a duration".into(),
            Tok::Str(_) => "a string".into(),
            Tok::Direct(d) => format!("`{d}`"),
            Tok::Partial(_, n) => format!("the partial access `%…{n}`"),
            Tok::Sym(s) => format!("`{}`", s.text()),
            Tok::Bad => "an unreadable token".into(),
            Tok::Eof => "the end of the file".into(),
        }
    }
}

/// A token and its place.
#[derive(Clone, Debug, PartialEq)]
pub struct Token {
    /// What.
    pub tok: Tok,
    /// Where.
    pub span: Span,
}

/// The tokens of `text`, ending with [`Tok::Eof`], and what could not be read (each such
/// place is a [`Tok::Bad`] token, so the parser goes on past it).
pub fn lex(text: &str) -> (Vec<Token>, Vec<Diagnostic>) {
    let mut l = Lexer {
        s: text.as_bytes(),
        text,
        i: 0,
        out: Vec::new(),
        errors: Vec::new(),
    };
    l.run();
    (l.out, l.errors)
}

struct Lexer<'a> {
    s: &'a [u8],
    text: &'a str,
    i: usize,
    out: Vec<Token>,
    errors: Vec<Diagnostic>,
}

impl Lexer<'_> {
    fn peek(&self, k: usize) -> u8 {
        self.s.get(self.i + k).copied().unwrap_or(0)
    }

    fn push(&mut self, tok: Tok, start: usize) {
        self.out.push(Token {
            tok,
            span: Span::new(start, self.i),
        });
    }

    fn error(&mut self, start: usize, message: impl Into<String>) {
        self.errors
            .push(Diagnostic::error(Span::new(start, self.i), message));
        self.push(Tok::Bad, start);
    }

    fn run(&mut self) {
        while self.i < self.s.len() {
            let c = self.s[self.i];
            let start = self.i;
            match c {
                b' ' | b'\t' | b'\r' | b'\n' => self.i += 1,
                b'(' if self.peek(1) == b'*' => self.comment(start, b"*)"),
                b'/' if self.peek(1) == b'*' => self.comment(start, b"*/"),
                b'/' if self.peek(1) == b'/' => {
                    while self.i < self.s.len() && self.s[self.i] != b'\n' {
                        self.i += 1;
                    }
                }
                b'a'..=b'z' | b'A'..=b'Z' | b'_' => self.word(start),
                b'0'..=b'9' => self.number(start),
                b'%' => self.direct(start),
                b'\'' | b'"' => self.string(start, c),
                _ => self.symbol(start),
            }
        }
        let end = self.s.len();
        self.out.push(Token {
            tok: Tok::Eof,
            span: Span::new(end, end),
        });
    }

    fn comment(&mut self, start: usize, close: &[u8]) {
        self.i += 2;
        while self.i < self.s.len() {
            if self.s[self.i..].starts_with(close) {
                self.i += 2;
                return;
            }
            self.i += 1;
        }
        self.errors.push(Diagnostic::error(
            Span::new(start, start + 2),
            format!(
                "this comment is never closed (`{}` is missing)",
                String::from_utf8_lossy(close)
            ),
        ));
    }

    fn word(&mut self, start: usize) {
        while matches!(self.peek(0), b'a'..=b'z' | b'A'..=b'Z' | b'0'..=b'9' | b'_') {
            self.i += 1;
        }
        let word = &self.text[start..self.i];
        let is_time = ["T", "TIME", "LT", "LTIME"]
            .iter()
            .any(|t| t.eq_ignore_ascii_case(word));
        if is_time && self.peek(0) == b'#' {
            self.i += 1;
            return self.duration(start);
        }
        let tok = match Kw::of(word) {
            Some(k) => Tok::Kw(k),
            None => Tok::Ident(word.to_owned()),
        };
        self.push(tok, start);
    }

    /// Digits of `radix` with `_` between them, from the present place; their value, or why
    /// not.
    fn digits(&mut self, radix: u32) -> Result<u64, &'static str> {
        let from = self.i;
        let mut value: u64 = 0;
        let mut overflow = false;
        let mut any = false;
        while self.i < self.s.len() {
            let c = self.s[self.i];
            if c == b'_' && any {
                self.i += 1;
                continue;
            }
            let Some(d) = (c as char).to_digit(radix) else {
                break;
            };
            any = true;
            match value
                .checked_mul(u64::from(radix))
                .and_then(|v| v.checked_add(u64::from(d)))
            {
                Some(v) => value = v,
                None => overflow = true,
            }
            self.i += 1;
        }
        if !any || self.s.get(self.i - 1) == Some(&b'_') && self.i > from {
            if !any {
                return Err("digits are missing");
            }
            return Err("a number ends with `_`");
        }
        if overflow {
            return Err("the number is too large (beyond 64 bits)");
        }
        Ok(value)
    }

    fn number(&mut self, start: usize) {
        let value = match self.digits(10) {
            Ok(v) => v,
            Err(e) => return self.error(start, e),
        };
        // A based number: 2#, 8#, 16#.
        if self.peek(0) == b'#' {
            self.i += 1;
            let radix = match value {
                2 | 8 | 16 => value as u32,
                _ => return self.error(start, "a based number is 2#…, 8#… or 16#…"),
            };
            return match self.digits(radix) {
                Ok(v) => self.push(Tok::Int(v), start),
                Err(e) => {
                    while self.peek(0).is_ascii_alphanumeric() || self.peek(0) == b'_' {
                        self.i += 1;
                    }
                    self.error(start, e)
                }
            };
        }
        // A real: digits `.` digits, with an exponent perhaps; `1..4` is a range.
        let fraction = self.peek(0) == b'.' && self.peek(1).is_ascii_digit();
        let exponent = matches!(self.peek(0), b'e' | b'E')
            && (self.peek(1).is_ascii_digit()
                || matches!(self.peek(1), b'+' | b'-') && self.peek(2).is_ascii_digit());
        if !fraction && !exponent {
            return self.push(Tok::Int(value), start);
        }
        if fraction {
            self.i += 1;
            if let Err(e) = self.digits(10) {
                return self.error(start, e);
            }
        }
        if matches!(self.peek(0), b'e' | b'E') {
            self.i += 1;
            if matches!(self.peek(0), b'+' | b'-') {
                self.i += 1;
            }
            if let Err(e) = self.digits(10) {
                return self.error(start, e);
            }
        }
        let text: String = self.text[start..self.i]
            .chars()
            .filter(|&c| c != '_')
            .collect();
        match text.parse::<f64>() {
            Ok(r) if r.is_finite() => self.push(Tok::Real(r), start),
            _ => self.error(start, "the number is not a finite real"),
        }
    }

    /// A duration after `T#`: `-`? then numbers with units d, h, m, s, ms, us, ns.
    fn duration(&mut self, start: usize) {
        let negative = self.peek(0) == b'-';
        if negative {
            self.i += 1;
        }
        let mut total: f64 = 0.0;
        let mut parts = 0;
        loop {
            if !self.peek(0).is_ascii_digit() {
                break;
            }
            let from = self.i;
            while self.peek(0).is_ascii_digit() || self.peek(0) == b'_' {
                self.i += 1;
            }
            if self.peek(0) == b'.' && self.peek(1).is_ascii_digit() {
                self.i += 1;
                while self.peek(0).is_ascii_digit() {
                    self.i += 1;
                }
            }
            let n: f64 = self.text[from..self.i]
                .chars()
                .filter(|&c| c != '_')
                .collect::<String>()
                .parse()
                .unwrap_or(f64::INFINITY);
            let unit_from = self.i;
            while self.peek(0).is_ascii_alphabetic() {
                self.i += 1;
            }
            let unit = self.text[unit_from..self.i].to_ascii_lowercase();
            let ns = match unit.as_str() {
                "d" => 86_400e9,
                "h" => 3_600e9,
                "m" => 60e9,
                "s" => 1e9,
                "ms" => 1e6,
                "us" => 1e3,
                "ns" => 1.0,
                "" => {
                    return self.error(start, "a unit (d, h, m, s, ms, us, ns) is missing");
                }
                _ => {
                    return self.error(
                        unit_from,
                        format!("`{unit}` is no unit of a duration (d, h, m, s, ms, us, ns)"),
                    )
                }
            };
            total += n * ns;
            parts += 1;
            if self.peek(0) == b'_' {
                self.i += 1;
            }
        }
        if parts == 0 {
            return self.error(
                start,
                "a duration needs a number and a unit, e.g. T#2s500ms",
            );
        }
        if !(total.is_finite() && total <= i64::MAX as f64) {
            return self.error(start, "the duration is too long");
        }
        let ns = total.round() as i64;
        self.push(Tok::Time(if negative { -ns } else { ns }), start);
    }

    fn direct(&mut self, start: usize) {
        self.i += 1;
        // `%X3` (no area): a partial access, as in `w.%X3`.
        let partial = Size::of(self.peek(0));
        if let (Some(size), true) = (partial, self.peek(1).is_ascii_digit()) {
            self.i += 1;
            return match self.digits(10).map(u32::try_from) {
                Ok(Ok(n)) => self.push(Tok::Partial(size, n), start),
                _ => self.error(start, "the bit's number is too large"),
            };
        }
        let area = match self.peek(0).to_ascii_uppercase() {
            b'I' => Area::Input,
            b'Q' => Area::Output,
            b'M' => Area::Memory,
            _ => return self.error(start, "a direct variable is %I…, %Q… or %M…"),
        };
        self.i += 1;
        let size = Size::of(self.peek(0));
        if size.is_some() {
            self.i += 1;
        }
        let mut path = Vec::new();
        loop {
            match self.digits(10) {
                Ok(n) => match u32::try_from(n) {
                    Ok(n) => path.push(n),
                    Err(_) => return self.error(start, "the address is too large"),
                },
                Err(e) => return self.error(start, e),
            }
            if self.peek(0) == b'.' && self.peek(1).is_ascii_digit() {
                self.i += 1;
            } else {
                break;
            }
        }
        let d = Direct {
            area,
            size: size.unwrap_or(Size::Bit),
            path,
        };
        self.push(Tok::Direct(d), start);
    }

    fn string(&mut self, start: usize, quote: u8) {
        self.i += 1;
        let mut out = String::new();
        while self.i < self.s.len() {
            let c = self.s[self.i];
            if c == quote {
                self.i += 1;
                return self.push(Tok::Str(out), start);
            }
            if c == b'\n' {
                break;
            }
            // `$` escapes: $$ $' $" $L $N $P $R $T and $hh.
            if c == b'$' {
                let e = self.peek(1).to_ascii_uppercase();
                // The escape's character, whole (it may be any character).
                let next = self.text[self.i + 1..]
                    .chars()
                    .next()
                    .map_or(0, char::len_utf8);
                self.i += 1 + next;
                match e {
                    b'$' => out.push('$'),
                    b'\'' => out.push('\''),
                    b'"' => out.push('"'),
                    b'L' | b'N' => out.push('\n'),
                    b'P' => out.push('\x0c'),
                    b'R' => out.push('\r'),
                    b'T' => out.push('\t'),
                    _ => {
                        // `$hh`: two hex digits.
                        let hex = self.text.get(self.i - 1..self.i + 1).unwrap_or("");
                        match u8::from_str_radix(hex, 16) {
                            Ok(b) if next == 1 => {
                                out.push(char::from(b));
                                self.i += 1;
                            }
                            _ => return self.error(start, "an unknown `$` escape"),
                        }
                    }
                }
                continue;
            }
            // Whole characters, not bytes.
            let ch = self.text[self.i..].chars().next().unwrap_or('\u{fffd}');
            out.push(ch);
            self.i += ch.len_utf8();
        }
        self.error(start, "this string is never closed")
    }

    fn symbol(&mut self, start: usize) {
        let two = [self.peek(0), self.peek(1)];
        let (sym, len) = match &two {
            b":=" => (Some(Sym::Assign), 2),
            b"=>" => (Some(Sym::Arrow), 2),
            b"<>" => (Some(Sym::Ne), 2),
            b"<=" => (Some(Sym::Le), 2),
            b">=" => (Some(Sym::Ge), 2),
            b"**" => (Some(Sym::Power), 2),
            b".." => (Some(Sym::DotDot), 2),
            _ => (
                match two[0] {
                    b'=' => Some(Sym::Eq),
                    b'<' => Some(Sym::Lt),
                    b'>' => Some(Sym::Gt),
                    b'+' => Some(Sym::Plus),
                    b'-' => Some(Sym::Minus),
                    b'*' => Some(Sym::Star),
                    b'/' => Some(Sym::Slash),
                    b'&' => Some(Sym::Amp),
                    b'(' => Some(Sym::LParen),
                    b')' => Some(Sym::RParen),
                    b'[' => Some(Sym::LBracket),
                    b']' => Some(Sym::RBracket),
                    b',' => Some(Sym::Comma),
                    b';' => Some(Sym::Semi),
                    b':' => Some(Sym::Colon),
                    b'.' => Some(Sym::Dot),
                    b'#' => Some(Sym::Hash),
                    _ => None,
                },
                1,
            ),
        };
        match sym {
            Some(s) => {
                self.i += len;
                self.push(Tok::Sym(s), start);
            }
            None => {
                let ch = self.text[self.i..].chars().next().unwrap_or('\u{fffd}');
                self.i += ch.len_utf8();
                self.error(start, format!("`{ch}` is not part of Structured Text"));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toks(text: &str) -> Vec<Tok> {
        let (t, e) = lex(text);
        assert!(e.is_empty(), "{e:?}");
        t.into_iter().map(|t| t.tok).collect()
    }

    #[test]
    fn keywords_and_identifiers_in_any_case() {
        assert_eq!(
            toks("if Then end_IF Floor_2"),
            [
                Tok::Kw(Kw::If),
                Tok::Kw(Kw::Then),
                Tok::Kw(Kw::EndIf),
                Tok::Ident("Floor_2".into()),
                Tok::Eof
            ]
        );
    }

    #[test]
    fn numbers_of_every_base_and_reals() {
        assert_eq!(
            toks("1_000 16#FF 2#1010_0101 8#17 1.5 2.5E3 1e-2 1..4"),
            [
                Tok::Int(1000),
                Tok::Int(255),
                Tok::Int(0b1010_0101),
                Tok::Int(15),
                Tok::Real(1.5),
                Tok::Real(2500.0),
                Tok::Real(0.01),
                Tok::Int(1),
                Tok::Sym(Sym::DotDot),
                Tok::Int(4),
                Tok::Eof
            ]
        );
    }

    #[test]
    fn durations_in_their_units() {
        assert_eq!(
            toks("T#2s500ms TIME#1h_30m t#-1.5s T#100us T#1d"),
            [
                Tok::Time(2_500_000_000),
                Tok::Time(5_400_000_000_000),
                Tok::Time(-1_500_000_000),
                Tok::Time(100_000),
                Tok::Time(86_400_000_000_000),
                Tok::Eof
            ]
        );
    }

    #[test]
    fn direct_variables() {
        let t = toks("%IX2.3 %QW4 %I0.1 %MD10");
        let d = |area, size, path: &[u32]| {
            Tok::Direct(Direct {
                area,
                size,
                path: path.to_vec(),
            })
        };
        assert_eq!(
            t,
            [
                d(Area::Input, Size::Bit, &[2, 3]),
                d(Area::Output, Size::Word, &[4]),
                d(Area::Input, Size::Bit, &[0, 1]),
                d(Area::Memory, Size::Double, &[10]),
                Tok::Eof
            ]
        );
    }

    #[test]
    fn comments_of_three_kinds_and_strings() {
        assert_eq!(
            toks("a (* x *) /* y */ // z\n 'it$'s' \"q\""),
            [
                Tok::Ident("a".into()),
                Tok::Str("it's".into()),
                Tok::Str("q".into()),
                Tok::Eof
            ]
        );
    }

    #[test]
    fn operators_longest_first() {
        assert_eq!(
            toks(":= => <> <= >= ** < > = : ."),
            [
                Tok::Sym(Sym::Assign),
                Tok::Sym(Sym::Arrow),
                Tok::Sym(Sym::Ne),
                Tok::Sym(Sym::Le),
                Tok::Sym(Sym::Ge),
                Tok::Sym(Sym::Power),
                Tok::Sym(Sym::Lt),
                Tok::Sym(Sym::Gt),
                Tok::Sym(Sym::Eq),
                Tok::Sym(Sym::Colon),
                Tok::Sym(Sym::Dot),
                Tok::Eof
            ]
        );
    }

    #[test]
    fn what_cannot_be_read_is_reported_and_skipped() {
        let (t, e) = lex("a ? 3#1 T#5x 99999999999999999999 (* open");
        let messages: Vec<&str> = e.iter().map(|d| d.message.as_str()).collect();
        assert_eq!(
            messages,
            [
                "`?` is not part of Structured Text",
                "a based number is 2#…, 8#… or 16#…",
                "`x` is no unit of a duration (d, h, m, s, ms, us, ns)",
                "the number is too large (beyond 64 bits)",
                "this comment is never closed (`*)` is missing)",
            ]
        );
        assert_eq!(t.last().map(|t| &t.tok), Some(&Tok::Eof));
    }
}
