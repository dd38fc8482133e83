//! Tests of capture decoding: worked captures, every receiver error class, and property tests.

use super::render::{seconds, summary, to_json_lines, to_text};
use super::*;
use crate::telegrams::TelegramType;
use asi_phy::waveform::{render, WaveformConfig};
use asi_phy::{Address, Nibble, PulseTrain, Request, Response};
use core::ops::ControlFlow;
use proptest::prelude::*;
use std::fmt::Write as _;

/// docs/physical-layer.md worked vectors: Data_Exchange 5 out=1010 from 10 µs, then the response 0110
/// 18 µs after the request's last pulse (94 µs).
fn spec_records() -> Vec<TelegramRecord> {
    vec![
        TelegramRecord {
            t_ns: 10_000,
            kind: TelegramType::Request,
            bits: "00001010101001".into(),
            call: Some("Data_Exchange"),
            address: Some(5),
            info: Some("01010".into()),
            data: None,
            errors: vec![],
        },
        TelegramRecord {
            t_ns: 112_000,
            kind: TelegramType::Response,
            bits: "0011001".into(),
            call: None,
            address: None,
            info: None,
            data: Some("0110".into()),
            errors: vec![],
        },
    ]
}

/// Pulses in docs/physical-layer.md notation (`0- 1+ ..`, grid points of 3 µs) from `start_us`.
fn spec_pulses(spec: &str, start_us: u64) -> Vec<Pulse> {
    spec.split_whitespace()
        .map(|tok| {
            let (k, sign) = tok.split_at(tok.len() - 1);
            let k: u64 = k.parse().expect("grid point");
            let polarity = if sign == "+" {
                Polarity::Positive
            } else {
                Polarity::Negative
            };
            Pulse::new(SimTime::from_micros(start_us + 3 * k), polarity)
        })
        .collect()
}

/// The line voltage of [`spec_line`]'s two telegrams, 170 µs, default waveform.
fn spec_waveform() -> Waveform {
    render(
        spec_line(),
        SimTime::ZERO,
        SimTime::from_micros(170),
        &WaveformConfig::default(),
    )
    .expect("render")
}

fn spec_line() -> Vec<Pulse> {
    let mut p = spec_pulses(
        "0- 1+ 2- 3+ 4- 5+ 6- 7+ 9- 11+ 13- 15+ 17- 19+ 21- 23+ 24- 25+ 27- 28+",
        10,
    );
    p.extend(spec_pulses(
        "0- 1+ 2- 3+ 5- 6+ 7- 9+ 10- 11+ 13- 14+",
        94 + 18,
    ));
    p
}

/// A wire VCD as asi-lift writes one: the idle level in `$dumpvars`, then one record per
/// pulse, `ticks_per_ns` units per nanosecond (a fraction for coarse timescales).
fn wire_vcd(pulses: &[Pulse], timescale: &str, ticks_per_ns: f64) -> String {
    let mut s = format!(
        "$timescale {timescale} $end\n$scope module rig $end\n$scope module bus $end\n\
         $var wire 1 ! line $end\n$upscope $end\n$upscope $end\n$enddefinitions $end\n\
         #0\n$dumpvars\n1!\n$end\n"
    );
    for p in pulses {
        let t = (p.at.as_nanos() as f64 * ticks_per_ns).round() as u64;
        let v = u8::from(p.polarity == Polarity::Positive);
        let _ = writeln!(s, "#{t}\n{v}!");
    }
    s
}

fn decode(text: &str, opts: &DecodeOptions) -> Result<Decoded, DecodeError> {
    decode_capture(text.as_bytes(), opts)
}

fn telegrams(text: &str) -> Vec<TelegramRecord> {
    decode(text, &DecodeOptions::default())
        .expect("decodes")
        .telegrams
}

/// The worked vectors by hand: a logic analyser's view of the comparator output in µs.
const SPEC_WIRE_VCD: &str = "\
$date asi-lift test $end
$version hand-written $end
$comment docs/physical-layer.md worked vectors: Data_Exchange 5 out=1010, response 0110 $end
$timescale 1 us $end
$scope module rig $end
$scope module bus $end
$var wire 1 ! line $end
$upscope $end
$upscope $end
$enddefinitions $end
$dumpvars
1!
$end
#10 0!
#13 1!
#16 0!
#19 1!
#22 0!
#25 1!
#28 0!
#31 1!
#37 0!
#43 1!
#49 0!
#55 1!
#61 0!
#67 1!
#73 0!
#79 1!
#82 0!
#85 1!
#91 0!
#94 1!
$comment response 18 us after the last pulse $end
#112 0!
#115 1!
#118 0!
#121 1!
#127 0!
#130 1!
#133 0!
#139 1!
#142 0!
#145 1!
#151 0!
#154 1!
";

