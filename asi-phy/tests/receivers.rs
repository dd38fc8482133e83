//! The bus merges slaves whose receivers have come to the same state (asi-bus src/bus/mod.rs, comparing
//! `Listener`s). Merging pays because it happens all the time: after a frame, a `Listener`'s
//! state depends only on the frame, the kind it took it for and whether it is synchronised.
//! Checked here on noisy traffic: any two listeners that agree on those two after the same
//! frame are equal.

use asi_phy::{
    BusTiming, Expect, FaultInjector, FaultRates, LineDecoder, Listener, Nibble, Pulse, PulseTrain,
    Request, Response, SimTime, TelegramKind,
};

#[test]
fn listeners_that_agree_on_kind_and_sync_are_identical() {
    let t = BusTiming::default();
    let cfg = t.receiver(Expect::Both);
    let mut inj = FaultInjector::new(
        7,
        FaultRates::uniform(asi_phy::PulseErrorRate::new(0.02).expect("a probability")),
        t.half_bit(),
    );
    let mut line = LineDecoder::new(&cfg);
    // Listeners that joined the line at different times.
    let mut ls: Vec<Listener> = Vec::new();
    let mut frames = Vec::new();
    let mut buf: Vec<Pulse> = Vec::new();
    let mut at = 0u64;
    for k in 0..4000u32 {
        let req = Request::data_exchange(
            asi_phy::Address::new((k % 31 + 1) as u8).expect("a"),
            Nibble::from_low_bits(k as u8),
        )
        .expect("req");
        let rt = PulseTrain::request(req, SimTime::from_micros(at), t.half_bit());
        let st = PulseTrain::response(
            Response::new(Nibble::from_low_bits((k / 3) as u8)),
            SimTime::from_micros(at + 102),
            t.half_bit(),
        );
        for train in [rt, st] {
            inj.corrupt(train.iter(), &mut buf);
            for p in &buf {
                frames.extend(line.push(*p));
            }
        }
        at += if k % 17 == 0 { 120 } else { 154 };
    }
    frames.extend(line.flush());
    let mut merges = 0;
    for (i, f) in frames.iter().enumerate() {
        if i % 97 == 0 {
            ls.push(Listener::new(&cfg));
        }
        let keys: Vec<(bool, bool)> = ls
            .iter_mut()
            .map(|l| {
                let r = l.accept(f);
                (r.kind == TelegramKind::Request, l.is_synchronised())
            })
            .collect();
        for x in 0..ls.len() {
            for y in 0..x {
                if keys[x] == keys[y] {
                    assert_eq!(ls[x], ls[y], "frame {i}");
                    merges += 1;
                }
            }
        }
    }
    assert!(merges > 1000, "{merges}");
}
