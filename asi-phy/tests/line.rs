//! The line's fast path for clean trains gives exactly the frames asi-phy's line decoder
//! gives, for every request and response, alone and back to back.

use asi_phy::line::{Line, Medium};
use asi_phy::{
    BusTiming, Expect, FaultInjector, FaultRates, Frame, LineDecoder, Nibble, PulseErrorRate,
    Request, Response, SimDuration, SimTime, Transmission,
};

fn both(trains: &[Transmission]) -> (Vec<Frame>, Vec<Frame>) {
    let t = BusTiming::default();
    let mut m = Medium::quiet(&t);
    let mut d = LineDecoder::new(&t.receiver(Expect::Both));
    let (mut fast, mut slow) = (Vec::new(), Vec::new());
    for tg in trains {
        m.transmit(tg, &mut |f| fast.push(f));
        slow.extend(d.push_train(&tg.train()));
    }
    fast.extend(m.poll(SimTime::MAX));
    slow.extend(d.flush());
    (fast, slow)
}

#[test]
fn every_clean_telegram_decodes_as_the_line_decoder_decodes_it() {
    let trains = all_telegrams();
    let (fast, slow) = both(&trains);
    assert_eq!(fast.len(), slow.len());
    assert_eq!(fast, slow);
}

/// Every request and response back to back; now and then a gap too short to end a telegram,
/// so that the trains overlap.
fn all_telegrams() -> Vec<Transmission> {
    let h = BusTiming::default().half_bit();
    let mut trains = Vec::new();
    let mut t = 0u64;
    for body in 0u16..1 << 11 {
        let bits = (body << 2) | (((body.count_ones() & 1) as u16) << 1) | 1;
        let req = Request::from_bits(bits).expect("valid");
        trains.push(Transmission::request(req, SimTime::from_micros(t), h));
        let resp = Response::new(Nibble::from_low_bits(body as u8));
        trains.push(Transmission::response(
            resp,
            SimTime::from_micros(t + 102),
            h,
        ));
        t += if body % 13 == 0 { 146 } else { 154 };
    }
    trains
}

/// On a noisy line the trains the injector leaves untouched take the fast path, the others
/// go through the decoder: the frames are those of the pulse-exact line with the same seed,
/// for every rate from a quiet line to one where most telegrams are hit, with and without
/// jitter.
#[test]
fn a_noisy_line_gives_the_frames_of_the_pulse_exact_line() {
    let t = BusTiming::default();
    let trains = all_telegrams();
    for (seed, rate, jitter_ns) in [
        (1, 1e-4, 0),
        (2, 1e-3, 0),
        (3, 5e-3, 0),
        (4, 3e-2, 0),
        (5, 0.3, 0),
        (6, 1e-3, 200),
    ] {
        let frames = |exact: bool| {
            let mut m = Medium::quiet(&t);
            m.set_pulse_exact(exact);
            let mut rates = FaultRates::uniform(PulseErrorRate::new(rate).expect("a rate"));
            rates.jitter = SimDuration::from_nanos(jitter_ns);
            m.set_faults(Some(FaultInjector::new(seed, rates, t.half_bit())));
            let mut out = Vec::new();
            for tg in &trains {
                m.transmit(tg, &mut |f| out.push(f));
            }
            out.extend(m.poll(SimTime::MAX));
            (out, m.faults_injected())
        };
        let (fast, fast_faults) = frames(false);
        let (exact, exact_faults) = frames(true);
        assert!(fast_faults > 0, "rate {rate}: faults were injected");
        assert_eq!(fast_faults, exact_faults, "rate {rate}");
        assert_eq!(fast.len(), exact.len(), "rate {rate}");
        if let Some(i) = (0..fast.len()).find(|&i| fast[i] != exact[i]) {
            panic!(
                "rate {rate}: frame {i}: {:?} against {:?}",
                fast[i], exact[i]
            );
        }
    }
}
