//! What `asi-lift run` writes, `asi-lift decode` reads back: the VCD's `manchester` wire (the
//! whole run), its `line_voltage` real and the CSV (the waveform window) decode to exactly the
//! telegrams of the JSON-lines trace, at the same nanoseconds.

use asi_lift_tests::Shared;
use asi_phy::{Nibble, Request, Response, SimDuration};
use asi_trace::capture::{decode_capture, DecodeOptions};
use asi_trace::telegrams::TelegramRecord;
use asi_trace::trace::TraceFormat;
use rig::report::{LogEvent, RigNote};
use rig::rig::Rig;
use rig::scenario::Scenario;
use rig::waves::WaveOutputs;

/// The telegrams of a JSON-lines trace: each request at its start, each response 102 µs later
/// (84 µs of request and the 18 µs master pause, docs/physical-layer.md).
fn telegrams_of_trace(jsonl: &[u8]) -> Vec<TelegramRecord> {
    let mut out = Vec::new();
    for line in String::from_utf8_lossy(jsonl).lines() {
        let v: serde_json::Value = serde_json::from_str(line).expect("a JSON line");
        let t = v["t_ns"].as_i64().expect("t_ns");
        let bits = |s: &serde_json::Value| u16::from_str_radix(s.as_str().expect("bits"), 2);
        let req = Request::from_bits(bits(&v["request"]["bits"]).expect("bits")).expect("request");
        out.push(TelegramRecord::request(t, req));
        if !v["response"].is_null() {
            let data =
                u8::from_str_radix(v["response"]["data"].as_str().expect("data"), 2).expect("data");
            let resp = Response::new(Nibble::from_low_bits(data));
            assert_eq!(v["response"]["bits"], format!("{:07b}", resp.bits()));
            out.push(TelegramRecord::response(t + 102_000, resp));
        }
    }
    out
}

#[test]
fn decode_returns_the_telegrams_of_the_trace() {
    let (trace, vcd, csv) = (Shared::default(), Shared::default(), Shared::default());
    let mut rig = Rig::new(Scenario::demo().expect("the demo")).expect("rig");
    rig.trace_to(Box::new(trace.clone()), TraceFormat::Jsonl);
    // The default window: the line is idle before the master starts at 5 ms, so a receiver
    // reading it is synchronised from the first telegram. (A window that opens in the middle
    // of a telegram leaves the receiver out of step until a pause of 18 µs, as on a real line.)
    let window = rig::waves::DEFAULT_WINDOW;
    rig.waves_to(WaveOutputs {
        vcd: Some(Box::new(vcd.clone())),
        csv: Some(Box::new(csv.clone())),
        window,
        pulse_window: None,
    });
    let report = rig.run(Some(SimDuration::from_millis(300)));
    assert_eq!(rig_errors(&report), None);
    let want = telegrams_of_trace(&trace.bytes());
    assert!(want.len() > 3000, "{}", want.len());

    // The whole run from the wire.
    let wire = decode_capture(vcd.bytes().as_slice(), &{
        let mut cfg = DecodeOptions::default();
        cfg.signal = Some("manchester".into());
        cfg
    })
    .expect("decode the wire");
    // The request in flight at the end is on the line but not yet in the trace.
    let last = want.last().map_or(0, |t| t.t_ns);
    let got: Vec<_> = wire
        .telegrams
        .into_iter()
        .filter(|t| t.t_ns <= last)
        .collect();
    assert_eq!(got.len(), want.len());
    assert_eq!(got, want);

    // The window, from the line voltage in the VCD and from the CSV.
    let (from, until) = (
        window.0.as_nanos() as i64,
        window.1.as_nanos() as i64 - 200_000,
    );
    let in_window: Vec<_> = want
        .iter()
        .filter(|t| t.t_ns >= from && t.t_ns < until)
        .cloned()
        .collect();
    assert!(in_window.len() > 50, "{}", in_window.len());
    let voltage = decode_capture(vcd.bytes().as_slice(), &{
        let mut cfg = DecodeOptions::default();
        cfg.signal = Some("rig.bus.line_voltage".into());
        cfg
    })
    .expect("decode the line voltage");
    let from_csv =
        decode_capture(csv.bytes().as_slice(), &DecodeOptions::default()).expect("decode the CSV");
    for (what, decoded) in [("VCD line_voltage", voltage), ("CSV", from_csv)] {
        let got: Vec<_> = decoded
            .telegrams
            .into_iter()
            .filter(|t| t.t_ns >= from && t.t_ns < until)
            .collect();
        assert_eq!(got, in_window, "{what}");
    }
}

fn rig_errors(r: &rig::report::Report) -> Option<String> {
    r.log.iter().find_map(|l| match &l.event {
        LogEvent::Note(RigNote::TraceNotWritten(e)) => Some(e.clone()),
        _ => None,
    })
}
