//! The line decoder's fast paths held to their references.

use super::*;
use crate::receiver::tests::equivalence::{border_config, grid_line};
use crate::receiver::Expect;
use crate::telegram::Request;
use crate::timing::BusTiming;
use proptest::prelude::{Just, Strategy};

/// Every request's pulses, each after the first off its grid point by exactly the
/// tolerance (late, early, alternately), then a pulse exactly a pause after the last, which
/// begins a run of 32 on the grid (so that [`Run::whole`] has all it looks at); and the
/// number of the request's pulses.
fn on_the_borders() -> impl Iterator<Item = (u16, Vec<Pulse>, usize)> {
    let timing = BusTiming::default();
    let tol = timing.tolerance().as_nanos();
    (0u16..1 << 11).map(move |body| {
        let bits = (body << 2) | (((body.count_ones() & 1) as u16) << 1) | 1;
        let req = Request::from_bits(bits).expect("valid");
        let t0 = SimTime::from_micros(7);
        let mut pulses: Vec<Pulse> = PulseTrain::request(req, t0, timing.half_bit())
            .iter()
            .collect();
        for (i, p) in pulses.iter_mut().enumerate().skip(1) {
            let at = p.at.as_nanos();
            p.at = SimTime::from_nanos(if i % 2 == 1 { at + tol } else { at - tol });
        }
        let n = pulses.len();
        let next = pulses[n - 1].at + timing.min_pause();
        pulses.extend((0..32u64).map(|k| {
            let polarity = if k % 2 == 0 {
                Polarity::Negative
            } else {
                Polarity::Positive
            };
            Pulse::new(next + timing.half_bit().saturating_mul(k), polarity)
        }));
        (bits, pulses, n)
    })
}

/// The fast paths take pulses exactly on the tolerance's borders and end a run exactly a
/// pause after its last pulse (that they give the same frames as the reference decoder is
/// the equivalence property tests' part; this is that they are taken).
#[test]
fn the_fast_paths_take_pulses_on_the_tolerance_borders() {
    let grid = Grid::new(&BusTiming::default().receiver(Expect::Both));
    assert_ne!(grid.recip, 0);
    for (bits, pulses, n) in on_the_borders() {
        let (frame, after) = whole_at_once(&pulses[0], &pulses[1..], &grid).expect("at once");
        assert_eq!(after, &pulses[n..], "{bits:#06x}");
        assert_eq!(
            (frame.raw, frame.line_failed, frame.pulses),
            (u32::from(bits), Checks::NONE, n as u32)
        );
        let mut run = Run::begin(pulses[0]);
        let (taken, same) = run.scan(&pulses[1..n], &grid);
        assert_eq!((taken, same), (n - 1, false), "{bits:#06x}");
        // (The count is extend's to keep.)
        run.count += taken as u32;
        assert_eq!(run.finish(), frame);
    }
}

/// [`Run::whole`] with its frame returned.
fn whole_at_once<'p>(
    first: &Pulse,
    tail: &'p [Pulse],
    grid: &Grid,
) -> Option<(Frame, &'p [Pulse])> {
    let mut frame = None;
    let after = Run::whole(first, tail, grid, &mut |f| {
        assert!(frame.replace(f).is_none(), "one frame");
    })?;
    Some((frame.expect("a frame"), after))
}

