//! Checks that the master's shortcuts give what the plain computations give: the flags are
//! recomputed exactly when their inputs changed (as when the signature was compared around
//! every transaction), and the cycle picks the same slaves as asking every address in turn.

use super::cycle::DEXG;
use super::requests::READS;
use super::*;
use crate::mailbox::post;
use asi_phy::SimDuration;

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
    fn nibble(&mut self) -> Nibble {
        Nibble::from_low_bits(self.next() as u8)
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

/// The slaves on the line as the test imagines them: which addresses answer, with what codes.
struct World {
    present: [Option<SlaveCodes>; 64],
}

impl World {
    fn new() -> World {
        let mut present = [None; 64];
        for s in projected().iter() {
            present[s.addr.index() as usize] = Some(s.codes);
        }
        World { present }
    }

    /// A slave appears, disappears or changes its codes.
    fn churn(&mut self, rng: &mut Rng) {
        let i = rng.below(64) as usize;
        if i == 32 {
            return;
        }
        self.present[i] = match rng.below(4) {
            0 => None,
            1 => Some(SlaveCodes::new(0x7, 0xA, rng.below(16) as u8, 0xE)),
            2 => Some(SlaveCodes::new(0x7, 0x3, 0xF, 0x5)),
            _ => Some(SlaveCodes::new(
                rng.below(16) as u8,
                rng.below(16) as u8,
                rng.below(16) as u8,
                rng.below(16) as u8,
            )),
        };
    }

    /// What comes back for the call the master has in flight.
    fn answer(&self, m: &Master, rng: &mut Rng) -> Outcome {
        if rng.chance(4) {
            return Outcome::Corrupt(Checks::from_bits(1));
        }
        if rng.chance(3) {
            return Outcome::NoResponse;
        }
        let Some(f) = m.in_flight else {
            return Outcome::NoResponse;
        };
        let target = match f.tx {
            Tx::Detect(a, _)
            | Tx::ActivateParam(a)
            | Tx::ActivateDexg(a)
            | Tx::Exchange(a)
            | Tx::Status(a)
            | Tx::Include(a, _)
            | Tx::OfflineDefault(a)
            | Tx::Job(JobStep::Param(a, _) | JobStep::Status(a) | JobStep::Delete(a, _)) => a,
            Tx::Job(JobStep::Assign(_)) => ZERO_A,
        };
        let Some(codes) = self.present[target.index() as usize] else {
            return Outcome::NoResponse;
        };
        let v = match f.tx {
            Tx::Detect(_, r) | Tx::Include(_, InclStep::Read(r)) => match r {
                Read::Io => codes.io,
                Read::Id => codes.id,
                Read::Id1 => codes.id1,
                Read::Id2 => codes.id2,
            },
            Tx::Include(_, InclStep::AutoAssign(_)) | Tx::Job(JobStep::Assign(_))
                if rng.chance(70) =>
            {
                ACK_0110
            }
            _ => rng.nibble(),
        };
        Outcome::Response(Response::new(v))
    }
}

/// The flag inputs as the master compared them before this change.
fn signature_of(m: &Master) -> Signature {
    m.signature()
}

/// Something the PLC or the supply does between transactions.
fn disturb(m: &mut Master, now: SimTime, rng: &mut Rng) {
    match rng.below(200) {
        0 => m.set_power(now, false),
        1..=3 => m.set_power(now, true),
        4..=6 => {
            let bits = [
                0,
                0,
                0,
                HostFlags::WORD0_LOCK_DATA_EXCHANGE,
                HostFlags::WORD0_OFFLINE,
            ][rng.below(5) as usize]
                | if rng.chance(30) {
                    HostFlags::WORD0_NO_AUTO_ADDRESS
                } else {
                    0
                };
            let out = &mut m.image_mut().output;
            let w = out.word(0) & 0x0FFF;
            out.set_word(0, w | bits);
        }
        7..=12 => {
            let cmd = [
                Command::WriteParameter,
                Command::ReadStatus,
                Command::ChangeAddress,
                Command::ReadProjected,
                Command::WriteProjected,
                Command::ReadActual,
                Command::StoreActual,
                Command::SetMode,
                Command::ReadList,
                Command::ReadFlags,
            ][rng.below(10) as usize];
            let mut args = [0u8; 5];
            args[0] = match cmd {
                Command::SetMode => rng.below(2) as u8,
                Command::ReadList => rng.below(5) as u8,
                _ => rng.below(32) as u8 | if rng.chance(20) { 0x20 } else { 0 },
            };
            args[1] = match cmd {
                Command::WriteProjected => rng.below(2) as u8,
                _ => rng.below(32) as u8,
            };
            args[2] = rng.next() as u8;
            args[3] = rng.next() as u8;
            args[4] = rng.below(16) as u8;
            post(&mut m.image_mut().output, cmd, &args);
        }
        13..=20 => {
            let a = addr(1 + rng.below(31) as u8, rng.chance(30));
            m.image_mut().output.set_nibble(a, rng.nibble());
        }
        21 => {
            m.take_lcs();
        }
        _ => {}
    }
}

/// Drives a master through `steps` transactions of random outcomes, slaves coming and going,
/// host flags, mailbox jobs and power cuts; after every call the flags must be what the
/// master computed them to be whenever the signature of their inputs changed across the call.
/// Returns which phases and lists it went through, so the caller can see it covered them.
fn drive(seed: u64, steps: usize) -> (u32, SlaveList) {
    let mut rng = Rng(seed | 1);
    let mut cfg = MasterConfig::default();
    if rng.chance(50) {
        cfg.mode = Mode::Configuration;
    }
    let mut m = Master::new(cfg, projected()).expect("master");
    let mut world = World::new();
    let mut now = SimTime::ZERO;
    let step = SimDuration::from_micros(154);
    let mut phases = 0u32;
    let mut seen = SlaveList::EMPTY;
    for _ in 0..steps {
        now += step;
        if rng.chance(2) {
            world.churn(&mut rng);
        }
        disturb(&mut m, now, &mut rng);

        let before = signature_of(&m);
        let t = m.poll_transmit(now);
        check_flags(&m, before);
        if !t.is_some_and(|t| t.repeat) {
            assert_eq!(
                m.host_flags(),
                HostFlags::from_output_word0(m.image().output.word(0)),
                "host flags read from output word 0 at every call but a repeat"
            );
        }
        phases |= 1 << m.phase as u32;
        seen = SlaveList::from_bits(seen.bits() | m.las().bits());
        if t.is_none() || rng.chance(1) {
            // Nothing sent, or an outcome that never arrives.
            continue;
        }
        let outcome = world.answer(&m, &mut rng);
        let before = signature_of(&m);
        m.handle_outcome(now, outcome);
        check_flags(&m, before);
    }
    (phases, seen)
}

/// After a call: when the signature changed across it, the flags (and input flag nibble) are
/// those of the master as it is now.
fn check_flags(m: &Master, before: Signature) {
    if signature_of(m) != before {
        let f = m.compute_flags();
        assert_eq!(m.flags(), f, "flags stale after a change of their inputs");
        let mut expect = m.clone();
        expect.update_flags();
        assert_eq!(expect.image.input.word(0), m.image.input.word(0));
    }
}

#[test]
fn flags_follow_their_inputs_through_random_traffic() {
    let mut phases = 0;
    let mut seen = SlaveList::EMPTY;
    for seed in 1..=40u64 {
        let (p, s) = drive(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15), 20_000);
        phases |= p;
        seen = SlaveList::from_bits(seen.bits() | s.bits());
    }
    eprintln!("phases {phases:#b}, slaves through LAS: {seen}");
    assert_eq!(phases, 0b1111, "every phase visited");
    assert!(seen.len() > 20, "many slaves went through LAS: {seen}");
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

impl Master {
    /// Whether the inclusion stage may probe `a`, asked address by address.
    fn is_inclusion_candidate(&self, a: SlaveAddr) -> bool {
        if self.las.contains(a) {
            return false;
        }
        match (a.number(), a.select) {
            (0, _) => (1..=31u8).any(|n| {
                !self.occupies_whole(n) && SlaveAddr::a(n).is_some_and(|x| !self.las.contains(x))
            }),
            (n, Select::B) => !self.occupies_whole(n),
            _ => true,
        }
    }
}

/// The inclusion candidate found by asking list bits in turn from the cursor.
fn inclusion_scan_by_address(m: &Master) -> Option<u8> {
    let mut i = m.incl_cursor;
    for _ in 0..64 {
        if let Some(a) = SlaveAddr::from_index(i) {
            if m.is_inclusion_candidate(a) {
                return Some(i);
            }
        }
        i = (i + 1) % 64;
    }
    None
}

#[test]
fn the_inclusion_scan_finds_the_candidate_asking_each_address_would() {
    let mut rng = Rng(0x1C1);
    let mut m = Master::new(MasterConfig::default(), projected()).expect("master");
    let mut found = 0;
    for round in 0..20_000 {
        // Sparse, dense and random lists; full ones leave no candidate.
        let list = |rng: &mut Rng| match round % 4 {
            0 => rng.next() & rng.next(),
            1 => rng.next() | rng.next(),
            2 => u64::MAX,
            _ => rng.next(),
        };
        m.las = SlaveList::from_bits(list(&mut rng));
        m.lds = SlaveList::from_bits(list(&mut rng) | m.las.bits());
        for i in 0..64 {
            let codes = if rng.chance(30) {
                SlaveCodes::new(0x7, 0xA, 0x7, 0xE)
            } else {
                SlaveCodes::new(0x7, 0x1, 0xF, 0xE)
            };
            m.set_detected(i, codes);
        }
        m.incl_cursor = rng.below(64) as u8;
        let want = inclusion_scan_by_address(&m);
        assert_eq!(
            m.inclusion_scan(),
            want,
            "las {:#x} lds {:#x} ab {:#x} cursor {}",
            m.las.bits(),
            m.lds.bits(),
            m.ab_mask,
            m.incl_cursor
        );
        found += want.is_some() as u32;
    }
    assert!(
        (1_000..19_000).contains(&found),
        "{found} of 20000 found one"
    );
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

/// The reference for the short paths: every call and every outcome through the general path,
/// as the master did before [`Master::next_exchange`], [`Master::next_cycle_call`], the
/// answered-Data_Exchange branch of [`Master::handle_outcome`] and
/// [`Master::judge_cycle_call`] existed.
impl Master {
    fn poll_transmit_reference(&mut self, now: SimTime) -> Option<Transmit> {
        if let Some(f) = self.in_flight {
            if self.repeat_pending {
                self.repeat_pending = false;
                return Some(Transmit {
                    request: f.request,
                    kind: f.tx.kind(),
                    repeat: true,
                    ab: self.is_ab_call(f.tx),
                    slave: f.tx.slave(),
                });
            }
            self.in_flight = None;
        }
        self.inputs_before();
        self.service_host(now);
        let t = self.next_transmit(now);
        self.inputs_after(now);
        t
    }

    fn handle_outcome_reference(&mut self, now: SimTime, outcome: Outcome) -> Verdict {
        self.judge_outcome(now, outcome)
    }
}

/// Two masters hold the same state: everything they hold (compared field by field; the whole
/// of both is printed only when they differ).
fn assert_same(m: &Master, r: &Master, what: &str, k: usize) {
    assert!(
        m == r,
        "{what} at step {k}:\n{}\n{}",
        state_of(m),
        state_of(r)
    );
}

/// Everything the master holds, printed.
fn state_of(m: &Master) -> String {
    format!(
        "{m:?} {:?} {:?}",
        m.image.input.words(),
        m.image.output.words()
    )
}

/// Two masters, one with the short paths and one through the general path only, driven
/// through the same random traffic (as `drive`): every call, verdict and all of their state
/// must be the same after every step.
fn lockstep(seed: u64, steps: usize) -> [u64; 3] {
    let mut rng = Rng(seed | 1);
    let mut cfg = MasterConfig::default();
    if rng.chance(50) {
        cfg.mode = Mode::Configuration;
    }
    let mut m = Master::new(cfg.clone(), projected()).expect("master");
    let mut r = Master::new(cfg, projected()).expect("master");
    let mut world = World::new();
    let mut now = SimTime::ZERO;
    let step = SimDuration::from_micros(154);
    // Data_Exchanges, Read_Status calls and inclusion probes of a normal cycle.
    let mut calls = [0; 3];
    for k in 0..steps {
        now += step;
        if rng.chance(2) {
            world.churn(&mut rng);
        }
        let mut twin = Rng(rng.0);
        disturb(&mut m, now, &mut rng);
        disturb(&mut r, now, &mut twin);
        if m.phase == Phase::NormalOperation && m.stage == Stage::Data && m.cycle_open {
            // Now and then a cursor from outside the cycle's order, to reach every slot and
            // address 0.
            if rng.chance(2) {
                let c = rng.below(34) as u8;
                m.cursor = c;
                r.cursor = c;
            }
        }
        let t = m.poll_transmit(now);
        let want = r.poll_transmit_reference(now);
        assert_eq!(t, want, "call at step {k}");
        assert_same(&m, &r, "state after the call", k);
        if let Some(t) = t.filter(|t| !t.repeat) {
            match t.kind {
                TxKind::DataExchange => calls[0] += 1,
                TxKind::Management => calls[1] += 1,
                TxKind::Inclusion if matches!(m.in_flight, Some(f) if f.tx.is_probe()) => {
                    calls[2] += 1
                }
                _ => {}
            }
        }
        if t.is_none() || rng.chance(1) {
            continue;
        }
        let outcome = world.answer(&m, &mut rng);
        let v = m.handle_outcome(now, outcome);
        let want = r.handle_outcome_reference(now, outcome);
        assert_eq!(v, want, "verdict at step {k}");
        assert_same(&m, &r, "state after the outcome", k);
    }
    calls
}

#[test]
fn the_short_paths_do_what_the_general_path_does() {
    let mut calls = [0; 3];
    for seed in 1..=12u64 {
        let c = lockstep(seed.wrapping_mul(0xD1B5_4A32_D192_ED03), 10_000);
        for (sum, n) in calls.iter_mut().zip(c) {
            *sum += n;
        }
    }
    let [exchanges, statuses, probes] = calls;
    assert!(
        exchanges > 5_000 && statuses > 500 && probes > 1_000,
        "the short paths ran: {exchanges} Data_Exchanges, {statuses} Read_Status calls, \
         {probes} inclusion probes"
    );
}

#[test]
fn the_data_exchange_table_holds_the_requests() {
    for n in 1..32u8 {
        let address = asi_phy::Address::new(n).expect("address");
        for d in 0..16u8 {
            let out = Nibble::from_low_bits(d);
            assert_eq!(
                Ok(DEXG.standard[n as usize][d as usize]),
                Request::data_exchange(address, out)
            );
            if d < 8 {
                for (base, select) in [(0, Select::A), (32, Select::B)] {
                    assert_eq!(
                        Ok(DEXG.ab[base + n as usize][d as usize]),
                        Request::data_exchange_ab(address, select, out)
                    );
                }
            }
        }
    }
}

#[test]
fn the_read_tables_hold_the_requests() {
    for i in 0..64u8 {
        let Some(a) = SlaveAddr::from_index(i) else {
            assert_eq!(
                (READS.status[i as usize], READS.io[i as usize]),
                (None, None)
            );
            continue;
        };
        assert_eq!(
            READS.status[i as usize],
            Request::read_status(a.address, a.select).ok(),
            "{a}"
        );
        assert_eq!(
            READS.io[i as usize],
            Request::read_io_configuration(a.address, a.select).ok(),
            "{a}"
        );
    }
}

/// A master after a transaction, with the flags' signature taken as the next transaction's
/// `inputs_before` takes it: two masters that differ only in when they looked at the flags'
/// inputs are the same after it.
fn looked(m: &Master) -> Master {
    let mut m = m.clone();
    m.inputs_before();
    m
}

/// The answered Data_Exchange leaves the flags to the next transaction's look instead of
/// looking before and after it (`Master::handle_outcome`). Two masters through the same random
/// traffic, one with the short paths and one through the general path, with the supply
/// marked as touched (and now and then changed) between the call and its outcome: the same
/// verdicts and calls, the same flags and the same state once both have looked.
#[test]
fn an_answered_data_exchange_leaves_the_flags_to_the_next_look() {
    let mut touched_answers = 0;
    for seed in 1..=8u64 {
        let mut rng = Rng(seed.wrapping_mul(0xA076_1D64_78BD_642F) | 1);
        let cfg = MasterConfig::default();
        let mut m = Master::new(cfg.clone(), projected()).expect("master");
        let mut r = Master::new(cfg, projected()).expect("master");
        let mut world = World::new();
        let mut now = SimTime::ZERO;
        for k in 0..6_000 {
            now += SimDuration::from_micros(154);
            if rng.chance(2) {
                world.churn(&mut rng);
            }
            let mut twin = Rng(rng.0);
            disturb(&mut m, now, &mut rng);
            disturb(&mut r, now, &mut twin);
            let t = m.poll_transmit(now);
            assert_eq!(t, r.poll_transmit_reference(now), "call at step {k}");
            assert_same(&looked(&m), &looked(&r), "state after the call", k);
            if t.is_none() {
                continue;
            }
            if rng.chance(30) {
                // The flags' inputs touched between the call and its outcome: only marked,
                // or (as the supply or a host write would) changed and marked.
                let change = rng.chance(30).then(|| addr(1 + rng.below(31) as u8, false));
                for x in [&mut m, &mut r] {
                    if let Some(a) = change {
                        let on = x.lpf.contains(a);
                        x.lpf.set(a, !on);
                    }
                    x.touch_inputs();
                }
            }
            let outcome = world.answer(&m, &mut rng);
            if m.inputs_touched
                && matches!(outcome, Outcome::Response(_))
                && matches!(
                    m.in_flight,
                    Some(InFlight {
                        tx: Tx::Exchange(_),
                        ..
                    })
                )
            {
                touched_answers += 1;
            }
            let v = m.handle_outcome(now, outcome);
            assert_eq!(
                v,
                r.handle_outcome_reference(now, outcome),
                "verdict at step {k}"
            );
            assert_eq!(m.flags(), r.flags(), "flags after the outcome at step {k}");
            assert_same(&looked(&m), &looked(&r), "state after the outcome", k);
        }
    }
    assert!(
        touched_answers > 100,
        "answered Data_Exchanges with the flags' inputs touched: {touched_answers}"
    );
}
