//! Cycle time in simulation against T = (n + 2) · 154 µs (the lift thesis, §2.1, formula (1);
//! docs/master.md, §7).

use crate::common::*;
use asi_bus::Bus;
use asi_master::{MasterConfig, ProjectedConfig, ProjectedSlave};
use asi_phy::{Call, Nibble, PulseFault, SimDuration};
use asi_slaves::devices::{IoModule, AB_MODULE};
use asi_slaves::Slave;

fn settle(bus: &mut Bus) {
    bus.advance_to(ms(40));
    assert!(bus.is_running());
}

#[test]
fn cycle_is_n_plus_2_transactions_for_1_to_30_slaves_and_32_for_31() {
    for n in 1..=31u8 {
        let mut bus = io_bus(n);
        settle(&mut bus);
        let before = bus.stats();
        bus.advance_to(ms(140));
        let s = bus.stats();
        assert!(s.cycles > before.cycles + 10, "n = {n}");
        let want = if n <= 30 { n as u64 + 2 } else { 32 };
        assert_eq!(s.cycle_min, us(want * 154), "n = {n}");
        assert_eq!(s.cycle_max, us(want * 154), "n = {n}");
        assert_eq!(s.repeats, 0);
        // 31 slaves: 4.928 ms, within the lift thesis' "≤ 5 ms for 31 slaves".
        assert!(s.cycle_max <= SimDuration::from_millis(5));
    }
}

#[test]
fn each_repeat_adds_one_transaction_time() {
    let mut bus = io_bus(5);
    settle(&mut bus);
    bus.enable_trace(10_000);
    let cycle = 7 * 154;
    // Corrupt the request that follows a point in the middle of a transaction.
    let t = bus.now();
    bus.advance_to(t + us(100));
    bus.corrupt_next_telegram(vec![PulseFault::Flip { index: 7 }]);
    bus.advance_to(t + us(10 * cycle));
    let s = bus.stats();
    assert_eq!(s.repeats, 1);
    assert_eq!(s.cycle_min, us(cycle));
    assert_eq!(s.cycle_max, us(cycle + 154));
    let trace = bus.drain_trace();
    let i = trace
        .iter()
        .position(|r| r.repeat)
        .expect("a repeat in the trace");
    assert_eq!(trace[i].request, trace[i - 1].request);
    assert!(trace[i - 1].no_response);
    assert!(!trace[i - 1].request_failed.is_empty());
}

/// 62 A/B slaves: 31 slots + 1 management call a cycle (no inclusion address is left), and each
/// slave is served every second cycle: 64 · 154 µs = 9.856 ms (≤ 10 ms, §2.1 of the lift thesis).
#[test]
fn sixty_two_ab_slaves_see_twice_the_cycle() {
    let b_codes = asi_phy::SlaveCodes {
        id1: Nibble::from_low_bits(0xF),
        ..AB_MODULE
    };
    let mut projected = Vec::new();
    let mut slaves = Vec::new();
    for n in 1..=31u8 {
        for (sel, codes) in [(a(n), AB_MODULE), (b(n), b_codes)] {
            projected.push(ProjectedSlave {
                addr: sel,
                codes,
                parameter: Nibble::from_low_bits(7),
            });
            slaves.push(Slave::new(
                format!("{sel}"),
                addr(n),
                codes,
                Box::new(IoModule::new()),
            ));
        }
    }
    let p = ProjectedConfig::new(projected).expect("projection");
    let mut bus = Bus::new(MasterConfig::default(), p, slaves).expect("bus");
    bus.advance_to(ms(100));
    assert!(bus.is_running());
    assert_eq!(bus.master().las().len(), 62);
    assert!(bus.master().flags().config_ok());
    bus.image_mut()
        .output
        .set_nibble(a(5), Nibble::from_low_bits(0b0111));
    bus.image_mut()
        .output
        .set_nibble(b(5), Nibble::from_low_bits(0b1010));
    bus.enable_trace(100_000);
    let before = bus.stats().cycles;
    bus.advance_to(ms(200));
    let s = bus.stats();
    assert!(s.cycles > before + 10);
    assert_eq!(s.cycle_min, us(32 * 154));
    assert_eq!(s.cycle_max, us(32 * 154));
    let trace = bus.drain_trace();
    // Data_Exchange to address 5: A (I3 = 1) and B (I3 = 0) alternate, 32 transactions apart.
    let to5: Vec<_> = trace
        .iter()
        .filter(|r| matches!(r.request.call(), Call::DataExchange { address, .. } if address.get() == 5))
        .collect();
    let sel: Vec<bool> = to5.iter().map(|r| r.request.info() & 0b1000 != 0).collect();
    assert!(sel.windows(2).all(|w| w[0] != w[1]), "A and B alternate");
    for w in to5.windows(3) {
        assert_eq!(w[1].start - w[0].start, us(32 * 154));
        assert_eq!(w[2].start - w[0].start, SimDuration::from_micros(64 * 154));
    }
    assert!(to5.iter().all(|r| r.response.is_some()));
    let shown: Vec<String> = to5[..2].iter().map(|r| r.to_string()).collect();
    assert!(
        shown.iter().any(|l| l.contains("Data_Exchange 5A out=111")),
        "{shown:?}"
    );
    assert!(
        shown.iter().any(|l| l.contains("Data_Exchange 5B out=010")),
        "D3 of an A/B slave's nibble is not sent: {shown:?}"
    );
    // The outputs reached the right slave of the pair (slaves 8 and 9 are 5A and 5B).
    let out = |i: usize| {
        bus.device::<IoModule>(bus.slave_ids().nth(i).expect("a slave"))
            .expect("io")
            .outputs()
            .get()
    };
    assert_eq!((out(8), out(9)), (0b111, 0b010), "5A and 5B");
}

/// The lab lift with 20 extra I/O modules fills all 31 addresses: (31 + 1) · 154 µs, and with
/// 9 extra modules 20 slaves: (20 + 2) · 154 µs (docs/master.md).
#[test]
fn the_lab_bus_with_extra_modules_follows_the_same_formula() {
    use asi_bus::lab::LabLift;
    for (extra, want) in [(0u8, 13u64), (9, 22), (20, 32)] {
        let mut lab = LabLift::with_extra(MasterConfig::default(), extra).expect("lab bus");
        lab.bus_mut().advance_to(ms(60));
        assert!(lab.bus().is_running(), "extra = {extra}");
        assert_eq!(lab.bus().master().las().len(), 11 + extra as u32);
        let before = lab.bus().stats();
        lab.bus_mut().advance_to(ms(200));
        let s = lab.bus().stats();
        assert!(s.cycles > before.cycles + 10);
        assert_eq!(s.cycle_min, us(want * 154), "extra = {extra}");
        assert_eq!(s.cycle_max, us(want * 154), "extra = {extra}");
    }
    assert!(LabLift::with_extra(MasterConfig::default(), 21).is_err());
}