/// The reference of [`Run::whole`]: the run decided at once as it was before its scan was
/// written out: the pulses after the first placed two at a time ([`Placed::scan`]), their
/// signs collected in order and checked to alternate, the positive ones found by prefix
/// parity; for a first pulse of either sign and a slice of any length.
fn whole_by_placed_scan<'p>(
    first: &Pulse,
    tail: &'p [Pulse],
    grid: &Grid,
) -> Option<(Frame, &'p [Pulse])> {
    if grid.recip == 0 {
        return None;
    }
    let t0 = first.at.as_nanos();
    let scanned = &tail[..tail.len().min(31)];
    let placed = Placed::scan(scanned, t0.wrapping_sub(grid.tol), 0, grid);
    let (n, q_prev) = (placed.n, placed.last_g);
    let occupied = 1 | placed.occupied;
    let signs = (first.polarity as u64) << n | placed.signs;
    let last_t = if n == 0 {
        t0
    } else {
        tail[n - 1].at.as_nanos()
    };
    let after = tail.get(n..)?;
    let at = after.first()?.at.as_nanos();
    if !(at.wrapping_sub(last_t) >= grid.pause && at >= last_t) {
        return None;
    }
    let all = (1u64 << n) - 1;
    if (signs ^ (signs >> 1)) & all != all {
        return None;
    }
    let first_positive = first.polarity == Polarity::Positive;
    let odd = prefix_parity(occupied);
    let run = Run {
        t0,
        last_t,
        last_g: q_prev,
        last_positive: signs & 1 == 1,
        on_grid: true,
        count: n as u32 + 1,
        occupied,
        positive: occupied & if first_positive { odd } else { !odd },
        failed: if first_positive {
            Checks::only(Check::StartBit)
        } else {
            Checks::NONE
        },
        clean: None,
    };
    Some((run.finish(), after))
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(2_000))]

    /// The written-out scan decides a run at once exactly where the placed scan did and
    /// gives the same frame, wherever it has the 32 pulses it looks at and the run begins
    /// negative (any other run goes the longer way): from every pulse of lines on the
    /// borders of the tolerance, the pause and the grid (`grid_line`).
    #[test]
    fn the_run_at_once_is_the_run_by_the_placed_scan(
        (cfg, pulses) in border_config().prop_flat_map(|cfg| (Just(cfg), grid_line(cfg))),
    ) {
        let grid = Grid::new(&cfg);
        for (i, first) in pulses.iter().enumerate() {
            let tail = &pulses[i + 1..];
            let reference = whole_by_placed_scan(first, tail, &grid);
            let expected = if tail.len() >= 32 && first.polarity == Polarity::Negative {
                reference
            } else {
                None
            };
            proptest::prop_assert_eq!(whole_at_once(first, tail, &grid), expected, "at {}", i);
        }
    }
}

/// The reference of [`Grid::place`]: the grid point and the distance to it by division.
fn place_by_division(grid: &Grid, y: u64, prev: u64) -> Option<u64> {
    let (q, r) = (y / grid.h, y % grid.h);
    (r <= grid.two_tol && (prev + 1..=prev + 2).contains(&q)).then_some(q)
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(20_000))]

    /// The placement by one widening multiplication is the placement by division, for
    /// every grid the fast scan takes (grids from 2 ns to 2²⁴ ns, tolerances up to just
    /// under half the grid) and pulses on, just inside and just outside the tolerance
    /// windows of the points around the next two, and anywhere.
    #[test]
    fn the_placement_by_multiplication_is_the_placement_by_division(
        h in proptest::prop_oneof![
            Just(2u64), Just(3), Just(3_000), Just(1 << 24), Just((1 << 24) - 1),
            2u64..64, 2u64..=1 << 24,
        ],
        t in 0u32..4,
        prev in 0u64..62,
        dq in 0u64..5,
        r in 0u32..6,
        any in proptest::prelude::any::<u64>(),
        far in proptest::prelude::any::<bool>(),
    ) {
        let tol = match t {
            0 => 0,
            1 => h.div_ceil(2) - 1,
            2 => (h.div_ceil(2) - 1) / 2,
            _ => any % h.div_ceil(2),
        };
        let cfg = ReceiverConfig {
            half_bit: h,
            tolerance: tol,
            pause: 2 * h + 2 * tol + 1,
            ..BusTiming::default().receiver(Expect::Both)
        };
        let grid = Grid::new(&cfg);
        proptest::prop_assert_ne!(grid.recip, 0);
        let two_tol = 2 * tol;
        let r = match r {
            0 => 0,
            1 => two_tol,
            2 => two_tol + 1,
            3 => h - 1,
            4 => any % h,
            _ => any % (two_tol + 1),
        };
        let y = if far { any } else { (prev + dq) * h + r.min(h - 1) };
        for y in [y, y.wrapping_sub(1), y.wrapping_add(1)] {
            proptest::prop_assert_eq!(
                grid.place(y, prev),
                place_by_division(&grid, y, prev),
                "h {} tol {} prev {} y {}", h, tol, prev, y
            );
        }
    }
}

/// The reference of [`bit_checks`]: each check from the bits it names.
fn bit_checks_bit_by_bit(raw: u32, cells: u32, g: u64) -> Checks {
    let mut failed = Checks::NONE;
    if cells >= 1 && raw >> (cells - 1) & 1 == 1 {
        failed = failed.with(Check::StartBit);
    }
    if cells >= 3 {
        let between = (raw >> 1) & ((1 << (cells - 2)) - 1);
        if odd_parity(between) {
            failed = failed.with(Check::Parity);
        }
    }
    if g % 2 != 0 || g.div_ceil(2) == 0 || raw & 1 == 0 {
        failed = failed.with(Check::EndBit);
    }
    failed
}