#[test]
fn a_wire_vcd_of_the_spec_vectors_decodes_to_them() {
    let d = decode(SPEC_WIRE_VCD, &DecodeOptions::default()).expect("decodes");
    assert_eq!(d.telegrams, spec_records());
    assert_eq!(d.pulses, 32);
    assert_eq!(
        d.source,
        CaptureSource::Wire {
            signal: "rig.bus.line".into()
        }
    );
    // The hand-written file holds the encoder's pulses.
    assert_eq!(
        telegrams(&wire_vcd(&spec_line(), "1 us", 1e-3)),
        spec_records()
    );
}

#[test]
fn the_timescale_gives_the_time_base() {
    for (ts, ticks_per_ns) in [
        ("1 us", 1e-3),
        ("10 ns", 0.1),
        ("1 ns", 1.0),
        ("100 ps", 10.0),
    ] {
        let got = telegrams(&wire_vcd(&spec_line(), ts, ticks_per_ns));
        assert_eq!(got, spec_records(), "{ts}");
    }
    // The same file read as 1 ms per unit: the telegrams are slow, not there.
    let slow = SPEC_WIRE_VCD.replace("1 us", "1 ms");
    assert!(telegrams(&slow).iter().all(|t| !t.is_valid()));
}

#[test]
fn a_real_vcd_rendered_from_the_pulses_decodes_the_same() {
    let wf = spec_waveform();
    // The voltage is written on change only; the wire rides along in the same file.
    let mut s = String::from(
        "$timescale 1 ns $end\n$scope module rig $end\n$scope module bus $end\n\
         $var real 64 % line_voltage $end\n$var wire 1 ! line $end\n\
         $upscope $end\n$upscope $end\n$enddefinitions $end\n#0\n$dumpvars r0 % 1! $end\n",
    );
    let mut last = 0.0;
    for (i, v) in wf.samples.iter().enumerate() {
        if *v != last {
            let _ = writeln!(s, "#{}\nr{v} %", 100 * i);
            last = *v;
        }
    }
    let _ = writeln!(s, "#170000\nr0 %");
    for signal in ["line_voltage", "bus.line_voltage", "rig.bus.line_voltage"] {
        let opts = DecodeOptions {
            signal: Some(signal.into()),
            ..DecodeOptions::default()
        };
        let d = decode(&s, &opts).expect("decodes");
        assert_eq!(d.telegrams, spec_records(), "{signal}");
        let CaptureSource::Voltage {
            samples, period_ns, ..
        } = d.source
        else {
            panic!("{:?}", d.source)
        };
        assert_eq!((samples, period_ns), (1701, 100.0));
    }
    // A grid finer than the changes holds each value over two samples: the line arrives
    // half a change spacing late, well inside the receiver's tolerance.
    let opts = DecodeOptions {
        signal: Some("line_voltage".into()),
        sample_period: Some(SimDuration::from_nanos(50)),
        ..DecodeOptions::default()
    };
    let late: Vec<TelegramRecord> = spec_records()
        .into_iter()
        .map(|t| TelegramRecord {
            t_ns: t.t_ns + 25,
            ..t
        })
        .collect();
    assert_eq!(decode(&s, &opts).expect("50 ns").telegrams, late);
}

#[test]
fn a_csv_with_a_header_and_comments_keeps_its_own_time() {
    // A scope on the 30 V supply whose record starts at 1 ms.
    let cfg = {
        let mut cfg = WaveformConfig::default();
        cfg.dc_offset = 30.0;
        cfg
    };
    let wf = render(spec_line(), SimTime::ZERO, SimTime::from_micros(170), &cfg).expect("render");
    let mut s = String::from("# exported by a scope\ntime_s,voltage_v\n");
    for (i, v) in wf.samples.iter().enumerate() {
        if i == 500 {
            s.push_str("# a comment among the samples\n");
        }
        let _ = writeln!(s, "{:.9},{v:.5}", 1e-3 + i as f64 * 1e-7);
    }
    let got = telegrams(&s);
    let want: Vec<TelegramRecord> = spec_records()
        .into_iter()
        .map(|t| TelegramRecord {
            t_ns: t.t_ns + 1_000_000,
            ..t
        })
        .collect();
    assert_eq!(got, want);
}

