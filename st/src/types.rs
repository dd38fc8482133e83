//! The elementary data types of Structured Text (IEC 61131-3, 3rd edition, §6.4.2, table 10)
//! that a lift program uses, their ranges, the implicit conversions between them (§6.6.1.6:
//! widening only, never a loss), the common type of a binary operation, and the typed
//! conversion functions `<FROM>_TO_<TO>`.

use std::fmt;

/// An elementary type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[allow(missing_docs)]
pub enum Elem {
    Bool,
    Byte,
    Word,
    Dword,
    Lword,
    Sint,
    Int,
    Dint,
    Lint,
    Usint,
    Uint,
    Udint,
    Ulint,
    Real,
    Lreal,
    Time,
    Ltime,
}

/// Every elementary type and its name.
const NAMES: &[(&str, Elem)] = &[
    ("BOOL", Elem::Bool),
    ("BYTE", Elem::Byte),
    ("WORD", Elem::Word),
    ("DWORD", Elem::Dword),
    ("LWORD", Elem::Lword),
    ("SINT", Elem::Sint),
    ("INT", Elem::Int),
    ("DINT", Elem::Dint),
    ("LINT", Elem::Lint),
    ("USINT", Elem::Usint),
    ("UINT", Elem::Uint),
    ("UDINT", Elem::Udint),
    ("ULINT", Elem::Ulint),
    ("REAL", Elem::Real),
    ("LREAL", Elem::Lreal),
    ("TIME", Elem::Time),
    ("LTIME", Elem::Ltime),
];

/// The implicit conversions, one step each (§6.6.1.6 of IEC 61131-3, 3rd edition: a value
/// converts implicitly only to a type that holds every value of its own); the relation is
/// their transitive closure ([`Elem::widens_to`]).
const WIDENING: &[(Elem, Elem)] = &[
    (Elem::Sint, Elem::Int),
    (Elem::Int, Elem::Dint),
    (Elem::Dint, Elem::Lint),
    (Elem::Usint, Elem::Uint),
    (Elem::Uint, Elem::Udint),
    (Elem::Udint, Elem::Ulint),
    (Elem::Usint, Elem::Int),
    (Elem::Uint, Elem::Dint),
    (Elem::Udint, Elem::Lint),
    // A REAL holds every integer of up to 16 bits exactly, an LREAL of up to 32.
    (Elem::Int, Elem::Real),
    (Elem::Uint, Elem::Real),
    (Elem::Dint, Elem::Lreal),
    (Elem::Udint, Elem::Lreal),
    (Elem::Real, Elem::Lreal),
    (Elem::Bool, Elem::Byte),
    (Elem::Byte, Elem::Word),
    (Elem::Word, Elem::Dword),
    (Elem::Dword, Elem::Lword),
    (Elem::Time, Elem::Ltime),
];

impl Elem {
    /// Every elementary type.
    pub fn all() -> impl Iterator<Item = Elem> {
        NAMES.iter().map(|&(_, e)| e)
    }