/// The checks of the bits without a branch for each are the checks bit by bit, for every
/// number of cells a frame holds (with its last pulse at the end of its last cell or in
/// its middle, or far past the 32 cells kept): every value up to 12 cells, and for more
/// the values with one bit, with all but one and 5,000 others each.
#[test]
fn the_checks_of_the_bits_are_the_checks_bit_by_bit() {
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    for cells in 0..=32u32 {
        let all = if cells == 32 {
            u32::MAX
        } else {
            (1u32 << cells) - 1
        };
        let mut values: Vec<u32> = if cells <= 12 {
            (0..=all).collect()
        } else {
            let ones = (0..cells).map(|k| 1 << k);
            let holes = (0..cells).map(|k| all & !(1 << k));
            ones.chain(holes).chain([0, all]).collect()
        };
        if cells > 12 {
            values.extend((0..100_000 / 20).map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                x as u32 & all
            }));
        }
        let ends = [
            2 * u64::from(cells),
            (2 * u64::from(cells)).saturating_sub(1),
        ];
        let gs = if cells == 32 {
            vec![63, 64, 65, 1_000]
        } else {
            ends.to_vec()
        };
        for g in gs {
            for &raw in &values {
                assert_eq!(
                    bit_checks(raw, cells, g),
                    bit_checks_bit_by_bit(raw, cells, g),
                    "{raw:#x} {cells} {g}"
                );
            }
        }
    }
}

#[test]
fn odd_parity_counts_the_ones() {
    let mut x = 0x9E37_79B9u32;
    for k in 0..200_000u32 {
        for v in [k, x, !k, k << 16] {
            assert_eq!(odd_parity(v), v.count_ones() % 2 == 1, "{v:#x}");
        }
        x = x.rotate_left(5) ^ k.wrapping_mul(0x85EB_CA6B);
    }
    assert!(!odd_parity(0) && odd_parity(u32::MAX >> 1) && !odd_parity(u32::MAX));
}

/// Every run of up to 31 pulses after the first, one or two grid points apart (all step
/// patterns up to 12 pulses, a spread of them beyond), exactly on the grid or off it by up to
/// the tolerance, followed by a pause: [`Run::whole`] decides each at once, with the frame of
/// the placed scan. This reaches the cases of the frame made at once (`whole_frame`): missing
/// middles of cells, one and two cells, up to 16 cells (read by table) and more.
#[test]
fn every_pattern_of_steps_is_decided_at_once_as_by_the_placed_scan() {
    let cfg = BusTiming::default().receiver(Expect::Both);
    let grid = Grid::new(&cfg);
    let (h, tol) = (cfg.half_bit, cfg.tolerance as i64);
    let mut seed = 0x2545_F491_4F6C_DD1Du64;
    let mut patterns = Vec::new();
    for n in 0..=31u32 {
        if n <= 12 {
            patterns.extend((0..1u64 << n).map(|p| (n, p)));
        } else {
            patterns.extend((0..200).map(|_| {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                (n, seed)
            }));
        }
    }
    let mut decided = [0u32; 32];
    for &(n, steps) in &patterns {
        for jitter in [false, true] {
            let t0 = 1_000_000u64;
            let mut g = 0u64;
            let mut pulses = vec![Pulse::new(SimTime::from_nanos(t0), Polarity::Negative)];
            for i in 0..n {
                g += 1 + (steps >> i & 1);
                let off = if jitter {
                    [tol, -tol, 0][i as usize % 3]
                } else {
                    0
                };
                let polarity = if i % 2 == 0 {
                    Polarity::Positive
                } else {
                    Polarity::Negative
                };
                let at = (t0 + g * h).saturating_add_signed(off);
                pulses.push(Pulse::new(SimTime::from_nanos(at), polarity));
            }
            let next = pulses[n as usize].at.as_nanos() + cfg.pause;
            pulses.extend(
                (0..32u64)
                    .map(|k| Pulse::new(SimTime::from_nanos(next + k * h), Polarity::Negative)),
            );
            let got = whole_at_once(&pulses[0], &pulses[1..], &grid);
            let want = whole_by_placed_scan(&pulses[0], &pulses[1..], &grid);
            assert!(got.is_some(), "{n} {steps:#x} {jitter}");
            assert_eq!(got, want, "{n} {steps:#x} {jitter}");
            decided[n as usize] += 1;
        }
    }
    assert!(decided.iter().all(|&d| d > 0));
}
