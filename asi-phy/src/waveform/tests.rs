use super::*;
use crate::pulse::PulseTrain;
use crate::pulse::{Polarity, Pulse};
use crate::receiver::{Expect, Receiver};
use crate::telegram::{Address, Nibble, Request};
use crate::time::{SimDuration, SimTime};
use crate::timing::BusTiming;

fn dexg() -> Request {
    Request::data_exchange(Address::new(5).expect("a"), Nibble::from_low_bits(0b1010))
        .expect("valid")
}

fn train(at_us: u64) -> PulseTrain {
    PulseTrain::request(
        dexg(),
        SimTime::from_micros(at_us),
        BusTiming::default().half_bit(),
    )
}

fn decode(pulses: Vec<Pulse>) -> Vec<crate::receiver::Received> {
    Receiver::new(BusTiming::default().receiver(Expect::Requests))
        .decode(pulses)
        .collect()
}

#[test]
fn a_rendered_pulse_is_sin_squared_of_the_configured_amplitude() {
    let p = Pulse::new(SimTime::from_micros(10), Polarity::Negative);
    let wf = render(
        [p],
        SimTime::ZERO,
        SimTime::from_micros(20),
        &WaveformConfig::default(),
    )
    .expect("ok");
    assert_eq!(wf.samples.len(), 200);
    assert!(
        (wf.samples[100] + 2.5).abs() < 1e-6,
        "peak {}",
        wf.samples[100]
    );
    assert!((wf.samples[100 - 7] + 2.5 * 0.5).abs() < 0.2);
    assert_eq!(wf.samples[85], 0.0);
    assert_eq!(wf.samples[115], 0.0);
}

#[test]
fn demodulation_recovers_the_exact_pulse_times() {
    let t = train(20);
    let wf = render(
        t,
        SimTime::ZERO,
        SimTime::from_micros(120),
        &WaveformConfig::default(),
    )
    .expect("ok");
    let got = Demodulator::demodulate(DemodConfig::default(), &wf).expect("ok");
    let want: Vec<Pulse> = t.iter().collect();
    assert_eq!(got, want);
}

#[test]
fn works_on_a_capture_on_the_supply_with_noise_uneven_amplitude_and_odd_start() {
    // 30 V supply, 6 Vpp, 0.1 V RMS noise, 25 MS/s, a capture starting in mid telegram.
    let cfg = WaveformConfig {
        amplitude: 3.0,
        sample_period: SimDuration::from_nanos(40),
        noise_rms: 0.1,
        dc_offset: 30.0,
        seed: 3,
        ..WaveformConfig::default()
    };
    let mut pulses: Vec<Pulse> = train(0).iter().collect();
    pulses.extend(train(154));
    pulses.extend(train(308));
    let mut wf = render(
        pulses,
        SimTime::from_micros(40),
        SimTime::from_micros(420),
        &cfg,
    )
    .expect("ok");
    // The second telegram's pulses at 65 % (master must see 60 %): scale by hand.
    for (i, s) in wf.samples.iter_mut().enumerate() {
        let t = 40_000 + 40 * i as u64;
        if (154_000..240_000).contains(&t) {
            *s = 30.0 + (*s - 30.0) * 0.65;
        }
    }
    let demod = DemodConfig {
        nominal_amplitude: 3.0,
        ..DemodConfig::default()
    };
    let got = decode(Demodulator::demodulate(demod, &wf).expect("ok"));
    let valid: Vec<Option<Request>> = got.iter().map(|r| r.request()).collect();
    // The cut first telegram is broken; the next two are read.
    assert_eq!(valid.len(), 3, "{got:?}");
    assert_eq!(valid[0], None);
    assert_eq!(&valid[1..], &[Some(dexg()), Some(dexg())]);
}

#[test]
fn disturbances_below_30_percent_are_ignored() {
    let mut wf = render(
        train(20),
        SimTime::ZERO,
        SimTime::from_micros(200),
        &WaveformConfig::default(),
    )
    .expect("ok");
    // A 0.7 V (28 %) blip in the pause after the telegram.
    let blip = render(
        [Pulse::new(SimTime::from_micros(150), Polarity::Negative)],
        SimTime::ZERO,
        SimTime::from_micros(200),
        &WaveformConfig {
            amplitude: 0.7,
            ..WaveformConfig::default()
        },
    )
    .expect("ok");
    for (s, b) in wf.samples.iter_mut().zip(&blip.samples) {
        *s += b;
    }
    let got = decode(Demodulator::demodulate(DemodConfig::default(), &wf).expect("ok"));
    assert_eq!(got.len(), 1);
    assert_eq!(got[0].request(), Some(dexg()));
}

