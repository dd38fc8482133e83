//! The physical-layer tool of the `asi-lift` command: show how a master call travels on the
//! line (`encode`). Reading a capture back into telegrams (`decode`) is [`crate::capture`].

use asi_phy::waveform::{render, WaveformConfig};
use asi_phy::{
    Address, BusTiming, Call, HalfBits, Nibble, PulseTrain, Request, Response, Select, SimDuration,
    SimTime,
};
use std::fmt::Write as _;

/// A telegram named on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LineTelegram {
    /// A master request.
    Request(Request),
    /// A Data_Exchange or Write_Parameter to an A/B slave (`dexg 7B 001`): the request alone
    /// does not say so (its I3, the select bit, is an output bit to a standard slave), so the
    /// slave named is kept for the description.
    AbRequest(Request, Select),
    /// A slave response.
    Response(Response),
}

/// Why a call named on the command line is not a telegram.
#[derive(Debug, PartialEq, Eq, thiserror::Error)]
pub enum CallError {
    /// The mnemonic is unknown.
    #[error("unknown call `{0}`: use dexg, wpar, adra, wid1, dela, res, rdio, rdid, rid1, rid2, rdst, br01 or resp")]
    UnknownCall(String),
    /// An argument is missing.
    #[error("`{call}` needs {what}")]
    Missing {
        /// The call.
        call: String,
        /// What is missing.
        what: &'static str,
    },
    /// An address is malformed.
    #[error("address `{0}`: expected 0..31, optionally followed by A or B (e.g. 5, 7B)")]
    BadAddress(String),
    /// A value is malformed.
    #[error("value `{0}`: expected four binary digits (1010), 0b1010 or a decimal 0..15")]
    BadValue(String),
    /// Too many arguments.
    #[error("unexpected argument `{0}`")]
    Extra(String),
    /// The fields make no telegram.
    #[error(transparent)]
    LineTelegram(#[from] asi_phy::TelegramError),
}

fn parse_address(s: &str) -> Result<(Address, Option<Select>), CallError> {
    let bad = || CallError::BadAddress(s.to_owned());
    let (num, sel) = match s.chars().last() {
        Some('a' | 'A') => (&s[..s.len() - 1], Some(Select::A)),
        Some('b' | 'B') => (&s[..s.len() - 1], Some(Select::B)),
        _ => (s, None),
    };
    let v: u8 = num.parse().map_err(|_| bad())?;
    Ok((Address::new(v).ok_or_else(bad)?, sel))
}

fn parse_nibble(s: &str) -> Result<Nibble, CallError> {
    let bad = || CallError::BadValue(s.to_owned());
    let v = if let Some(bin) = s.strip_prefix("0b") {
        u8::from_str_radix(bin, 2).map_err(|_| bad())?
    } else if s.len() == 4 && s.bytes().all(|b| b == b'0' || b == b'1') {
        u8::from_str_radix(s, 2).map_err(|_| bad())?
    } else {
        s.parse().map_err(|_| bad())?
    };
    Nibble::new(v).ok_or_else(bad)
}

/// Reads a call from its ZMD mnemonic and arguments, e.g. `dexg 5 1010`, `rdst 7B`,
/// `adra 12`, `br01`, `resp 0110` (a slave response).
pub fn parse_call(args: &[String]) -> Result<LineTelegram, CallError> {
    let Some((name, rest)) = args.split_first() else {
        return Err(CallError::UnknownCall(String::new()));
    };
    let call = name.to_ascii_lowercase();
    let arg = |i: usize, what: &'static str| {
        rest.get(i).ok_or_else(|| CallError::Missing {
            call: call.clone(),
            what,
        })
    };
    let (telegram, used) = match call.as_str() {
        "dexg" | "wpar" => {
            let (a, sel) = parse_address(arg(0, "an address")?)?;
            let v = parse_nibble(arg(1, "a value")?)?;
            let t = match (call.as_str(), sel) {
                ("dexg", None) => LineTelegram::Request(Request::data_exchange(a, v)?),
                ("dexg", Some(s)) => {
                    LineTelegram::AbRequest(Request::data_exchange_ab(a, s, v)?, s)
                }
                (_, None) => LineTelegram::Request(Request::write_parameter(a, v)?),
                (_, Some(s)) => LineTelegram::AbRequest(Request::write_parameter_ab(a, s, v)?, s),
            };
            (t, 2)
        }
        "adra" => {
            let (a, _) = parse_address(arg(0, "the new address")?)?;
            (LineTelegram::Request(Request::address_assignment(a)), 1)
        }
        "wid1" => {
            let v = parse_nibble(arg(0, "an ID1 value")?)?;
            (LineTelegram::Request(Request::write_extended_id1(v)), 1)
        }
        "dela" | "res" | "rdio" | "rdid" | "rid1" | "rid2" | "rdst" => {
            let (a, sel) = parse_address(arg(0, "an address")?)?;
            let s = sel.unwrap_or(Select::A);
            let r = match call.as_str() {
                "dela" => Request::delete_address(a, s)?,
                "res" => Request::reset_slave(a, s)?,
                "rdio" => Request::read_io_configuration(a, s)?,
                "rdid" => Request::read_id_code(a, s)?,
                "rid1" => Request::read_id1(a, s)?,
                "rid2" => Request::read_id2(a, s)?,
                _ => Request::read_status(a, s)?,
            };
            (LineTelegram::Request(r), 1)
        }
        "br01" => (LineTelegram::Request(Request::broadcast_reset()), 0),
        "resp" => (
            LineTelegram::Response(Response::new(parse_nibble(arg(0, "a value")?)?)),
            1,
        ),
        _ => return Err(CallError::UnknownCall(name.clone())),
    };
    match rest.get(used) {
        Some(extra) => Err(CallError::Extra(extra.clone())),
        None => Ok(telegram),
    }
}

