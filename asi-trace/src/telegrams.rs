//! Telegram fields as asi-lift writes them for machines: the JSON of `run --trace FILE.jsonl`
//! and of `decode --json` share these shapes, so a trace and a decoded capture compare field by
//! field (docs/physical-layer.md bit order ST..EB; check names as in the report).

use asi_phy::{Check, Checks, Received, Request, Response, TelegramKind};
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

/// The keys of the failed checks, in the fixed order of docs/physical-layer.md.
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

/// What a telegram on the line was: the `type` of a [`TelegramRecord`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum TelegramType {
    /// A 14-bit master request.
    Request,
    /// A 7-bit slave response.
    Response,
    /// A pulse run of neither length as the receiver expected it (a 7-bit run where the
    /// receiver waited for a request, a cut or merged telegram).
    Unknown,
}

impl TelegramType {
    /// `request`, `response` or `unknown`.
    pub const fn name(self) -> &'static str {
        match self {
            TelegramType::Request => "request",
            TelegramType::Response => "response",
            TelegramType::Unknown => "unknown",
        }
    }
}

/// One telegram as a line of `run --trace FILE.jsonl` or of `decode --json`:
/// `{"t_ns": 10000, "type": "request", "bits": "00001010101001", "call": "Data_Exchange",
/// "address": 5, "info": "01010", "data": null, "errors": []}`.
///
/// The call, address, info and data are those of a valid telegram; a telegram that failed a
/// check shows only its bits and the failed checks.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize)]
pub struct TelegramRecord {
    /// Time of the first pulse in nanoseconds, in the time base of the run or the capture.
    pub t_ns: i64,
    /// Request, response or unknown.
    #[serde(rename = "type")]
    pub kind: TelegramType,
    /// The bits ST..EB as received (at most 32 digits).
    pub bits: String,
    /// A valid request's call name ([`asi_phy::Call::name`]).
    pub call: Option<&'static str>,
    /// A valid request's address A4..A0.
    pub address: Option<u8>,
    /// A valid request's I4..I0 as 5 digits.
    pub info: Option<String>,
    /// A valid response's I3..I0 as 4 digits.
    pub data: Option<String>,
    /// The failed checks' keys ([`check_key`]) in the order of docs/physical-layer.md; empty if valid.
    pub errors: Vec<&'static str>,
}

impl TelegramRecord {
    /// A valid request whose first pulse is at `t_ns`.
    pub fn request(t_ns: i64, r: Request) -> TelegramRecord {
        let f = RequestFields::of(r);
        TelegramRecord {
            t_ns,
            kind: TelegramType::Request,
            bits: f.bits,
            call: Some(f.call),
            address: Some(f.address),
            info: Some(f.info),
            data: None,
            errors: Vec::new(),
        }
    }

    /// A valid response whose first pulse is at `t_ns`.
    pub fn response(t_ns: i64, r: Response) -> TelegramRecord {
        let f = ResponseFields::of(r);
        TelegramRecord {
            t_ns,
            kind: TelegramType::Response,
            bits: f.bits,
            call: None,
            address: None,
            info: None,
            data: Some(f.data),
            errors: Vec::new(),
        }
    }

    /// What a receiver made of a pulse run, its first pulse at `t_ns`. The type is the
    /// receiver's if the run has that type's length, else unknown.
    pub fn received(t_ns: i64, r: &Received) -> TelegramRecord {
        if let Some(q) = r.request() {
            return TelegramRecord::request(t_ns, q);
        }
        if let Some(p) = r.response() {
            return TelegramRecord::response(t_ns, p);
        }
        let kind = match r.kind {
            k if r.bit_count != k.bits() => TelegramType::Unknown,
            TelegramKind::Request => TelegramType::Request,
            TelegramKind::Response => TelegramType::Response,
        };
        TelegramRecord {
            t_ns,
            kind,
            bits: r.bit_string(),
            call: None,
            address: None,
            info: None,
            data: None,
            errors: check_keys(r.failed),
        }
    }

    /// `true` if every check passed.
    pub fn is_valid(&self) -> bool {
        self.errors.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use asi_phy::{Address, Nibble};

    #[test]
    fn fields_of_the_spec_vectors() {
        // docs/physical-layer.md worked vectors.
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