#[test]
fn a_repeated_level_is_a_pulse_so_a_line_fault_stays_visible() {
    // Pulse 6- of the request sent positive: three positive pulses in a row.
    let mut line = spec_line();
    line[6].polarity = Polarity::Positive;
    let got = telegrams(&wire_vcd(&line, "1 ns", 1.0));
    assert_eq!(
        got[0],
        TelegramRecord {
            t_ns: 10_000,
            kind: TelegramType::Request,
            bits: "00001010101001".into(),
            call: None,
            address: None,
            info: None,
            data: None,
            errors: vec!["alternation"],
        }
    );
}

#[test]
fn the_first_high_record_is_the_idle_line() {
    // A logic analyser writes the level at the start of its record, without `$dumpvars`.
    let analyser = SPEC_WIRE_VCD.replace("$dumpvars\n1!\n$end\n", "#0 1!\n");
    assert_eq!(telegrams(&analyser), spec_records());
}

#[test]
fn a_run_of_neither_length_is_unknown() {
    // A response with no request before it: a live-bus receiver waits for a request.
    let lone = spec_pulses("0- 1+ 2- 3+ 5- 6+ 7- 9+ 10- 11+ 13- 14+", 5);
    let got = telegrams(&wire_vcd(&lone, "1 ns", 1.0));
    assert_eq!(got.len(), 1);
    assert_eq!(
        (got[0].kind, got[0].bits.as_str(), got[0].errors.as_slice()),
        (TelegramType::Unknown, "0011001", &["length"][..])
    );
    let d = Decoded {
        telegrams: got,
        pulses: 12,
        source: CaptureSource::Wire { signal: "l".into() },
    };
    assert!(to_text(&d).contains("unknown   0011001"), "{}", to_text(&d));
}

#[test]
fn json_lines_carry_the_trace_fields() {
    let d = decode(SPEC_WIRE_VCD, &DecodeOptions::default()).expect("decodes");
    let json = to_json_lines(&d).expect("serialises");
    let lines: Vec<serde_json::Value> = json
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON"))
        .collect();
    assert_eq!(
        lines,
        [
            serde_json::json!({"t_ns": 10000, "type": "request", "bits": "00001010101001",
                "call": "Data_Exchange", "address": 5, "info": "01010", "data": null,
                "errors": []}),
            serde_json::json!({"t_ns": 112000, "type": "response", "bits": "0011001",
                "call": null, "address": null, "info": null, "data": "0110", "errors": []}),
        ]
    );
    let bad = TelegramRecord::received(
        -1500,
        &Receiver::new(BusTiming::default().receiver(Expect::Requests))
            .decode(spec_pulses("0- 1+ 2- 3+ 4- 5+ 6- 7+ 8- 9+ 10- 11+", 0))
            .next()
            .expect("a run"),
    );
    let v = serde_json::to_value(&bad).expect("JSON");
    assert_eq!(v["t_ns"], -1500);
    assert_eq!(v["type"], "unknown");
    assert_eq!(v["call"], serde_json::Value::Null);
    assert_eq!(v["errors"], serde_json::json!(["end_bit", "length"]));
}

#[test]
fn text_lines_and_the_summary() {
    let d = decode(SPEC_WIRE_VCD, &DecodeOptions::default()).expect("decodes");
    assert_eq!(
        to_text(&d),
        "        time_s  type      bits            call                   address  info   data  errors\n\
         \x20  0.000010000  request   00001010101001  Data_Exchange          5        01010  -     ok\n\
         \x20  0.000112000  response  0011001         -                      -        -      0110  ok\n\
         2 telegrams, 2 valid; 32 pulses from wire rig.bus.line\n"
    );
    assert_eq!(seconds(-1_500), "-0.000001500");
    assert_eq!(seconds(754_000_000_123), "754.000000123");
    let idle = "$var wire 1 ! line $end $enddefinitions $end\n#0 1!\n#100000\n";
    let d = decode(idle, &DecodeOptions::default()).expect("idle");
    assert_eq!(to_text(&d), "no telegrams found; 0 pulses from wire line\n");
}