/// The pulse train of `t` starting at time zero.
pub fn pulse_train(t: LineTelegram) -> PulseTrain {
    let h = BusTiming::default().half_bit();
    match t {
        LineTelegram::Request(r) | LineTelegram::AbRequest(r, _) => {
            PulseTrain::request(r, SimTime::ZERO, h)
        }
        LineTelegram::Response(r) => PulseTrain::response(r, SimTime::ZERO, h),
    }
}

/// A readable description of how `t` travels: bits, Manchester levels, pulses.
pub fn describe(t: LineTelegram) -> String {
    let mut s = String::new();
    let (bits, halves) = match t {
        LineTelegram::Request(r) => {
            let _ = writeln!(s, "call        {}", r.call());
            (r.to_string(), HalfBits::from(r))
        }
        LineTelegram::AbRequest(r, select) => {
            // The A/B slave's three outputs or parameters D2..D0; I3 is the select bit.
            let low3 = |n: Nibble| n.get() & 0b111;
            let _ = match r.call() {
                Call::DataExchange { address, data } => writeln!(
                    s,
                    "call        Data_Exchange {address}{select} out={:03b}",
                    low3(data)
                ),
                Call::WriteParameter { address, parameter } => writeln!(
                    s,
                    "call        Write_Parameter {address}{select} P={:03b}",
                    low3(parameter)
                ),
                other => writeln!(s, "call        {other}"),
            };
            (r.to_string(), HalfBits::from(r))
        }
        LineTelegram::Response(r) => {
            let _ = writeln!(s, "response    {}", r.data());
            (r.to_string(), HalfBits::from(r))
        }
    };
    let train = pulse_train(t);
    let _ = writeln!(s, "bits        {bits}");
    let _ = writeln!(s, "manchester  {halves}");
    let _ = writeln!(s, "pulses      {train}   (grid points of 3 µs)");
    let _ = writeln!(
        s,
        "span        {} from first to last pulse, {} pulses",
        train.end() - train.start(),
        train.len()
    );
    s
}

/// The line voltage of `t` with 10 µs of idle line before and after, as `time,voltage` CSV.
pub fn waveform_csv(
    t: LineTelegram,
    cfg: &WaveformConfig,
) -> Result<String, asi_phy::waveform::WaveformError> {
    let lead = SimDuration::from_micros(10);
    let train = pulse_train(t).at(SimTime::ZERO + lead);
    let wf = render(train, SimTime::ZERO, train.end() + lead, cfg)?;
    let mut s = String::from("time_s,voltage_v\n");
    for (i, v) in wf.samples.iter().enumerate() {
        let _ = writeln!(s, "{:.9},{v:.5}", wf.time_of(i as f64).as_secs_f64());
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(s: &str) -> Vec<String> {
        s.split_whitespace().map(String::from).collect()
    }

    #[test]
    fn parses_the_mnemonics_engineers_use() {
        let a5 = Address::new(5).expect("a");
        assert_eq!(
            parse_call(&args("dexg 5 1010")),
            Ok(LineTelegram::Request(
                Request::data_exchange(a5, Nibble::from_low_bits(0b1010)).expect("v")
            ))
        );
        assert_eq!(
            parse_call(&args("RDST 5B")),
            Ok(LineTelegram::Request(
                Request::read_status(a5, Select::B).expect("v")
            ))
        );
        assert_eq!(
            parse_call(&args("br01")),
            Ok(LineTelegram::Request(Request::broadcast_reset()))
        );
        assert_eq!(
            parse_call(&args("resp 0b110")),
            Ok(LineTelegram::Response(Response::new(
                Nibble::from_low_bits(6)
            )))
        );
    }

    #[test]
    fn names_what_is_wrong_with_a_call() {
        assert_eq!(
            parse_call(&args("dexg 32 1")),
            Err(CallError::BadAddress("32".into()))
        );
        assert_eq!(
            parse_call(&args("dexg 5 16")),
            Err(CallError::BadValue("16".into()))
        );
        assert_eq!(
            parse_call(&args("dexg 5")).map_err(|e| e.to_string()),
            Err("`dexg` needs a value".into())
        );
        assert_eq!(
            parse_call(&args("br01 7")),
            Err(CallError::Extra("7".into()))
        );
        assert!(matches!(
            parse_call(&args("xyz")),
            Err(CallError::UnknownCall(_))
        ));
        assert!(matches!(
            parse_call(&args("dexg 0 1")),
            Err(CallError::LineTelegram(_))
        ));
    }

    #[test]
    fn describe_names_the_ab_slave() {
        let d = describe(parse_call(&args("dexg 7B 0001")).expect("call"));
        assert!(d.contains("call        Data_Exchange 7B out=001\n"), "{d}");
        let d = describe(parse_call(&args("wpar 7A 5")).expect("call"));
        assert!(d.contains("call        Write_Parameter 7A P=101\n"), "{d}");
        let d = describe(parse_call(&args("dexg 7 0001")).expect("call"));
        assert!(d.contains("call        Data_Exchange 7 out=0001\n"), "{d}");
    }

    #[test]
    fn describe_shows_the_spec_vector() {
        let t = parse_call(&args("dexg 5 1010")).expect("call");
        let d = describe(t);
        assert!(d.contains("bits        0 0 00101 01010 0 1"), "{d}");
        assert!(d.contains(
            "pulses      0- 1+ 2- 3+ 4- 5+ 6- 7+ 9- 11+ 13- 15+ 17- 19+ 21- 23+ 24- 25+ 27- 28+"
        ));
        assert!(d.contains("84 µs from first to last pulse, 20 pulses"));
    }
}
