//! Properties of the handshake engines (src/handshake.rs): whatever the ratio of PLC scans to
//! AS-i cycles and wherever either side is reset, the next word gets through, whole and
//! unchanged.

use crate::common;

use asi_master::integrated_analog::S73OutputMaster;
use asi_master::plc_handshake::{CabinDisplayMaster, CabinPanelMaster, FloorStationMaster};
use asi_phy::handshake_words::CabinPanelState;
use asi_phy::Nibble;
use asi_slaves::analog_firmware::S73OutputSlave;
use asi_slaves::device_handshake::{CabinDisplaySlave, CabinPanelSlave, FloorStationSlave};
use proptest::prelude::*;

/// Drives a PLC side and a device side: `plc_every` device steps per PLC step (or the PLC
/// steps `plc_every` times per device step when `plc_faster`), resetting the device at
/// `dev_resets` and the PLC at `plc_resets` (step numbers). Returns after `steps`.
#[allow(clippy::too_many_arguments)]
fn drive(
    plc: &mut dyn FnMut(Nibble) -> Nibble,
    plc_reset: &mut dyn FnMut(),
    dev: &mut dyn FnMut(Nibble) -> Nibble,
    dev_reset: &mut dyn FnMut(),
    plc_every: usize,
    plc_faster: bool,
    resets: &[(usize, bool)],
    steps: usize,
) {
    let mut input = Nibble::ZERO;
    let mut output = Nibble::ZERO;
    for k in 0..steps {
        for &(at, which) in resets {
            if at == k {
                if which {
                    dev_reset();
                } else {
                    plc_reset();
                }
            }
        }
        if plc_faster {
            for _ in 0..plc_every {
                output = plc(input);
            }
            input = dev(output);
        } else {
            if k % plc_every == 0 {
                output = plc(input);
            }
            input = dev(output);
        }
    }
}