/// Each bad input: its error and line.
#[test]
fn every_bad_capture_names_the_line() {
    let head = "$timescale 1 ns $end\n$var wire 1 ! line $end\n";
    let cases: Vec<(String, usize, &str)> = vec![
        (String::new(), 1, "the file is empty"),
        (
            "time_s,voltage\n".into(),
            1,
            "is a header and no `time,voltage` sample follows",
        ),
        (
            "0,1\n1e-7,1\n2e-7,1\nabc,1\n".into(),
            4,
            "`abc,1` is not two numbers",
        ),
        (
            "0,1\n1e-7,1\n2e-7".into(),
            3,
            "expected `time,voltage`, found `2e-7`",
        ),
        ("0,1\n2e-7,1\n1e-7,1\n".into(), 3, "does not increase"),
        (head.into(), 2, "no `$enddefinitions`"),
        (
            format!("{head}$enddefinitions $end\n#10 0!\n#5 1!\n"),
            5,
            "goes back",
        ),
        (
            format!("{head}$enddefinitions $end\n#10 0!\n#12 1\"\n"),
            5,
            "unknown identifier code `\"`",
        ),
        (
            format!("{head}$enddefinitions $end\n#10 0!\n#12 x!\n"),
            5,
            "line is `x` at #12",
        ),
        (
            format!("{head}$enddefinitions $end\n#10 0!\n#12 r1.5 !\n"),
            5,
            "holds a real",
        ),
        (
            "$var real 64 % v $end\n$enddefinitions $end\n#0 r0 %\n#10 r1e308 %\n".into(),
            4,
            "v (real): 1e308 is out of range: expected a finite voltage within ±3.4028235e38 V",
        ),
    ];
    for (text, line, cause) in cases {
        match decode(&text, &DecodeOptions::default()) {
            Err(DecodeError::File(e)) => {
                assert_eq!(e.line, line, "{text:?}: {e}");
                assert!(e.cause.contains(cause), "{text:?}: {e}");
            }
            other => panic!("{text:?}: {other:?}"),
        }
    }
    let not_text = b"0,1\n1e-7,1\n\xff\xfe,1\n";
    let e = decode_capture(&not_text[..], &DecodeOptions::default()).expect_err("binary");
    assert_eq!(e.to_string(), "line 3: not text (invalid UTF-8)");
}

#[test]
fn the_signal_is_named_and_must_carry_the_line() {
    let text = "$timescale 1 ns $end\n$scope module rig $end\n$scope module bus $end\n\
        $var wire 1 ! line $end\n$var real 64 \" line_voltage $end\n$upscope $end\n\
        $scope module plc $end\n$var wire 1 # line $end\n$var wire 4 $ word [3:0] $end\n\
        $var string 1 % state $end\n$upscope $end\n$upscope $end\n$enddefinitions $end\n";
    let named = |s: Option<&str>| {
        decode(
            text,
            &DecodeOptions {
                signal: s.map(String::from),
                ..DecodeOptions::default()
            },
        )
    };
    let all = "rig.bus.line (wire), rig.bus.line_voltage (real), rig.plc.line (wire), \
               rig.plc.word (wire, 4 bits), rig.plc.state (string)";
    assert_eq!(
        named(None).expect_err("several").to_string(),
        format!("several signals: choose one with --signal NAME; the file has: {all}")
    );
    assert_eq!(
        named(Some("volts")).expect_err("none").to_string(),
        format!("no signal `volts`; the file has: {all}")
    );
    assert_eq!(
        named(Some("line")).expect_err("two").to_string(),
        "`line` names several signals: rig.bus.line (wire), rig.plc.line (wire); give the \
         full path"
    );
    assert!(named(Some("bus.line")).is_ok());
    // One identifier code declared in two scopes is one signal.
    let aliased = text.replace("$var wire 1 # line", "$var wire 1 ! line");
    let alias = decode(
        &aliased,
        &DecodeOptions {
            signal: Some("line".into()),
            ..DecodeOptions::default()
        },
    );
    assert!(alias.is_ok(), "{alias:?}");
    assert!(named(Some("rig.plc.line")).is_ok());
    for (s, shown) in [
        ("word", "rig.plc.word (wire, 4 bits)"),
        ("state", "rig.plc.state (string)"),
    ] {
        assert_eq!(
            named(Some(s)).expect_err(s),
            DecodeError::Undecodable {
                signal: shown.into()
            }
        );
    }
}

