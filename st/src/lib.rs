//! IEC 61131-3 Structured Text for asi-lift: a PLC programmer's lift program, run as the
//! simulated PLC against the bit-exact AS-i bus.
//!
//! This crate is the language's front end: the source and its diagnostics ([`source`]), the
//! tokens ([`lexer`]), the syntax ([`ast`]), the parser ([`parser`]), the elementary types
//! ([`types`]), the declarations checked ([`check`]), the statements typed ([`typeck`]), the
//! standard function blocks ([`stdfb`]) and the interpreter ([`run`]). A program that does
//! not parse is refused with every error at once, each as `file:line:column`, the source line
//! with a caret under the place, and the cause:
//!
//! ```
//! use st::source::Source;
//!
//! let src = Source::new("lift.st", "PROGRAM Lift\n  x := 1 +;\nEND_PROGRAM\n");
//! let (_, errors) = st::parser::parse(&src);
//! assert_eq!(
//!     src.render_all(&errors),
//!     "lift.st:2:10: error: an operand is missing after `+`\n  x := 1 +;\n         ^"
//! );
//! ```
//!
//! Why a parser of its own: the two Structured Text crates on crates.io (`iec61131` 0.7 and
//! `iecst` 0.5) refuse constructs the standard has and a lift program uses (an enumeration
//! `TYPE`, a based literal `16#FF`, a typed literal `INT#2`), stop at the first error, and give
//! an expression no place of its own (docs/dev/structured-text.md).

pub mod ast;
pub mod check;
pub mod lexer;
pub mod parser;
pub mod run;
pub mod source;
pub mod stdfb;
pub mod typeck;
pub mod types;