#[test]
fn a_noise_burst_corrupts_a_telegram_and_the_receiver_says_so() {
    let mut wf = render(
        train(20),
        SimTime::ZERO,
        SimTime::from_micros(120),
        &WaveformConfig::default(),
    )
    .expect("ok");
    wf.add_burst(
        &NoiseBurst {
            start: SimTime::from_micros(50),
            duration: SimDuration::from_micros(10),
            rms: 3.0,
        },
        9,
    );
    let got = decode(Demodulator::demodulate(DemodConfig::default(), &wf).expect("ok"));
    assert!(got.iter().all(|r| !r.is_valid()), "{got:?}");
}

#[test]
fn bad_settings_are_rejected_with_the_field() {
    let e = render(
        [],
        SimTime::ZERO,
        SimTime::ZERO,
        &WaveformConfig {
            amplitude: -1.0,
            ..WaveformConfig::default()
        },
    )
    .expect_err("negative amplitude");
    assert_eq!(e.field, "amplitude");
    let e = Demodulator::new(
        DemodConfig {
            threshold: 0.6,
            ..DemodConfig::default()
        },
        SimTime::ZERO,
        100.0,
    )
    .expect_err("threshold");
    assert_eq!(
        e.to_string(),
        "threshold = 0.6: must lie within 0.45..=0.55 of the first pulse"
    );
    assert!(Demodulator::new(DemodConfig::default(), SimTime::ZERO, f64::NAN).is_err());
}

#[test]
fn reads_a_capture_and_names_the_bad_line() {
    let cap = read_capture("Time,Ch1\n# scope export\n-1e-6,30.1\n-0.9e-6,30.2\n-0.8e-6,29.9\n")
        .expect("ok");
    assert_eq!(cap.waveform.samples, [30.1, 30.2, 29.9]);
    assert!((cap.waveform.period_ns - 100.0).abs() < 1e-6);
    assert_eq!(cap.first_time_s, -1e-6);
    let e = read_capture("0,1\n1e-7,1\nabc,2\n").expect_err("bad line");
    assert_eq!(
        (e.line, e.cause.as_str()),
        (3, "`abc,2` is not two numbers (seconds, volts)")
    );
    let e = read_capture("0,1\n1e-7,1\n3e-7,1\n4e-7,1\n").expect_err("uneven");
    assert_eq!(e.line, 3);
    let e = read_capture("0,1\n0,1\n").expect_err("not increasing");
    assert_eq!(e.line, 2);
}

#[test]
fn a_line_past_the_bound_is_refused_before_it_fills_memory() {
    // An endless line (`/dev/zero`): read only up to the bound, then refused at its line.
    let zeros = std::io::BufReader::new(std::io::repeat(0));
    let e = CaptureReader::open(zeros, 16).expect_err("endless line");
    assert_eq!(e.line, 1);
    assert!(e.cause.contains("longer than 1 MiB"), "{e}");
    // A long line after good samples, read as a stream.
    let text = format!("0,1\n1e-7,1\n2e-7,{}\n", "9".repeat(MAX_LINE_BYTES + 10));
    let (mut r, _) = CaptureReader::open(text.as_bytes(), 2).expect("prefix");
    let e = r.read(&mut Vec::new(), 10).expect_err("long line");
    assert_eq!(e.line, 3);
    assert!(e.cause.contains("longer than 1 MiB"), "{e}");
    // A long token in a line within the bound is quoted cut short.
    let text = format!("0,1\n1e-7,1\n2e-7 {}\n", "x".repeat(100_000));
    let e = read_capture(&text).expect_err("bad line");
    assert!(e.cause.len() < 200, "{e}");
    assert!(e.cause.contains("xxx…`"), "{e}");
}