    /// The type named `name` (any case).
    pub fn of(name: &str) -> Option<Elem> {
        NAMES
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(name))
            .map(|&(_, e)| e)
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        NAMES
            .iter()
            .find(|&&(_, e)| e == self)
            .map_or("?", |&(n, _)| n)
    }

    /// A signed or unsigned integer (ANY_INT).
    pub fn is_int(self) -> bool {
        self.int_range().is_some()
    }

    /// REAL or LREAL (ANY_REAL).
    pub fn is_real(self) -> bool {
        matches!(self, Elem::Real | Elem::Lreal)
    }

    /// An integer or a real (ANY_NUM).
    pub fn is_num(self) -> bool {
        self.is_int() || self.is_real()
    }

    /// A bit string, BOOL included (ANY_BIT).
    pub fn is_bits(self) -> bool {
        self.bits().is_some()
    }

    /// TIME or LTIME (ANY_DURATION).
    pub fn is_duration(self) -> bool {
        matches!(self, Elem::Time | Elem::Ltime)
    }

    /// How many bits a bit string has.
    pub fn bits(self) -> Option<u32> {
        Some(match self {
            Elem::Bool => 1,
            Elem::Byte => 8,
            Elem::Word => 16,
            Elem::Dword => 32,
            Elem::Lword => 64,
            _ => return None,
        })
    }

    /// The least and the greatest value of an integer type.
    pub fn int_range(self) -> Option<(i128, i128)> {
        Some(match self {
            Elem::Sint => (i8::MIN.into(), i8::MAX.into()),
            Elem::Int => (i16::MIN.into(), i16::MAX.into()),
            Elem::Dint => (i32::MIN.into(), i32::MAX.into()),
            Elem::Lint => (i64::MIN.into(), i64::MAX.into()),
            Elem::Usint => (0, u8::MAX.into()),
            Elem::Uint => (0, u16::MAX.into()),
            Elem::Udint => (0, u32::MAX.into()),
            Elem::Ulint => (0, u64::MAX.into()),
            _ => return None,
        })
    }

    /// `true` if integer `value` is one of the type's values (an integer type or a bit
    /// string, whose values are its bit patterns).
    pub fn holds(self, value: i128) -> bool {
        if let Some((lo, hi)) = self.int_range() {
            return (lo..=hi).contains(&value);
        }
        match self.bits() {
            Some(64) => (0..=i128::from(u64::MAX)).contains(&value),
            Some(n) => (0..1i128 << n).contains(&value),
            None => false,
        }
    }

    /// `true` if a value of `self` converts implicitly to `to` (the same type included).
    pub fn widens_to(self, to: Elem) -> bool {
        if self == to {
            return true;
        }
        // The relation is small and acyclic: a search over its steps.
        WIDENING
            .iter()
            .filter(|&&(from, _)| from == self)
            .any(|&(_, next)| next.widens_to(to))
    }

    /// The type both `a` and `b` convert to implicitly for a binary operation: the least one,
    /// if any (`INT` and `UINT`: `DINT`; `INT` and `REAL`: `REAL`; `WORD` and `INT`: none).
    /// Two integers meet in an integer type where one holds both (`INT` and `UINT` also
    /// meet in `REAL`, which is no integer).
    pub fn common(a: Elem, b: Elem) -> Option<Elem> {
        let ints = a.is_int() && b.is_int();
        let meet = |t: &Elem| a.widens_to(*t) && b.widens_to(*t);
        let mut candidates: Vec<Elem> = Elem::all()
            .filter(|t| meet(t) && (!ints || t.is_int()))
            .collect();
        if candidates.is_empty() {
            candidates = Elem::all().filter(meet).collect();
        }
        // The least: the candidate every other candidate is reached from.
        candidates
            .iter()
            .copied()
            .find(|&t| candidates.iter().all(|&u| t.widens_to(u)))
    }

    /// The typed conversion function `<FROM>_TO_<TO>` named `name` (any case), with the
    /// types it converts between; `None` for another name. Between any two of the types
    /// the lift program uses: numbers, bit strings and durations, and BOOL.
    pub fn conversion(name: &str) -> Option<(Elem, Elem)> {
        let upper = name.to_ascii_uppercase();
        let (from, to) = upper.split_once("_TO_")?;
        let (from, to) = (Elem::of(from)?, Elem::of(to)?);
        (from != to).then_some((from, to))
    }
}

