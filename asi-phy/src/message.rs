//! Numbers and input as messages quote them: short, whatever the input was.

/// `x` for a message, compactly: plain digits for everyday magnitudes (`0.5`, `1200`), else
/// scientific notation (`1e308`, `2.5e-9`), so that no number fills a line.
pub fn short_number(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || (1e-4..1e9).contains(&a) || !a.is_finite() {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::short_number;

    #[test]
    fn everyday_magnitudes_in_digits_the_rest_in_scientific_notation() {
        assert_eq!(short_number(0.5), "0.5");
        assert_eq!(short_number(-1200.0), "-1200");
        assert_eq!(short_number(2.5e-9), "2.5e-9");
        assert_eq!(short_number(1e308), "1e308");
        assert_eq!(short_number(f64::INFINITY), "inf");
    }
}
