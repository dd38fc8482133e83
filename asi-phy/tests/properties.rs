//! Property tests: no input makes the receiver, the demodulator or the capture reader panic,
//! streaming gives the same result however the input is cut, and jitter within the tolerance
//! never changes a telegram.

use asi_phy::waveform::{read_capture, DemodConfig, Demodulator};
use asi_phy::{
    BusTiming, Expect, Polarity, Pulse, PulseTrain, Received, Receiver, Request, SimDuration,
    SimTime,
};
use proptest::prelude::*;

fn polarity() -> impl Strategy<Value = Polarity> {
    prop_oneof![Just(Polarity::Negative), Just(Polarity::Positive)]
}

/// Pulses with arbitrary times: anywhere, near the grid, or going back in time.
fn pulse_sequence() -> impl Strategy<Value = Vec<Pulse>> {
    let step = prop_oneof![
        3 => (2_500u64..3_500).prop_map(|d| d as i64),
        2 => (5_500u64..6_500).prop_map(|d| d as i64),
        1 => (0u64..40_000).prop_map(|d| d as i64),
        1 => -5_000i64..0,
        1 => any::<u32>().prop_map(|d| d as i64),
    ];
    prop::collection::vec((step, polarity()), 0..300).prop_map(|steps| {
        let mut t = 1u64 << 40;
        steps
            .into_iter()
            .map(|(d, p)| {
                t = t.saturating_add_signed(d);
                Pulse::new(SimTime::from_nanos(t), p)
            })
            .collect()
    })
}

fn expect() -> impl Strategy<Value = Expect> {
    prop_oneof![
        Just(Expect::Requests),
        Just(Expect::Responses),
        Just(Expect::Both)
    ]
}

fn request() -> impl Strategy<Value = Request> {
    (0u16..1 << 11).prop_map(|body| {
        Request::from_bits((body << 2) | (((body.count_ones() & 1) as u16) << 1) | 1)
            .expect("valid")
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn the_receiver_never_panics_and_accounts_for_every_pulse(pulses in pulse_sequence(), expect in expect()) {
        let mut rx = Receiver::new(BusTiming::default().receiver(expect));
        let got: Vec<Received> = rx.decode(pulses.iter().copied()).collect();
        let counted: u64 = got.iter().map(|g| g.pulses as u64).sum();
        prop_assert_eq!(counted, pulses.len() as u64);
        for g in &got {
            prop_assert!(g.start <= g.end || !g.failed.is_empty());
            if g.is_valid() {
                prop_assert!(g.request().is_some() || g.response().is_some());
            }
        }
    }

    #[test]
    fn decoding_slices_equals_pushing_each_pulse(pulses in pulse_sequence(), cuts in prop::collection::vec(0usize..300, 0..6), expect in expect()) {
        let cfg = BusTiming::default().receiver(expect);
        let one: Vec<Received> = Receiver::new(cfg).decode(pulses.iter().copied()).collect();
        let mut rx = Receiver::new(cfg);
        let mut sliced = Vec::new();
        let mut cuts: Vec<usize> = cuts.into_iter().map(|c| c.min(pulses.len())).collect();
        cuts.push(0);
        cuts.push(pulses.len());
        cuts.sort_unstable();
        for w in cuts.windows(2) {
            rx.push_slice(&pulses[w[0]..w[1]], |r| sliced.push(r));
        }
        sliced.extend(rx.flush());
        prop_assert_eq!(one, sliced);
    }

    #[test]
    fn polling_between_pulses_changes_nothing(pulses in pulse_sequence(), polls in prop::collection::vec(0u64..20_000, 0..300)) {
        let cfg = BusTiming::default().receiver(Expect::Both);
        let plain: Vec<Received> = Receiver::new(cfg).decode(pulses.iter().copied()).collect();
        let mut rx = Receiver::new(cfg);
        let mut polled = Vec::new();
        for (i, p) in pulses.iter().enumerate() {
            // Poll at some moment before this pulse (never after it: time goes forward).
            if let Some(d) = polls.get(i) {
                let before = p.at - SimDuration::from_nanos(*d);
                if let Some(r) = rx.poll(before) {
                    polled.push(r);
                }
            }
            polled.extend(rx.push(*p));
        }
        polled.extend(rx.flush());
        // Polling can only complete a telegram the next pulse would have completed anyway,
        // unless pulses go back in time; compare on sequences that go forward.
        if pulses.windows(2).all(|w| w[0].at <= w[1].at) {
            prop_assert_eq!(plain, polled);
        }
    }

    #[test]
    fn jitter_within_the_tolerance_never_changes_a_telegram(req in request(), jitter in prop::collection::vec(-250i64..=250, 29)) {
        // The tolerance (±0.5 µs) is measured from the first pulse, which may itself be late:
        // pulse jitter of ±0.25 µs against an ideal clock is always accepted.
        let t = BusTiming::default();
        let train = PulseTrain::request(req, SimTime::from_micros(50), t.half_bit());
        let pulses: Vec<Pulse> = train
            .iter()
            .zip(&jitter)
            .map(|(p, j)| Pulse::new(SimTime::from_nanos(p.at.as_nanos().saturating_add_signed(*j)), p.polarity))
            .collect();
        let got: Vec<Received> = Receiver::new(t.receiver(Expect::Requests)).decode(pulses).collect();
        prop_assert_eq!(got.len(), 1);
        prop_assert_eq!(got[0].request(), Some(req));
    }

    #[test]
    fn the_demodulator_never_panics_and_streams_like_one_buffer(
        samples in prop::collection::vec(prop_oneof![
            8 => -10.0f32..10.0,
            1 => prop::num::f32::ANY,
        ], 0..4000),
        cuts in prop::collection::vec(0usize..4000, 0..8),
        period in prop_oneof![Just(100.0f64), 0.5f64..1000.0],
        nominal in 0.1f32..8.0,
    ) {
        let cfg = {
            let mut cfg = DemodConfig::default();
            cfg.nominal_amplitude = nominal;
            cfg
        };
        let mut whole = Vec::new();
        let mut d = Demodulator::new(cfg, SimTime::ZERO, period).expect("valid settings");
        d.push(&samples, |p| whole.push(p));
        d.finish(|p| whole.push(p));
        prop_assert!(whole.windows(2).all(|w| w[0].at <= w[1].at));

        // The same samples in pieces: the baseline starts from the first piece only, so compare
        // with a fixed baseline.
        let fixed = {
            let mut config = cfg;
            config.baseline_tau = SimDuration::ZERO;
            config
        };
        let mut one = Vec::new();
        let mut d = Demodulator::new(fixed, SimTime::ZERO, period).expect("valid");
        d.push(&samples, |p| one.push(p));
        d.finish(|p| one.push(p));
        let mut cuts = cuts;
        cuts.push(0);
        cuts.push(samples.len());
        cuts.sort_unstable();
        let mut pieces = Vec::new();
        let mut d = Demodulator::new(fixed, SimTime::ZERO, period).expect("valid");
        for w in cuts.windows(2) {
            let (a, b) = (w[0].min(samples.len()), w[1].min(samples.len()));
            d.push(&samples[a..b], |p| pieces.push(p));
        }
        d.finish(|p| pieces.push(p));
        prop_assert_eq!(one, pieces);
    }

    #[test]
    fn the_capture_reader_never_panics(text in "[0-9eE.,;+\\- \t\n#a-z]{0,400}") {
        let _ = read_capture(&text);
    }
}