impl fmt::Display for Elem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_in_any_case() {
        assert_eq!(Elem::of("dint"), Some(Elem::Dint));
        assert_eq!(Elem::of("Real"), Some(Elem::Real));
        assert_eq!(Elem::of("STRING"), None);
        for e in Elem::all() {
            assert_eq!(Elem::of(e.name()), Some(e));
        }
    }

    /// The implicit conversions never lose a value: every integer type widens only to types
    /// whose range holds its own, a bit string only to longer ones, a real never to an
    /// integer, and nothing narrows.
    #[test]
    fn widening_never_loses_a_value() {
        for a in Elem::all() {
            for b in Elem::all() {
                if !a.widens_to(b) || a == b {
                    continue;
                }
                assert!(!b.widens_to(a), "{a} and {b} widen into each other");
                if let (Some((alo, ahi)), Some((blo, bhi))) = (a.int_range(), b.int_range()) {
                    assert!(blo <= alo && ahi <= bhi, "{a} → {b} loses values");
                }
                if let Some((lo, hi)) = a.int_range() {
                    // A REAL's 24-bit mantissa holds every 16-bit integer, an LREAL's 53
                    // bits every 32-bit one.
                    let exact = match b {
                        Elem::Real => 1i128 << 24,
                        Elem::Lreal => 1i128 << 53,
                        _ => i128::MAX,
                    };
                    assert!(-exact <= lo && hi <= exact, "{a} → {b} rounds");
                }
                if a.is_real() {
                    assert!(b.is_real(), "{a} → {b}");
                }
                if let (Some(x), Some(y)) = (a.bits(), b.bits()) {
                    assert!(x < y, "{a} → {b}");
                }
                assert_eq!(a.is_bits(), b.is_bits(), "{a} → {b} crosses kinds");
                assert_eq!(a.is_duration(), b.is_duration(), "{a} → {b} crosses kinds");
            }
        }
    }

    #[test]
    fn the_widenings_a_programmer_relies_on() {
        use Elem::*;
        for (a, b) in [
            (Sint, Lint),
            (Usint, Int),
            (Uint, Dint),
            (Int, Real),
            (Dint, Lreal),
            (Real, Lreal),
            (Bool, Word),
            (Byte, Lword),
            (Time, Ltime),
        ] {
            assert!(a.widens_to(b), "{a} → {b}");
        }
        for (a, b) in [
            (Dint, Real),
            (Lint, Lreal),
            (Int, Uint),
            (Uint, Int),
            (Word, Int),
            (Int, Word),
            (Real, Dint),
            (Time, Dint),
            (Bool, Int),
        ] {
            assert!(!a.widens_to(b), "{a} → {b}");
        }
    }

    #[test]
    fn the_common_type_of_an_operation() {
        use Elem::*;
        assert_eq!(Elem::common(Int, Int), Some(Int));
        assert_eq!(Elem::common(Sint, Int), Some(Int));
        assert_eq!(Elem::common(Int, Uint), Some(Dint));
        assert_eq!(Elem::common(Usint, Sint), Some(Int));
        assert_eq!(Elem::common(Int, Real), Some(Real));
        assert_eq!(Elem::common(Dint, Real), Some(Lreal));
        assert_eq!(Elem::common(Byte, Word), Some(Word));
        assert_eq!(Elem::common(Word, Int), None);
        assert_eq!(Elem::common(Lint, Real), None);
        assert_eq!(Elem::common(Time, Int), None);
    }

    #[test]
    fn ranges_and_bit_patterns() {
        use Elem::*;
        assert!(Int.holds(-32_768) && Int.holds(32_767) && !Int.holds(32_768));
        assert!(Uint.holds(65_535) && !Uint.holds(-1));
        assert!(Word.holds(0xFFFF) && !Word.holds(0x1_0000) && !Word.holds(-1));
        assert!(Lword.holds(u64::MAX.into()) && Bool.holds(1) && !Bool.holds(2));
        assert!(!Real.holds(1));
    }

    #[test]
    fn conversion_functions_by_name() {
        assert_eq!(
            Elem::conversion("INT_TO_WORD"),
            Some((Elem::Int, Elem::Word))
        );
        assert_eq!(
            Elem::conversion("real_to_dint"),
            Some((Elem::Real, Elem::Dint))
        );
        assert_eq!(Elem::conversion("INT_TO_INT"), None);
        assert_eq!(Elem::conversion("INT_TO_STRING"), None);
        assert_eq!(Elem::conversion("SHL"), None);
    }
}
