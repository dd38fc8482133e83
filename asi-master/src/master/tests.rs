//! Checks that the master's shortcuts give what the plain computations give: the cycle picks
//! the same slaves as asking every address in turn.

use super::*;

/// A small deterministic random source (xorshift64*), so a failure can be replayed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    fn chance(&mut self, percent: u64) -> bool {
        self.below(100) < percent
    }
}

fn addr(n: u8, b: bool) -> SlaveAddr {
    if b { SlaveAddr::b(n) } else { SlaveAddr::a(n) }.expect("address")
}

/// The lab-like projection: standard slaves, an A/B pair and an S-7.3 analog output slave.
fn projected() -> ProjectedConfig {
    let std = SlaveCodes::new(0x7, 0x1, 0xF, 0xE);
    let ab = SlaveCodes::new(0x7, 0xA, 0x7, 0xE);
    let analog = SlaveCodes::new(0x7, 0x3, 0xF, 0x5);
    let slaves = [
        (addr(1, false), std),
        (addr(2, false), std),
        (addr(5, false), ab),
        (addr(5, true), ab),
        (addr(12, false), analog),
    ];
    ProjectedConfig::new(slaves.map(|(a, codes)| crate::config::ProjectedSlave {
        addr: a,
        codes,
        parameter: Nibble::from_low_bits(0x7),
    }))
    .expect("projection")
}

/// The data-exchange call the cycle made by asking addresses 1..31 in turn.
fn data_call_by_address(m: &mut Master) -> Option<Tx> {
    while m.cursor <= 31 {
        let n = m.cursor;
        m.cursor += 1;
        if let Some(a) = m.slot(n) {
            return Some(Tx::Exchange(a));
        }
    }
    None
}

/// The Read_Status call the cycle made by asking list bits in turn from the cursor.
fn status_call_by_address(m: &mut Master) -> Option<Tx> {
    if m.las.is_empty() {
        return None;
    }
    for _ in 0..64 {
        let i = m.status_cursor;
        m.status_cursor = (m.status_cursor + 1) % 64;
        if let Some(a) = SlaveAddr::from_index(i) {
            if m.las.contains(a) {
                return Some(Tx::Status(a));
            }
        }
    }
    None
}

#[test]
fn the_cycle_calls_the_slaves_asking_each_address_would() {
    let mut rng = Rng(0x5EED);
    let mut m = Master::new(MasterConfig::default(), projected()).expect("master");
    m.phase = Phase::NormalOperation;
    let now = SimTime::ZERO;
    for round in 0..20_000 {
        // Sparse, dense, single and random lists.
        let bits = match round % 4 {
            0 => rng.next() & rng.next(),
            1 => rng.next() | rng.next(),
            2 => 1 << rng.below(64),
            _ => rng.next(),
        };
        m.las = SlaveList::from_bits(bits);
        m.odd_cycle = rng.chance(50);
        m.cycle_open = true;
        m.job = None;
        m.cursor = 1 + rng.below(32) as u8;
        m.status_cursor = rng.below(64) as u8;

        m.stage = Stage::Data;
        let mut by_address = m.clone();
        let want = data_call_by_address(&mut by_address);
        let got = m.normal_next(now);
        match want {
            Some(tx) => {
                assert_eq!(got, Some(tx), "las {:#x}", bits);
                assert_eq!(m.cursor, by_address.cursor);
            }
            None => {
                // The cycle went on to the management call (or, with LAS empty, past it).
                if !m.las.is_empty() {
                    assert_eq!(m.cursor, 32);
                    let want = status_call_by_address(&mut by_address);
                    assert_eq!(got, want, "las {:#x}", bits);
                    assert_eq!(m.status_cursor, by_address.status_cursor);
                }
            }
        }

        m.stage = Stage::Management;
        let mut by_address = m.clone();
        let want = status_call_by_address(&mut by_address);
        assert_eq!(m.management_next(), want, "las {:#x}", bits);
        assert_eq!(m.status_cursor, by_address.status_cursor);
    }
}
