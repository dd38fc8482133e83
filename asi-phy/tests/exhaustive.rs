//! Exhaustive tests over every valid telegram (issue: asi-phy "What it must show").
//!
//! - Every one of the 2^11 valid requests and 2^4 valid responses round-trips through bits,
//!   Manchester half-bits, APM pulses and the default waveform.
//! - Every single pulse fault on every valid telegram is reported by the receiver.

use asi_phy::fault::{apply_faults, single_faults};
use asi_phy::waveform::{render, DemodConfig, Demodulator, WaveformConfig};
use asi_phy::{
    BusTiming, Expect, HalfBits, Nibble, Pulse, PulseTrain, Received, Receiver, Request, Response,
    SimDuration, SimTime,
};

fn all_requests() -> impl Iterator<Item = Request> {
    (0u16..1 << 11).map(|body| {
        let bits = (body << 2) | (((body.count_ones() & 1) as u16) << 1) | 1;
        Request::from_bits(bits).expect("every 11-bit body with its parity is a request")
    })
}

fn all_responses() -> impl Iterator<Item = Response> {
    (0u8..16).map(|v| Response::new(Nibble::from_low_bits(v)))
}

/// Every valid telegram's pulse train, with the receiver setting that expects it.
fn all_trains() -> Vec<(PulseTrain, Expect)> {
    let h = BusTiming::default().half_bit();
    let start = SimTime::from_micros(100);
    all_requests()
        .map(|r| (PulseTrain::request(r, start, h), Expect::Requests))
        .chain(all_responses().map(|r| (PulseTrain::response(r, start, h), Expect::Responses)))
        .collect()
}

fn decode(pulses: &[Pulse], expect: Expect) -> Vec<Received> {
    Receiver::new(BusTiming::default().receiver(expect))
        .decode(pulses.iter().copied())
        .collect()
}

#[test]
fn every_request_round_trips_through_bits_manchester_pulses_and_waveform() {
    let timing = BusTiming::default();
    let h = timing.half_bit();
    let slot = timing.transaction();
    let requests: Vec<Request> = all_requests().collect();
    // All requests back to back, one per 154 µs slot, on one line.
    let mut pulses = Vec::new();
    for (i, r) in requests.iter().enumerate() {
        assert_eq!(Request::from_bits(r.bits()), Ok(*r));
        assert_eq!(HalfBits::from(*r).to_request(), Ok(*r));
        let start = SimTime::ZERO + SimDuration::from_micros(20) + slot.saturating_mul(i as u64);
        pulses.extend(PulseTrain::request(*r, start, h));
    }
    let by_pulses: Vec<Option<Request>> = decode(&pulses, Expect::Requests)
        .iter()
        .map(|g| g.request())
        .collect();
    assert_eq!(
        by_pulses,
        requests.iter().map(|r| Some(*r)).collect::<Vec<_>>()
    );

    let end = SimTime::ZERO + slot.saturating_mul(requests.len() as u64 + 1);
    let wf = render(
        pulses.iter().copied(),
        SimTime::ZERO,
        end,
        &WaveformConfig::default(),
    )
    .expect("render");
    let demodulated = Demodulator::demodulate(DemodConfig::default(), &wf).expect("demodulate");
    assert_eq!(
        demodulated, pulses,
        "the comparator must find every pulse at its exact time"
    );
}

#[test]
fn every_response_round_trips_through_bits_manchester_pulses_and_waveform() {
    let h = BusTiming::default().half_bit();
    for r in all_responses() {
        assert_eq!(HalfBits::from(r).to_response(), Ok(r));
        let train = PulseTrain::response(r, SimTime::from_micros(10), h);
        let pulses: Vec<Pulse> = train.iter().collect();
        let got = decode(&pulses, Expect::Responses);
        assert_eq!(got.len(), 1);
        assert_eq!(got[0].response(), Some(r));
        let wf = render(
            train,
            SimTime::ZERO,
            SimTime::from_micros(70),
            &WaveformConfig::default(),
        )
        .expect("render");
        assert_eq!(
            Demodulator::demodulate(DemodConfig::default(), &wf).expect("demod"),
            pulses
        );
    }
}

#[test]
fn every_single_pulse_fault_on_every_valid_telegram_is_detected() {
    let mut out = Vec::new();
    let mut checked = 0u64;
    let mut undetected = Vec::new();
    for (train, expect) in all_trains() {
        let pulses: Vec<Pulse> = train.iter().collect();
        for fault in single_faults(&train) {
            apply_faults(&pulses, &[fault], &mut out);
            let got = decode(&out, expect);
            checked += 1;
            if got.iter().all(|g| g.is_valid()) {
                undetected.push((train, fault, got));
            }
        }
    }
    // 2048 requests and 16 responses, about a hundred faults each.
    assert!(checked > 190_000, "{checked}");
    // No class of single fault escapes the seven checks: a drop, insert or flip always breaks
    // alternation (or the start or end pulse); a shift by one grid step moves a mid-bit pulse
    // off its cell's middle (information), moves the first or last pulse off the telegram's
    // span (length, end bit), or lands a boundary pulse on an occupied mid-bit point (pause).
    assert!(
        undetected.is_empty(),
        "undetected single faults: {undetected:?}"
    );
}
