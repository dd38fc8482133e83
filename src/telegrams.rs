//! Telegram fields as asi-lift writes them for machines: the JSON of `run --trace FILE.jsonl`
//! and of `decode --json` share these shapes, so a trace and a decoded capture compare field by
//! field (SPEC §1 bit order ST..EB; check names as in the report).

use asi_phy::{Check, Checks, Request, Response};
use serde::Serialize;

/// A check's key in reports, traces and decoder output: `start_bit`, `alternation`, `pause`,
/// `information`, `parity`, `end_bit`, `length`.
pub const fn check_key(c: Check) -> &'static str {
    match c {
        Check::StartBit => "start_bit",
        Check::Alternation => "alternation",
        Check::Pause => "pause",
        Check::Information => "information",
        Check::Parity => "parity",
        Check::EndBit => "end_bit",
        Check::Length => "length",
    }
}

/// The keys of the failed checks, in the fixed order of SPEC §1.
pub fn check_keys(c: Checks) -> Vec<&'static str> {
    c.iter().map(check_key).collect()
}

/// `n` bits of `raw` (first bit most significant) as `0`/`1` digits.
pub fn bit_string(raw: u32, n: u32) -> String {
    let n = n.min(32);
    (0..n)
        .map(|i| {
            if raw >> (n - 1 - i) & 1 == 1 {
                '1'
            } else {
                '0'
            }
        })
        .collect()
}

/// A master request: its 14 bits ST..EB, the call's name, the address A4..A0 and the
/// information bits I4..I0.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct RequestFields {
    /// 14 digits, ST first.
    pub bits: String,
    /// The call's name (`Data_Exchange`, `Read_ID1`, …; `Unknown` for a reserved code).
    pub call: &'static str,
    /// A4..A0.
    pub address: u8,
    /// I4..I0 as 5 digits.
    pub info: String,
}

impl RequestFields {
    /// The fields of `r`.
    pub fn of(r: Request) -> RequestFields {
        RequestFields {
            bits: bit_string(r.bits() as u32, Request::BITS),
            call: r.call().name(),
            address: r.address().get(),
            info: bit_string(r.info() as u32, 5),
        }
    }
}

/// A slave response: its 7 bits ST..EB and the data I3..I0.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct ResponseFields {
    /// 7 digits, ST first.
    pub bits: String,
    /// I3..I0 as 4 digits.
    pub data: String,
}

impl ResponseFields {
    /// The fields of `r`.
    pub fn of(r: Response) -> ResponseFields {
        ResponseFields {
            bits: bit_string(r.bits() as u32, Response::BITS),
            data: bit_string(r.data().get() as u32, 4),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use asi_phy::{Address, Nibble};

    #[test]
    fn fields_of_the_spec_vectors() {
        // SPEC §1 worked vectors.
        let q = Request::data_exchange(
            Address::new(5).expect("address"),
            Nibble::from_low_bits(0b1010),
        )
        .expect("valid");
        assert_eq!(
            RequestFields::of(q),
            RequestFields {
                bits: "00001010101001".into(),
                call: "Data_Exchange",
                address: 5,
                info: "01010".into(),
            }
        );
        assert_eq!(
            RequestFields::of(Request::broadcast_reset()).bits,
            "01111111010111"
        );
        let r = ResponseFields::of(Response::new(Nibble::from_low_bits(0b0110)));
        assert_eq!(r.bits, "0011001");
        assert_eq!(r.data, "0110");
    }

    #[test]
    fn check_keys_follow_the_spec_order() {
        let c = Checks::only(Check::Length)
            .with(Check::StartBit)
            .with(Check::Parity);
        assert_eq!(check_keys(c), ["start_bit", "parity", "length"]);
        assert_eq!(check_keys(Checks::NONE), Vec::<&str>::new());
    }
}