#[test]
fn numbers_out_of_range_are_named_with_the_range_compactly() {
    let e = read_capture("0,1\n1e-7,1e308\n").expect_err("too large");
    assert_eq!(
        (e.line, e.cause.as_str()),
        (
            2,
            "voltage 1e308 V is out of range: expected a finite voltage within ±3.4028235e38 V"
        )
    );
    let e = read_capture("0,1\n1e400,1\n").expect_err("inf time");
    assert_eq!(
        e.cause,
        "time inf s is out of range: expected a finite time in seconds"
    );
    let e = read_capture("0,1\n1e300,1\n1e299,1\n").expect_err("back");
    assert_eq!(
        e.cause,
        "time 1e299 s does not increase (previous sample 1e300 s)"
    );
}

#[test]
fn a_capture_without_samples_says_why() {
    let cases = [
        ("", 1, "the file is empty"),
        ("\n  \n", 2, "the file is empty"),
        (
            "# scope\n#\n",
            2,
            "no samples: the file holds only comments",
        ),
        (
            "# export\ntime_s,voltage\n",
            2,
            "`time_s,voltage` is a header and no `time,voltage` sample follows",
        ),
        (
            "hello\nworld\nagain\n",
            1,
            "no samples: `hello` and the 2 lines after it are not `time,voltage` (seconds, volts)",
        ),
        (
            "t,v\n0,1\n",
            2,
            "only one sample: a capture needs two or more",
        ),
    ];
    for (text, line, cause) in cases {
        let e = read_capture(text).expect_err(text);
        assert_eq!((e.line, e.cause.as_str()), (line, cause), "{text:?}");
    }
}

#[test]
fn a_capture_read_as_a_stream_holds_a_prefix_and_reads_like_the_whole() {
    use super::CaptureReader;
    let mut text = String::from("time,volts\n");
    for i in 0..1000 {
        let _ = std::fmt::Write::write_fmt(
            &mut text,
            format_args!("{:.9},{}\n", i as f64 * 1e-7, (i % 7) as f32),
        );
    }
    let whole = read_capture(&text).expect("whole");
    let (mut r, head) = CaptureReader::open(text.as_bytes(), 10).expect("prefix");
    assert_eq!(head.waveform.samples.len(), 10);
    assert_eq!(head.first_time_s, whole.first_time_s);
    assert!((head.waveform.period_ns - whole.waveform.period_ns).abs() < 1e-6);
    let mut all = head.waveform.samples;
    let mut buf = Vec::new();
    loop {
        r.read(&mut buf, 64).expect("rest");
        assert!(buf.len() <= 64);
        if buf.is_empty() {
            break;
        }
        all.extend_from_slice(&buf);
    }
    assert_eq!(all, whole.waveform.samples);
    // A step after the prefix is judged against the prefix's median step.
    let bad = "0,1\n1e-7,1\n2e-7,1\n3e-7,1\n5e-7,1\n";
    let (mut r, _) = CaptureReader::open(bad.as_bytes(), 3).expect("prefix");
    let e = r.read(&mut buf, 64).expect_err("uneven");
    assert_eq!(e.line, 5);
}

#[test]
fn a_constant_span_pushed_at_once_demodulates_as_sample_by_sample() {
    let wf = render(
        train(20),
        SimTime::ZERO,
        SimTime::from_micros(120),
        &WaveformConfig::default(),
    )
    .expect("ok");
    // Telegram, a flat span on a raised level (the baseline must settle), an off-level span
    // held inside a lobe, the telegram again; both ways alike, pulse for pulse.
    let spans: [(f32, u64); 3] = [(1.0, 300_000), (-3.0, 50_000), (0.0, 400_000)];
    let run = |bulk: bool| {
        let mut d = Demodulator::for_waveform(DemodConfig::default(), &wf).expect("ok");
        let mut got = Vec::new();
        d.push(&wf.samples, |p| got.push(p));
        for (v, n) in spans {
            if bulk {
                d.push_constant(v, n, |p| got.push(p));
            } else {
                d.push(&vec![v; n as usize], |p| got.push(p));
            }
        }
        d.push(&wf.samples, |p| got.push(p));
        d.finish(|p| got.push(p));
        got
    };
    let (slow, fast) = (run(false), run(true));
    assert!(slow.len() > 2 * train(20).iter().count(), "{slow:?}");
    assert_eq!(fast, slow);
}