/// asi-lift's own VCD holds many signals; without `--signal` its pulse wire, which holds the
/// whole run, is read, and a lookalike elsewhere in the file does not count.
#[test]
fn asi_lifts_own_vcd_is_read_from_its_pulse_wire() {
    let text = |path_of_wire: &str| {
        let (outer, inner) = path_of_wire.split_once('.').expect("scope.scope");
        format!(
            "$timescale 1 ns $end\n$scope module {outer} $end\n$scope module {inner} $end\n\
             $var wire 1 ! manchester $end\n$var real 64 \" line_voltage $end\n\
             $var wire 1 # repeat $end\n$upscope $end\n$upscope $end\n$enddefinitions $end\n\
             #0\n1!\n0#\n"
        )
    };
    let own = decode(&text("rig.bus"), &DecodeOptions::default()).expect("own VCD");
    assert_eq!(
        own.source,
        CaptureSource::Wire {
            signal: "rig.bus.manchester".into()
        }
    );
    let other = decode(&text("top.line"), &DecodeOptions::default());
    assert!(
        matches!(other, Err(DecodeError::NoSignal { wanted: None, .. })),
        "{other:?}"
    );
}

#[test]
fn the_format_comes_from_the_content_or_the_name() {
    assert_eq!(
        CaptureFormat::sniff(b"\n  $date x $end"),
        CaptureFormat::Vcd
    );
    assert_eq!(CaptureFormat::sniff(b"$comment\n"), CaptureFormat::Vcd);
    assert_eq!(CaptureFormat::sniff(b"# scope\n0,1\n"), CaptureFormat::Csv);
    assert_eq!(CaptureFormat::sniff(b""), CaptureFormat::Csv);
    assert_eq!(
        CaptureFormat::of_path(Path::new("run.VCD")),
        Some(CaptureFormat::Vcd)
    );
    assert_eq!(CaptureFormat::of_path(Path::new("scope.csv")), None);
    // A .vcd that holds CSV is read as a VCD and says what it found.
    let opts = DecodeOptions {
        format: Some(CaptureFormat::Vcd),
        ..DecodeOptions::default()
    };
    assert_eq!(
        decode("0,1\n", &opts).expect_err("not a VCD").to_string(),
        "line 1: `0,1` is no VCD command (they start with `$`)"
    );
}

#[test]
fn a_written_waveform_decodes_back() {
    let t = crate::encode::parse_call(&["rid1".into(), "7".into()]).expect("call");
    let csv = crate::encode::waveform_csv(t, &WaveformConfig::default()).expect("render");
    let d = decode(&csv, &DecodeOptions::default()).expect("decode");
    assert_eq!(d.telegrams.len(), 1);
    assert_eq!(d.telegrams[0].call, Some("Read_ID1"));
    assert!(to_text(&d).contains("1 telegram, 1 valid; 22 pulses from 1040 samples"));
}

proptest! {
    /// Valid requests, some answered, written as a wire VCD: decoded back to themselves at
    /// the simulator's nanosecond times.
    #[test]
    fn requests_in_a_wire_vcd_decode_back(
        calls in proptest::collection::vec(
            (any::<bool>(), 0u8..32, 0u8..32, proptest::option::of(0u8..16)),
            1..8,
        ),
        start in 0u64..1_000_000,
    ) {
        let h = BusTiming::default().half_bit();
        let mut pulses = Vec::new();
        let mut want = Vec::new();
        for (i, (cb, a, info, answer)) in calls.into_iter().enumerate() {
            let address = Address::new(a).expect("0..32");
            let q = Request::from_fields(cb, address, info).expect("5-bit info");
            let t = SimTime::from_nanos(start + 154_000 * i as u64);
            pulses.extend(PulseTrain::request(q, t, h));
            want.push(TelegramRecord::request(t.as_nanos() as i64, q));
            if let Some(d) = answer {
                let r = Response::new(Nibble::from_low_bits(d));
                let t = t + SimDuration::from_micros(84 + 18);
                pulses.extend(PulseTrain::response(r, t, h));
                want.push(TelegramRecord::response(t.as_nanos() as i64, r));
            }
        }
        prop_assert_eq!(telegrams(&wire_vcd(&pulses, "1 ns", 1.0)), want);
    }
}

/// The three kinds of capture of the spec vectors: a wire VCD, a real VCD, a CSV.
fn spec_captures() -> Vec<(String, DecodeOptions)> {
    let wf = spec_waveform();
    let mut csv = String::new();
    let mut real = String::from(
        "$timescale 1 ns $end\n$var real 64 % v $end\n$enddefinitions $end\n#0\n$dumpvars r0 % $end\n",
    );
    for (i, v) in wf.samples.iter().enumerate() {
        let _ = writeln!(csv, "{:.9},{v}", i as f64 * 1e-7);
        let _ = writeln!(real, "#{}\nr{v} %", 100 * i);
    }
    vec![
        (SPEC_WIRE_VCD.to_owned(), DecodeOptions::default()),
        (real, DecodeOptions::default()),
        (csv, DecodeOptions::default()),
    ]
}

