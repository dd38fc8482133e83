//! The transaction trace of `asi-lift run --trace`: one transaction per line, as readable text
//! (for snapshot tests and the terminal) or as JSON lines (for machines).

use crate::telegrams::{check_keys, RequestFields, ResponseFields};
use asi_master::record::{describe_request, TransactionRecord};
use serde::Serialize;
use std::io::{self, Write};
use std::path::Path;

/// How the trace is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TraceFormat {
    /// One readable line per transaction (asi-master's trace line).
    Text,
    /// One JSON object per line ([`TraceEntry`]).
    Jsonl,
}

impl TraceFormat {
    /// The format a file name asks for: `.jsonl` or `.json` is JSON lines, anything else text.
    pub fn for_path(path: &Path) -> TraceFormat {
        match path.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("jsonl") || e.eq_ignore_ascii_case("json") => {
                TraceFormat::Jsonl
            }
            _ => TraceFormat::Text,
        }
    }
}

/// One transaction as a JSON line.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct TraceEntry {
    /// Time of the request's first pulse, ns of simulated time.
    pub t_ns: u64,
    /// What the master was doing: detect, activate, data, manage, job, include, auto-addr,
    /// offline.
    pub phase: &'static str,
    /// The request the master sent.
    pub request: RequestFields,
    /// The call as one readable line (`Data_Exchange 5 out=1010`, `Read_Status 3A`).
    pub text: String,
    /// The response the master received intact, or null (none came, or it was corrupt).
    pub response: Option<ResponseFields>,
    /// The receiver checks that failed, on the request (as the slaves saw it) and on the
    /// response (as the master saw it), in the order of docs/physical-layer.md.
    pub errors: Vec<&'static str>,
    /// `true` for the immediate repeat of a failed transaction.
    pub repeat: bool,
}

impl TraceEntry {
    /// The entry of a transaction.
    pub fn of(r: &TransactionRecord) -> TraceEntry {
        TraceEntry {
            t_ns: r.start.as_nanos(),
            phase: r.kind.label(),
            request: RequestFields::of(r.request),
            text: describe_request(r.request, r.ab),
            response: r.response.map(ResponseFields::of),
            errors: check_keys(r.request_failed.union(r.response_failed)),
            repeat: r.repeat,
        }
    }
}

/// Writes one transaction in `format`.
pub fn write_record(
    out: &mut dyn Write,
    r: &TransactionRecord,
    format: TraceFormat,
) -> io::Result<()> {
    match format {
        TraceFormat::Text => writeln!(out, "{r}"),
        TraceFormat::Jsonl => {
            serde_json::to_writer(&mut *out, &TraceEntry::of(r)).map_err(io::Error::other)?;
            out.write_all(b"\n")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use asi_master::record::TxKind;
    use asi_phy::{Address, Check, Checks, Nibble, Request, Response, SimTime};

    fn record() -> TransactionRecord {
        TransactionRecord {
            start: SimTime::from_micros(40_266),
            kind: TxKind::DataExchange,
            request: Request::data_exchange(
                Address::new(5).expect("address"),
                Nibble::from_low_bits(0b1010),
            )
            .expect("valid"),
            request_failed: Checks::NONE,
            response: Some(Response::new(Nibble::from_low_bits(0b0110))),
            response_failed: Checks::NONE,
            no_response: false,
            repeat: false,
            ab: false,
        }
    }

    fn line(r: &TransactionRecord, f: TraceFormat) -> String {
        let mut out = Vec::new();
        write_record(&mut out, r, f).expect("write");
        String::from_utf8(out).expect("utf-8")
    }

    #[test]
    fn a_transaction_as_a_json_line() {
        assert_eq!(
            line(&record(), TraceFormat::Jsonl),
            concat!(
                r#"{"t_ns":40266000,"phase":"data","#,
                r#""request":{"bits":"00001010101001","call":"Data_Exchange","address":5,"info":"01010"},"#,
                r#""text":"Data_Exchange 5 out=1010","response":{"bits":"0011001","data":"0110"},"#,
                r#""errors":[],"repeat":false}"#,
                "\n"
            )
        );
        let failed = TransactionRecord {
            request_failed: Checks::only(Check::Alternation),
            response: None,
            no_response: true,
            repeat: true,
            ..record()
        };
        let l = line(&failed, TraceFormat::Jsonl);
        assert!(
            l.ends_with("\"response\":null,\"errors\":[\"alternation\"],\"repeat\":true}\n"),
            "{l}"
        );
    }

    #[test]
    fn a_transaction_as_a_text_line() {
        assert_eq!(
            line(&record(), TraceFormat::Text),
            " 0.040266000 s  data      0 0 00101 01010 0 1  Data_Exchange 5 out=1010       -> 0 0110 0 1\n"
        );
    }

    #[test]
    fn the_file_name_picks_the_format() {
        assert_eq!(
            TraceFormat::for_path(Path::new("t.jsonl")),
            TraceFormat::Jsonl
        );
        assert_eq!(
            TraceFormat::for_path(Path::new("t.JSON")),
            TraceFormat::Jsonl
        );
        assert_eq!(TraceFormat::for_path(Path::new("t.txt")), TraceFormat::Text);
        assert_eq!(TraceFormat::for_path(Path::new("-")), TraceFormat::Text);
    }
}
