//! The bus holds a transaction's telegrams off the line when they are alone on a clean line,
//! takes their frames directly and, where its events fall within the caller's horizon, runs
//! them in one go (`Bus::may_run_quick`); the pulse-exact bus never does, and takes every
//! transaction as its three events through the pulse decoder. Driven alike, the two must be
//! indistinguishable at every step: what `advance_before` returns, the time, the next event,
//! every trace record, the statistics, the process image, every slave and monitor, the pulses
//! recorded on the line. The drive mixes what changes the quick path's conditions: steps of
//! every length (horizons inside and between transactions), the PLC's output writes (new
//! output nibbles for watched slaves, which must end `advance_before` at their moment),
//! pulled slaves, power cuts, line noise switched on and off, one-shot pulse faults, the
//! line recording, and buttons pressed on the floor stations and the cabin panel (inputs the
//! slaves sample when a request reaches them).

use crate::common::*;
use asi_bus::lab::LabLift;
use asi_bus::{Stop, Watch};
use asi_phy::{FaultRates, PulseErrorRate, PulseFault, SimDuration, SimTime};
use proptest::prelude::*;

/// What the test does at one step.
#[derive(Clone, Debug)]
enum Act {
    Before(u64),
    To(u64),
    Write(usize, u16),
    Volts(f64),
    Pull(u8),
    Noise(u64, f64),
    Quiet,
    Corrupt(usize),
    Record(bool),
    Buttons(u8, bool, bool),
    CabinButton(u8, bool),
}

fn act() -> impl Strategy<Value = Act> {
    prop_oneof![
        8 => (1u64..2_000).prop_map(Act::Before),
        4 => (1u64..2_000).prop_map(Act::To),
        3 => (0usize..244, any::<u16>()).prop_map(|(i, v)| Act::Write(i, v)),
        1 => prop_oneof![Just(0.0), Just(20.0), Just(30.0)].prop_map(Act::Volts),
        1 => (1u8..13).prop_map(Act::Pull),
        1 => (any::<u64>(), 0.001f64..0.05).prop_map(|(s, r)| Act::Noise(s, r)),
        1 => Just(Act::Quiet),
        1 => (0usize..20).prop_map(Act::Corrupt),
        1 => any::<bool>().prop_map(Act::Record),
        2 => (1u8..5, any::<bool>(), any::<bool>()).prop_map(|(f, u, d)| Act::Buttons(f, u, d)),
        2 => (1u8..5, any::<bool>()).prop_map(|(f, p)| Act::CabinButton(f, p)),
    ]
}

/// Everything the two buses must agree on.
fn state(lab: &mut LabLift) -> String {
    let bus = lab.bus_mut();
    let trace = bus.drain_trace();
    let pulses = bus.take_line_pulses();
    let mut s = format!(
        "now {} next {} stats {:?} image {:?} trace {trace:?} pulses {pulses:?}\n",
        bus.now(),
        bus.poll_at(),
        bus.stats(),
        bus.image(),
    );
    for id in bus.slave_ids() {
        s += &format!("{:?}\n", bus.slave(id));
    }
    s += &format!("{:?}", lab.monitor());
    s
}

fn step(lab: &mut LabLift, now: &mut SimTime, a: &Act) -> Option<Stop> {
    match *a {
        Act::Before(us) => {
            let until = *now + SimDuration::from_micros(us);
            let r = lab.bus_mut().advance_before(until);
            *now = match r {
                Some(Stop::Output(t) | Stop::Look(t)) => t,
                None => until,
            };
            return r;
        }
        Act::To(us) => {
            *now += SimDuration::from_micros(us);
            lab.bus_mut().advance_to(*now);
        }
        Act::Write(i, v) => lab.bus_mut().image_mut().output.set_word(i, v),
        Act::Volts(v) => lab.bus_mut().set_supply_voltage(v),
        Act::Pull(n) => {
            if let Some(id) = lab.slave_id(n) {
                if lab.bus().is_attached(id) {
                    lab.bus_mut().detach(id);
                } else {
                    lab.bus_mut().attach(id);
                }
            }
        }
        Act::Noise(seed, rate) => lab.bus_mut().set_line_faults(
            seed,
            FaultRates::uniform(PulseErrorRate::new(rate).expect("a probability")),
        ),
        Act::Quiet => lab.bus_mut().set_line_faults(0, FaultRates::NONE),
        Act::Corrupt(i) => lab
            .bus_mut()
            .corrupt_next_telegram(vec![PulseFault::Drop { index: i }]),
        Act::Record(on) => lab.bus_mut().record_line(on),
        Act::Buttons(floor, up, down) => {
            if let Some(f) = lab.floor_mut(floor) {
                f.set_buttons(up, down);
            }
        }
        Act::CabinButton(floor, pressed) => {
            if let Some(p) = lab.cabin_panel_mut() {
                p.set_floor_button(floor, pressed);
            }
        }
    }
    None
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn quick_transactions_are_the_three_events(
        start_ms in 0u64..60,
        watch in prop_oneof![Just(0b0100_1011_1110u32), Just(0), any::<u32>()],
        acts in proptest::collection::vec(act(), 1..300),
    ) {
        let mut quick = LabLift::new().expect("lab");
        let mut exact = LabLift::new().expect("lab");
        exact.bus_mut().set_pulse_exact(true);
        for lab in [&mut quick, &mut exact] {
            // The rig's watch (the floor stations, the cabin display, the converter, the set
            // point), none, or any.
            lab.bus_mut().watch(Watch {
                outputs: watch,
                ..Watch::default()
            });
            lab.bus_mut().enable_trace(1 << 20);
            lab.bus_mut().advance_to(ms(start_ms));
        }
        let (mut tq, mut te) = (ms(start_ms), ms(start_ms));
        prop_assert_eq!(state(&mut quick), state(&mut exact));
        for (k, a) in acts.iter().enumerate() {
            let rq = step(&mut quick, &mut tq, a);
            let re = step(&mut exact, &mut te, a);
            prop_assert_eq!(rq, re, "step {} {:?}", k, a);
            prop_assert_eq!(state(&mut quick), state(&mut exact), "step {} {:?}", k, a);
        }
    }
}