#[test]
fn a_stream_hands_over_the_telegrams_in_order_as_the_whole_decode_has_them() {
    for (text, opts) in spec_captures() {
        let whole = decode(&text, &opts).expect("whole");
        assert_eq!(whole.telegrams, spec_records(), "{text:.40}");
        let mut got = Vec::new();
        let s = decode_stream(text.as_bytes(), &opts, |t| {
            got.push(t);
            ControlFlow::Continue(())
        })
        .expect("stream");
        assert_eq!(got, whole.telegrams);
        assert_eq!(s, whole.summary());
        // A sink that stops ends the decode after its telegram.
        let mut seen = 0;
        let s = decode_stream(text.as_bytes(), &opts, |_| {
            seen += 1;
            ControlFlow::Break(())
        })
        .expect("stopped");
        assert_eq!((seen, s.telegrams), (1, 1));
    }
}

/// A CSV capture made on the fly: `reps` repetitions of the spec vectors' 170 µs, one
/// sample every 100 ns, counting the bytes handed out.
struct Generated {
    window: Vec<f32>,
    reps: usize,
    /// The next sample's index over all repetitions.
    next: usize,
    line: Vec<u8>,
    pos: usize,
    produced: std::rc::Rc<std::cell::Cell<usize>>,
}

impl std::io::Read for Generated {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.pos == self.line.len() {
            if self.next == self.window.len() * self.reps {
                return Ok(0);
            }
            self.line.clear();
            let v = self.window[self.next % self.window.len()];
            let _ = std::io::Write::write_fmt(
                &mut self.line,
                format_args!("{:.9},{v}\n", self.next as f64 * 1e-7),
            );
            self.next += 1;
            self.pos = 0;
        }
        let n = buf.len().min(self.line.len() - self.pos);
        buf[..n].copy_from_slice(&self.line[self.pos..self.pos + n]);
        self.pos += n;
        self.produced.set(self.produced.get() + n);
        Ok(n)
    }
}

#[test]
fn a_capture_longer_than_the_prefix_streams_through_bounded_state() {
    let wf = spec_waveform();
    let window = wf.samples[..1700].to_vec();
    // Past the prefix, so most of the capture goes through without being held.
    let reps = PREFIX_SAMPLES / window.len() * 3 / 2;
    let produced = std::rc::Rc::new(std::cell::Cell::new(0));
    let input = std::io::BufReader::new(Generated {
        window,
        reps,
        next: 0,
        line: Vec::new(),
        pos: 0,
        produced: produced.clone(),
    });
    let want = spec_records();
    let mut n = 0usize;
    let mut first_at = None;
    // The sink checks each telegram as it comes and keeps nothing.
    let s = decode_stream(input, &DecodeOptions::default(), |t| {
        first_at.get_or_insert(produced.get());
        let w = &want[n % 2];
        let shift = (n / 2) as i64 * 170_000;
        assert_eq!(
            t,
            TelegramRecord {
                t_ns: w.t_ns + shift,
                ..w.clone()
            },
            "telegram {n}"
        );
        n += 1;
        ControlFlow::Continue(())
    })
    .expect("decodes");
    assert_eq!((n, s.telegrams, s.valid), (2 * reps, 2 * reps, 2 * reps));
    let CaptureSource::Voltage { samples, .. } = s.source else {
        panic!("{:?}", s.source)
    };
    assert_eq!(samples, 1700 * reps);
    // Telegrams came out while most of the input was still to be read: after the prefix,
    // not at the end.
    let first_at = first_at.expect("a telegram");
    assert!(
        first_at < produced.get() * 3 / 4,
        "first telegram after {first_at} of {} bytes",
        produced.get()
    );
}