/// The bits of the display word (lab crate) for `floor` and the indicator bits of `bits`.
fn word(floor: u8, bits: u8) -> u16 {
    common::display_bits(
        floor,
        bits & 1 != 0,
        bits & 2 != 0,
        bits & 4 != 0,
        bits & 8 != 0,
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn floor_word_gets_through(
        floor in 1u8..=24, bits in 0u8..16, every in 1usize..8, faster in any::<bool>(),
        resets in proptest::collection::vec((0usize..300, any::<bool>()), 0..3),
    ) {
        let w = word(floor, bits);
        let mut m = FloorStationMaster::new();
        m.set_word(w);
        let s = std::cell::RefCell::new(FloorStationSlave::new());
        let mm = std::cell::RefCell::new(m);
        drive(
            &mut |i| mm.borrow_mut().step(i),
            &mut || mm.borrow_mut().reset(),
            &mut |o| s.borrow_mut().step(o),
            &mut || s.borrow_mut().reset(),
            every, faster, &resets, 300 + 2_000,
        );
        prop_assert_eq!(s.borrow().display(), Some(w));
    }

    #[test]
    fn cabin_display_word_gets_through(
        floor in 1u8..=24, bits in 0u8..16, every in 1usize..8, faster in any::<bool>(),
        resets in proptest::collection::vec((0usize..300, any::<bool>()), 0..3),
    ) {
        let w = word(floor, bits);
        let mut m = CabinDisplayMaster::new();
        m.set_word(w);
        let s = std::cell::RefCell::new(CabinDisplaySlave::new());
        let mm = std::cell::RefCell::new(m);
        drive(
            &mut |i| mm.borrow_mut().step(i),
            &mut || mm.borrow_mut().reset(),
            &mut |o| s.borrow_mut().step(o),
            &mut || s.borrow_mut().reset(),
            every, faster, &resets, 300 + 3_000,
        );
        prop_assert_eq!(s.borrow().display(), Some(w));
    }

    #[test]
    fn cabin_panel_word_gets_through(
        buttons in 0u32..1 << 24, flags in 0u8..32, every in 1usize..8, faster in any::<bool>(),
        resets in proptest::collection::vec((0usize..300, any::<bool>()), 0..3),
    ) {
        let want = CabinPanelState {
            floor_buttons: buttons,
            bell: flags & 1 != 0,
            stop: flags & 2 != 0,
            door_closed: flags & 4 != 0,
            vane_left: flags & 8 != 0,
            vane_right: flags & 16 != 0,
        };
        let mut dev = CabinPanelSlave::new();
        *dev.signals_mut() = want;
        let s = std::cell::RefCell::new(dev);
        let m = std::cell::RefCell::new(CabinPanelMaster::new());
        let mut updates = Vec::new();
        drive(
            &mut |i| {
                let mut m = m.borrow_mut();
                let o = m.step(i);
                updates.extend(m.take_update());
                o
            },
            &mut || m.borrow_mut().reset(),
            &mut |o| s.borrow_mut().step(o),
            &mut || s.borrow_mut().reset(),
            every, faster, &resets, 300 + 4_000,
        );
        prop_assert_eq!(m.borrow().state(), Some(want));
        // Whatever was reset, no torn word was ever taken.
        prop_assert!(updates.iter().all(|&u| u == want));
    }

    /// Table 4.7 of the lift thesis over a lossy bus: any panel word (all 29 signal bits, so every
    /// 32-bit word of table 4.6 with a right parity) arrives intact whatever Data_Exchanges
    /// lose their request or their response and whatever PLC scans come late or twice. The
    /// slave's module answers from its pins one exchange late, as the AC2726 does.
    #[test]
    fn cabin_panel_word_survives_lost_and_delayed_scans(
        buttons in 0u32..1 << 24, flags in 0u8..32,
        ticks in proptest::collection::vec(0u8..16, 0..600),
    ) {
        let want = CabinPanelState {
            floor_buttons: buttons,
            bell: flags & 1 != 0,
            stop: flags & 2 != 0,
            door_closed: flags & 4 != 0,
            vane_left: flags & 8 != 0,
            vane_right: flags & 16 != 0,
        };
        let mut dev = CabinPanelSlave::new();
        *dev.signals_mut() = want;
        let mut plc = CabinPanelMaster::new();
        let (mut out_image, mut in_image, mut pins) = (Nibble::ALL, Nibble::ZERO, Nibble::ZERO);
        let mut updates = Vec::new();
        // Random ticks first: bit 0 = a Data_Exchange, bit 1 = its request lost, bit 2 = its
        // response lost, bit 3 = a PLC scan. Then a clean bus: an exchange every tick and a
        // scan every 5th, until two whole words have arrived.
        let clean = (0..2_000).map(|i| if i % 5 == 0 { 0b1001 } else { 0b0001 });
        for t in ticks.iter().copied().chain(clean) {
            if t & 1 != 0 && t & 2 == 0 {
                let sampled = pins;
                pins = dev.step(out_image);
                if t & 4 == 0 {
                    in_image = sampled;
                }
            }
            if t & 8 != 0 {
                out_image = plc.step(in_image);
                updates.extend(plc.take_update());
            }
            if plc.words().good() >= 2 {
                break;
            }
        }
        prop_assert!(plc.words().good() >= 2);
        prop_assert_eq!(plc.words().bad(), 0);
        prop_assert_eq!(plc.restarts(), 0, "lost and late telegrams never stall a word");
        prop_assert!(updates.iter().all(|&u| u == want));
    }

    #[test]
    fn s73_value_gets_through(value in 0u16..=u16::MAX, resets in proptest::collection::vec((0usize..100, any::<bool>()), 0..3)) {
        let m = std::cell::RefCell::new(S73OutputMaster::new(2));
        m.borrow_mut().set_value(1, value);
        m.borrow_mut().set_value(2, !value);
        let s = std::cell::RefCell::new(S73OutputSlave::new(2));
        drive(
            &mut |i| m.borrow_mut().step(i),
            &mut || m.borrow_mut().reset(),
            &mut |o| s.borrow_mut().step(o),
            &mut || s.borrow_mut().reset(),
            1, false, &resets, 100 + 1_000,
        );
        prop_assert_eq!(s.borrow().value(1), Some(value));
        prop_assert_eq!(s.borrow().value(2), Some(!value));
    }
}
