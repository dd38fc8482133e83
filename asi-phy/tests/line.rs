//! The line's fast path for clean trains gives exactly the frames asi-phy's line decoder
//! gives, for every request and response, alone and back to back.

use asi_phy::line::{Line, Medium};
use asi_phy::{
    BusTiming, Expect, Frame, LineDecoder, Nibble, PulseTrain, Request, Response, SimTime,
};

fn both(trains: &[(PulseTrain, u32, u32)]) -> (Vec<Frame>, Vec<Frame>) {
    let t = BusTiming::default();
    let mut m = Medium::quiet(&t);
    let mut d = LineDecoder::new(&t.receiver(Expect::Both));
    let (mut fast, mut slow) = (Vec::new(), Vec::new());
    for (tr, raw, bits) in trains {
        m.transmit(tr, *raw, *bits, &mut |f| fast.push(f));
        slow.extend(d.push_train(tr));
    }
    fast.extend(m.poll(SimTime::MAX));
    slow.extend(d.flush());
    (fast, slow)
}

#[test]
fn every_clean_telegram_decodes_as_the_line_decoder_decodes_it() {
    let h = BusTiming::default().half_bit();
    let mut trains = Vec::new();
    let mut t = 0u64;
    for body in 0u16..1 << 11 {
        let bits = (body << 2) | (((body.count_ones() & 1) as u16) << 1) | 1;
        let req = Request::from_bits(bits).expect("valid");
        trains.push((
            PulseTrain::request(req, SimTime::from_micros(t), h),
            req.bits() as u32,
            14,
        ));
        let resp = Response::new(Nibble::from_low_bits(body as u8));
        trains.push((
            PulseTrain::response(resp, SimTime::from_micros(t + 102), h),
            resp.bits() as u32,
            7,
        ));
        // Now and then a gap too short to end a telegram: the trains overlap.
        t += if body % 13 == 0 { 146 } else { 154 };
    }
    let (fast, slow) = both(&trains);
    assert_eq!(fast.len(), slow.len());
    assert_eq!(fast, slow);
}