#[test]
fn a_real_vcd_longer_than_the_prefix_is_gridded_as_it_comes() {
    let wf = spec_waveform();
    let window = &wf.samples[..1700];
    let reps = PREFIX_SAMPLES / window.len() * 2;
    // Written on change, so the grid's period comes from the prefix's smallest spacing and
    // the values are held between changes past it.
    let mut s = String::from(
        "$timescale 1 ns $end\n$var real 64 % v $end\n$enddefinitions $end\n#0\n$dumpvars r0 % $end\n",
    );
    let mut last = 0.0;
    let mut changes = 0;
    for i in 0..window.len() * reps {
        let v = window[i % window.len()];
        if v != last {
            let _ = writeln!(s, "#{}\nr{v} %", 100 * i);
            last = v;
            changes += 1;
        }
    }
    let _ = writeln!(s, "#{}\nr0 %", 100 * (window.len() * reps - 1));
    assert!(changes > PREFIX_SAMPLES, "{changes}");
    let mut n = 0;
    let want = spec_records();
    let sum = decode_stream(s.as_bytes(), &DecodeOptions::default(), |t| {
        let w = &want[n % 2];
        let shift = (n / 2) as i64 * 170_000;
        assert_eq!(t.t_ns, w.t_ns + shift, "telegram {n}");
        assert_eq!(t.bits, w.bits, "telegram {n}");
        n += 1;
        ControlFlow::Continue(())
    })
    .expect("decodes");
    assert_eq!((n, sum.valid), (2 * reps, 2 * reps));
    let CaptureSource::Voltage {
        samples, period_ns, ..
    } = sum.source
    else {
        panic!("{:?}", sum.source)
    };
    assert_eq!((samples, period_ns), (1700 * reps, 100.0));
}

#[test]
fn a_quiet_start_longer_than_the_prefix_waits_for_the_first_pulses() {
    // A line at 0 V for 0.15 s (more than the prefix), then the spec vectors every 170 µs
    // for 3.4 ms (pulses in more than 0.5 % of the samples after the prefix, as the estimate
    // needs).
    let wf = spec_waveform();
    let quiet = PREFIX_SAMPLES * 3 / 2;
    let mut s = String::new();
    for i in 0..quiet {
        let _ = writeln!(s, "{:.9},0", i as f64 * 1e-7);
    }
    let busy = 1700 * 20;
    for k in 0..busy {
        let v = wf.samples[k % 1700];
        let _ = writeln!(s, "{:.9},{v}", (quiet + k) as f64 * 1e-7);
    }
    let d = decode(&s, &DecodeOptions::default()).expect("decodes");
    let shift = (quiet as f64 * 100.0).round() as i64;
    let want: Vec<TelegramRecord> = (0..20)
        .flat_map(|k| {
            spec_records().into_iter().map(move |t| TelegramRecord {
                t_ns: t.t_ns + shift + k * 170_000,
                ..t
            })
        })
        .collect();
    assert_eq!(d.telegrams, want);
    let CaptureSource::Voltage {
        samples, nominal, ..
    } = d.source
    else {
        panic!("{:?}", d.source)
    };
    assert_eq!(samples, quiet + busy);
    assert!(
        nominal.is_some_and(|a| (a - 2.5).abs() < 0.25),
        "{nominal:?}"
    );
    // A line quiet to its end is flat.
    let quiet_only = s.lines().take(quiet).collect::<Vec<_>>().join("\n");
    let flat = decode(&quiet_only, &DecodeOptions::default()).expect("flat");
    assert!(flat.telegrams.is_empty());
    assert!(
        summary(&flat).ends_with("a flat line"),
        "{}",
        summary(&flat)
    );
}

/// A real VCD of the spec telegrams written on change: once from `#0`, then 20 times from
/// `#gap_ns` (enough for the amplitude's estimate), the line at 0 V between: one long flat
/// span.
fn real_vcd_with_a_gap(gap_ns: u64) -> String {
    let wf = spec_waveform();
    let mut s = String::from(
        "$timescale 1 ns $end\n$var real 64 % v $end\n$enddefinitions $end\n#0\n$dumpvars r0 % $end\n",
    );
    let mut last = 0.0;
    let origins = std::iter::once(0).chain((0..20).map(|k| gap_ns + k * 170_000));
    for origin in origins {
        for (i, v) in wf.samples.iter().enumerate().take(1700) {
            if *v != last {
                let _ = writeln!(s, "#{}\nr{v} %", origin + 100 * i as u64);
                last = *v;
            }
        }
    }
    let _ = writeln!(s, "#{}\nr0 %", gap_ns + 20 * 170_000);
    s
}

#[test]
fn a_long_flat_span_of_a_real_signal_is_run_through_at_once() {
    // 6.8e10 grid points at 100 ns: one at a time, about 18 minutes.
    for gap in [1_000_000_000, 1_000_000_000_000, 6_800_000_000_000] {
        let s = real_vcd_with_a_gap(gap);
        for nominal in [None, Some(2.5)] {
            let opts = DecodeOptions {
                nominal,
                ..DecodeOptions::default()
            };
            let d = decode(&s, &opts).expect("decodes");
            let origins = std::iter::once(0).chain((0..20).map(|k| (gap + k * 170_000) as i64));
            let want: Vec<TelegramRecord> = origins
                .flat_map(|origin| {
                    spec_records().into_iter().map(move |t| TelegramRecord {
                        t_ns: t.t_ns + origin,
                        ..t
                    })
                })
                .collect();
            // Past 10^12 ns the pulse times carry some tens of ns of float rounding.
            let slack = if gap > 1_000_000_000_000 { 50 } else { 0 };
            assert_eq!(
                d.telegrams.len(),
                want.len(),
                "gap {gap}, nominal {nominal:?}"
            );
            for (got, want) in d.telegrams.iter().zip(&want) {
                assert!((got.t_ns - want.t_ns).abs() <= slack, "{got:?} {want:?}");
                let got = TelegramRecord {
                    t_ns: want.t_ns,
                    ..got.clone()
                };
                assert_eq!(&got, want, "gap {gap}, nominal {nominal:?}");
            }
            let CaptureSource::Voltage { samples, .. } = d.source else {
                panic!("{:?}", d.source)
            };
            assert_eq!(samples as u64, (gap + 20 * 170_000) / 100 + 1, "gap {gap}");
        }
    }
    // The tiny VCD of a flat line that changes once, far out: a flat line, at once.
    let tiny = "$timescale 1 ns $end\n$var real 64 ! v $end\n$enddefinitions $end\n\
                #0\nr0 !\n#6800000000000\nr1 !\n";
    let d = decode(tiny, &DecodeOptions::default()).expect("decodes");
    assert!(d.telegrams.is_empty());
    assert!(summary(&d).ends_with("a flat line"), "{}", summary(&d));
}

/// Random and mutated bytes into the capture decoders (CSV, VCD): never a panic, an `Ok` or an
/// error of a line or two, in bounded time.
mod fuzz {
    use super::*;

    use asi_phy::testing::mutate;

    /// Small captures the project writes: a wire VCD, a real VCD and a CSV of the spec
    /// telegrams (the real VCD and the CSV cut to a few hundred samples, for speed).
    fn seeds() -> &'static [String] {
        static SEEDS: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
        SEEDS.get_or_init(|| {
            let mut v: Vec<String> = spec_captures().into_iter().map(|(s, _)| s).collect();
            for s in &mut v {
                if s.len() > 6000 {
                    let cut = s[..6000].rfind('\n').unwrap_or(0);
                    s.truncate(cut + 1);
                }
            }
            v
        })
    }

    fn check(bytes: &[u8], format: Option<CaptureFormat>) -> Result<(), TestCaseError> {
        let opts = DecodeOptions {
            format,
            ..DecodeOptions::default()
        };
        if let Err(e) = decode_capture(bytes, &opts) {
            let m = e.to_string();
            prop_assert!(m.len() < 600, "{} bytes: {}", m.len(), m);
        }
        Ok(())
    }

    fn formats() -> impl Strategy<Value = Option<CaptureFormat>> {
        prop_oneof![
            Just(None),
            Just(Some(CaptureFormat::Csv)),
            Just(Some(CaptureFormat::Vcd))
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(asi_phy::testing::fuzz_cases(500)))]

        #[test]
        fn mutated_captures_decode_or_are_refused_clearly(
            which in any::<prop::sample::Index>(),
            edits in prop::collection::vec((any::<u8>(), any::<usize>(), any::<u8>()), 1..6),
            format in formats(),
        ) {
            check(&mutate(which.get(seeds()).as_bytes(), &edits), format)?;
        }

        #[test]
        fn random_bytes_decode_or_are_refused_clearly(
            bytes in prop::collection::vec(any::<u8>(), 0..400),
            format in formats(),
        ) {
            check(&bytes, format)?;
        }

        #[test]
        fn random_vcd_like_text_decodes_or_is_refused_clearly(
            text in "\\$timescale 1 (ns|ps|s) \\$end\n\\$var (real 64|wire 1) ! v \\$end\n\
                     \\$enddefinitions \\$end\n(#[0-9]{1,16}\n|r-?[0-9.e]{1,8} !\n|[01xz]!\n){0,30}",
        ) {
            check(text.as_bytes(), None)?;
        }
    }
}
