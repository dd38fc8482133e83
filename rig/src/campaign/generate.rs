//! The scenario generator of a campaign: a pure function of (campaign seed, run index,
//! profile) to a valid [`Scenario`] (the book, "Campaigns").
//!
//! A run has three parts on its timeline:
//!
//! 1. **Activity**, from 1 s to `act_end` = probe − 16 s: a random number of random events
//!    ([`ActivityKind`], drawn by the profile's weights) at random millisecond times. Some kinds
//!    bring their own follow-ups: a slave comes back online and a vane sensor is repaired
//!    1..30 s later, an opened door is mostly closed 2..20 s later, a crank follows a STOP
//!    once K1 has opened (10..15 s later) and is sometimes turned back. Every follow-up falls
//!    within the activity window; what it cannot repair there, the recovery does.
//! 2. **Recovery**, 22 s before the probe: every slave ever taken offline is put back, every
//!    vane sensor ever broken is repaired (but one a profile deliberately leaves broken), the
//!    load goes back to empty, loaded or full if it ever changed, the door is closed if it was
//!    ever open. With the repairs an attendant takes over (`attend`): from then on, whenever
//!    K1 stays open for a cause an operator answers (an overtravel, a group error, a monitor
//!    waiting for its reset), the attendant rescues a cabin left beyond an end floor,
//!    acknowledges (ERR_ACK) and presses the safety reset, and again while K1 stays open. The
//!    probe comes 22 s after the repairs. The recovery repairs everything the activity could
//!    have broken, whatever events remain, so a shrunk scenario that keeps the recovery is
//!    still repaired.
//! 3. **Probe**: a cabin call `probe_lead` before the end. The lift is in service at the end
//!    if the probe is served and the controller ends in a normal service state.
//!
//! Nothing here reads a clock or an unseeded random source: the run's seed is a hash of the
//! campaign seed and the index ([`run_seed`]), and a ChaCha8 generator seeded with it makes
//! every choice; the scenario's line-noise seed is the run's seed.

use super::profile::{ActivityKind, Profile};
use crate::scenario::{needs_rescue, start_range_mm, Action, Fault, Scenario, ScenarioEvent};
use asi_phy::{SimDuration, SimTime};
use lift_model::{Button, LiftConfig, LoadLevel, SensorFault, VaneSensor};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeSet;

/// The largest total of the hand cranks in one run, mm (either way).
pub const MAX_CRANK_SUM_MM: f64 = 40.0;

/// From the end of the activity to the recovery: longer than any hold (3 s) or power fail
/// (5 s) that starts in the activity.
const QUIET_GAP: SimDuration = SimDuration::from_secs(6);
/// From the recovery's repairs to the probe.
const RECOVERY: SimDuration = SimDuration::from_secs(22);

/// The probe: the cabin call whose service says the lift is in service at the end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Probe {
    /// When it is pressed.
    pub at: SimTime,
    /// The floor called.
    pub floor: u8,
    /// `false` when the profile left a vane sensor broken on purpose: the run cannot be
    /// expected to be in service, and reports `in_service: null`.
    pub judged: bool,
}

/// A generated run: its scenario, which of its events are the recovery and the probe, and
/// the probe.
#[derive(Clone, Debug, PartialEq)]
pub struct Generated {
    /// The scenario.
    pub scenario: Scenario,
    /// `tail[i]`: event `i` belongs to the recovery or is the probe.
    pub tail: Vec<bool>,
    /// The probe.
    pub probe: Option<Probe>,
}

/// Where the recovery begins among `events` whose recovery, probe and start procedure are
/// flagged in `tail`: the first event from which on every event is the recovery or the probe
/// (the operator's start procedure, also kept, lies before the activity).
pub fn recovery_index(tail: &[bool], events: &[ScenarioEvent]) -> Option<usize> {
    (0..tail.len().min(events.len()))
        .find(|&i| tail[i..].iter().all(|t| *t) && events[i].at >= RECOVERY_NOT_BEFORE)
}

/// The recovery never starts before this: the start procedure ends at 7 s, and shrinking never
/// moves the recovery earlier than 10 s.
pub const RECOVERY_NOT_BEFORE: SimTime = SimTime::from_millis(10_000);

/// The seed of run `index` of the campaign with seed `campaign_seed`: SplitMix64 of both, so
/// that neighbouring runs and neighbouring campaigns are unrelated.
pub fn run_seed(campaign_seed: u64, index: u64) -> u64 {
    splitmix64(campaign_seed ^ splitmix64(index.wrapping_add(0x5EED_CA4D_A16E_0001)))
}

fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn ms(t: u64) -> SimTime {
    SimTime::from_millis(t)
}

fn dur_ms(d: SimDuration) -> u64 {
    d.as_nanos() / 1_000_000
}

/// What the activity touched, for the recovery.
#[derive(Default)]
struct Touched {
    slaves: BTreeSet<u8>,
    vanes: BTreeSet<u8>,
    load: bool,
    door: bool,
    converter: bool,
    encoder: bool,
    /// The sizes of the first cranks so far, mm.
    crank_sum_mm: f64,
}

/// Builds the events of one run.
struct Builder<'a> {
    rng: ChaCha8Rng,
    profile: &'a Profile,
    floors: u8,
    /// The activity window, ms.
    act_start: u64,
    act_end: u64,
    events: Vec<(u64, Action)>,
    touched: Touched,
}

impl Builder<'_> {
    fn push(&mut self, at_ms: u64, action: Action) {
        self.events.push((at_ms, action));
    }

    fn hold(&mut self) -> SimDuration {
        if self.rng.random_bool(self.profile.long_hold_chance) {
            SimDuration::from_millis(self.rng.random_range(500..=5000))
        } else {
            crate::scenario::DEFAULT_HOLD
        }
    }

    fn floor(&mut self) -> u8 {
        self.rng.random_range(1..=self.floors)
    }

    /// A follow-up `lo..=hi` ms after `t`, if it still falls within the activity.
    fn later(&mut self, t: u64, lo: u64, hi: u64) -> Option<u64> {
        let at = t + self.rng.random_range(lo..=hi);
        (at <= self.act_end).then_some(at)
    }

    fn press(&mut self, t: u64, button: Button, hold: SimDuration) {
        self.push(t, Action::Press { button, hold });
    }

    fn episode(&mut self, t: u64, kind: ActivityKind) {
        match kind {
            ActivityKind::Cabin => {
                let (f, h) = (self.floor(), self.hold());
                self.press(t, Button::Cabin(f), h);
            }
            ActivityKind::Hall => {
                let f = self.floor();
                let up = match f {
                    1 => true,
                    f if f == self.floors => false,
                    _ => self.rng.random_bool(0.5),
                };
                let h = self.hold();
                let b = if up {
                    Button::HallUp(f)
                } else {
                    Button::HallDown(f)
                };
                self.press(t, b, h);
            }
            ActivityKind::Stop => {
                let h = SimDuration::from_millis(self.rng.random_range(300..=3000));
                self.press(t, Button::Stop, h);
            }
            ActivityKind::Bell => {
                let h = self.hold();
                self.press(t, Button::Bell, h);
            }
            ActivityKind::Load => {
                let level = match self.rng.random_range(0..4) {
                    0 => LoadLevel::Empty,
                    1 => LoadLevel::Loaded,
                    2 => LoadLevel::Full,
                    _ => LoadLevel::Overloaded,
                };
                self.touched.load = true;
                self.push(t, Action::Load(level));
            }
            ActivityKind::Door => {
                self.touched.door = true;
                self.push(t, Action::Door { closed: false });
                if self.rng.random_bool(0.7) {
                    if let Some(c) = self.later(t, 2_000, 20_000) {
                        self.push(c, Action::Door { closed: true });
                    }
                }
            }
            ActivityKind::Crank => {
                // STOP, then crank once K1 has opened (the STOP delay is 9.1 s).
                let h = SimDuration::from_millis(self.rng.random_range(500..=2000));
                self.press(t, Button::Stop, h);
                let Some(c) = self.later(t, 10_000, 15_000) else {
                    return;
                };
                // The cranks of a run add up to at most 40 mm either way whatever their
                // order in time: every first crank spends its size from a budget of 40 mm,
                // and a crank back only undoes its own first crank, later.
                let left = ((MAX_CRANK_SUM_MM - self.touched.crank_sum_mm) * 10.0).floor() as i64;
                let tenths = self.rng.random_range(-left.min(200)..=left.min(200));
                if tenths == 0 {
                    return;
                }
                let mm = tenths as f64 / 10.0;
                self.touched.crank_sum_mm += mm.abs();
                self.push(c, Action::Crank { mm });
                if self.rng.random_bool(0.5) {
                    if let Some(back) = self.later(c, 3_000, 8_000) {
                        self.push(back, Action::Crank { mm: -mm });
                    }
                }
            }
            ActivityKind::Reset => self.push(t, Action::Reset),
            ActivityKind::Ack => self.push(t, Action::Ack),
            ActivityKind::Slave => {
                let slave = lab::address::ALL[self.rng.random_range(0..lab::address::ALL.len())];
                self.touched.slaves.insert(slave);
                self.push(t, Action::Fault(Fault::SlaveOffline { slave }));
                if let Some(back) = self.later(t, 1_000, 30_000) {
                    self.push(back, Action::Fault(Fault::SlaveOnline { slave }));
                }
            }
            ActivityKind::PowerFail => {
                let duration = SimDuration::from_millis(self.rng.random_range(100..=5000));
                self.push(t, Action::Fault(Fault::PowerFail { duration }));
            }
            ActivityKind::SafeLinkDrop => {
                let duration = SimDuration::from_millis(self.rng.random_range(50..=2000));
                self.push(t, Action::Fault(Fault::SafeLinkDrop { duration }));
            }
            ActivityKind::Runaway => {
                let up = self.rng.random_bool(0.5);
                self.touched.converter = true;
                self.push(t, Action::Fault(Fault::ConverterRunaway { up }));
                if let Some(r) = self.later(t, 1_000, 20_000) {
                    self.push(r, Action::Fault(Fault::ConverterRepaired));
                }
            }
            ActivityKind::Encoder => {
                self.touched.encoder = true;
                self.push(t, Action::Fault(Fault::EncoderFailed));
                if let Some(r) = self.later(t, 1_000, 20_000) {
                    self.push(r, Action::Fault(Fault::EncoderRepaired));
                }
            }
            ActivityKind::Vane => {
                let (sensor, fault) = self.vane_fault();
                self.touched.vanes.insert(sensor_index(sensor));
                self.push(t, Action::Fault(Fault::Vane { sensor, fault }));
                if let Some(r) = self.later(t, 1_000, 30_000) {
                    let repaired = Fault::Vane {
                        sensor,
                        fault: SensorFault::None,
                    };
                    self.push(r, Action::Fault(repaired));
                }
            }
        }
    }

    fn vane_fault(&mut self) -> (VaneSensor, SensorFault) {
        let sensor = if self.rng.random_bool(0.5) {
            VaneSensor::Left
        } else {
            VaneSensor::Right
        };
        let fault = if self.rng.random_bool(0.5) {
            SensorFault::StuckOn
        } else {
            SensorFault::StuckOff
        };
        (sensor, fault)
    }
}

fn sensor_index(s: VaneSensor) -> u8 {
    match s {
        VaneSensor::Left => 0,
        VaneSensor::Right => 1,
    }
}

/// Run `index` of the campaign with seed `campaign_seed` under `profile` (which must pass
/// [`Profile::check`]).
pub fn generate(campaign_seed: u64, index: u64, profile: &Profile) -> Generated {
    let seed = run_seed(campaign_seed, index);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let floors = profile.floors.pick(&mut rng).unwrap_or(4);
    let algorithm = profile.algorithm.pick(&mut rng).unwrap_or_default();
    let (lo, hi) = profile.duration;
    let duration_s =
        rng.random_range(lo.as_nanos().div_ceil(1_000_000_000)..=hi.as_nanos() / 1_000_000_000);
    let duration = SimDuration::from_secs(duration_s);
    let range = start_range_mm(floors);
    let shaft = {
        let mut cfg = LiftConfig::default();
        cfg.floors = floors;
        cfg
    };
    let start_mm = if rng.random_bool(profile.start_level_chance) {
        let floor = rng.random_range(1..=floors);
        shaft.floor_level_mm(floor).unwrap_or(0.0)
    } else {
        let x = rng.random_range(*range.start()..=*range.end());
        let rounded = (x * 10.0).round() / 10.0;
        if range.contains(&rounded) {
            rounded
        } else {
            x
        }
    };
    let load = profile.load.pick(&mut rng).unwrap_or(LoadLevel::Empty);
    let door_closed = !rng.random_bool(profile.door_open_chance);
    let pulse_error_rate = profile.pulse_error_rate.pick(&mut rng).unwrap_or(0.0);
    let extra_slaves = if rng.random_bool(profile.extra_slaves_chance) {
        rng.random_range(1..=lab::address::FREE.len() as u8)
    } else {
        0
    };
    let plc_scan = profile
        .scan
        .pick(&mut rng)
        .unwrap_or(SimDuration::from_millis(10));
    // A start initialisation cannot handle by itself gets the operator's procedure first
    // (the book, "Start heights"): the power-on reset, the rescue (a crank back to the end
    // floor's level, up to 14 s at 10 mm/s), the safety reset and the acknowledge; the
    // activity begins after it.
    let rescue_first = needs_rescue(floors, start_mm);
    let power_on_reset = rescue_first || !rng.random_bool(profile.no_power_on_reset_chance);
    let leave_vane_broken = rng.random_bool(profile.leave_vane_broken_chance);

    let end = dur_ms(duration);
    let probe_at = end - dur_ms(profile.probe_lead);
    let recovery = probe_at - dur_ms(RECOVERY);
    let act_end = recovery - dur_ms(QUIET_GAP);
    let preamble: Vec<(u64, Action)> = if rescue_first {
        vec![
            (2_000, Action::Rescue),
            (18_000, Action::Reset),
            (19_000, Action::Ack),
        ]
    } else {
        Vec::new()
    };
    let act_start = if preamble.is_empty() { 1_000 } else { 20_000 };
    let mut b = Builder {
        rng,
        profile,
        floors,
        act_start: act_start.min(act_end),
        act_end,
        events: Vec::new(),
        touched: Touched {
            load: load == LoadLevel::Overloaded,
            door: !door_closed,
            ..Touched::default()
        },
    };
    let n = b.rng.random_range(profile.events.0..=profile.events.1);
    for _ in 0..n {
        let t = b.rng.random_range(b.act_start..=b.act_end);
        if let Some(kind) = profile.event.pick(&mut b.rng) {
            b.episode(t, kind);
        }
    }
    let broken = leave_vane_broken.then(|| {
        let t = b.rng.random_range(b.act_start..=b.act_end);
        let (sensor, fault) = b.vane_fault();
        b.push(t, Action::Fault(Fault::Vane { sensor, fault }));
        sensor_index(sensor)
    });
    b.events.sort_by_key(|(t, _)| *t);

    // The recovery: repair whatever the activity touched.
    let mut tail: Vec<(u64, Action)> = Vec::new();
    for slave in &b.touched.slaves {
        tail.push((
            recovery,
            Action::Fault(Fault::SlaveOnline { slave: *slave }),
        ));
    }
    for v in &b.touched.vanes {
        if Some(*v) == broken {
            continue;
        }
        let sensor = if *v == 0 {
            VaneSensor::Left
        } else {
            VaneSensor::Right
        };
        let fault = SensorFault::None;
        tail.push((recovery, Action::Fault(Fault::Vane { sensor, fault })));
    }
    if b.touched.load {
        let level = match b.rng.random_range(0..3) {
            0 => LoadLevel::Empty,
            1 => LoadLevel::Loaded,
            _ => LoadLevel::Full,
        };
        tail.push((recovery, Action::Load(level)));
    }
    if b.touched.door {
        tail.push((recovery, Action::Door { closed: true }));
    }
    if b.touched.converter {
        tail.push((recovery, Action::Fault(Fault::ConverterRepaired)));
    }
    if b.touched.encoder {
        tail.push((recovery, Action::Fault(Fault::EncoderRepaired)));
    }
    // The attendant answers every safety stop from the repairs on: a cabin left on an
    // overtravel sensor (a vane sensor fault can take it there, or a restart from a vane
    // reading taken before its repair reached the PLC, campaign 12 run 3764), a group error,
    // a Safety-at-Work monitor trip by line noise that stays on (campaign 12 run 6768).
    tail.push((recovery, Action::Attend));
    let probe_floor = b.rng.random_range(1..=floors);
    // Drawn last, and only when the profile leaves it to chance, so that the runs of a
    // profile without the safe drive stay as they were.
    let safe_drive = match profile.safe_drive_chance {
        c if c <= 0.0 => false,
        c if c >= 1.0 => true,
        c => b.rng.random_bool(c),
    };
    tail.push((
        probe_at,
        Action::Press {
            button: Button::Cabin(probe_floor),
            hold: crate::scenario::DEFAULT_HOLD,
        },
    ));
    if !safe_drive {
        // Without the safe drive there is no encoder to fail (a scenario file refuses the
        // fault): the draws stay, the events go.
        let encoder = |a: &Action| {
            matches!(
                a,
                Action::Fault(Fault::EncoderFailed | Fault::EncoderRepaired)
            )
        };
        b.events.retain(|(_, a)| !encoder(a));
        tail.retain(|(_, a)| !encoder(a));
    }

    // The start procedure is kept like the recovery; in a run too short for an activity after
    // it, the activity overlaps it (in time order; the procedure first at equal times).
    let mut flagged: Vec<(u64, Action, bool)> = preamble
        .into_iter()
        .map(|(t, a)| (t, a, true))
        .chain(b.events.into_iter().map(|(t, a)| (t, a, false)))
        .collect();
    flagged.sort_by_key(|(t, _, _)| *t);
    flagged.extend(tail.into_iter().map(|(t, a)| (t, a, true)));
    let is_tail: Vec<bool> = flagged.iter().map(|(_, _, k)| *k).collect();
    let events: Vec<ScenarioEvent> = flagged
        .into_iter()
        .map(|(t, action, _)| ScenarioEvent {
            at: ms(t),
            action,
            line: 0,
        })
        .collect();
    Generated {
        scenario: Scenario {
            name: format!("campaign {campaign_seed} ({}) run {index}", profile.name),
            seed,
            duration,
            algorithm,
            floors,
            start_mm,
            load,
            door_closed,
            pulse_error_rate,
            extra_slaves,
            master_mode: asi_master::Mode::Protected,
            plc_scan,
            // The campaign's own program, if it has one, is put in by its runner.
            program: None,
            power_on_reset,
            safe_drive,
            events,
            // The campaign's passengers are its own presses.
            traffic: Vec::new(),
        },
        tail: is_tail,
        probe: Some(Probe {
            at: ms(probe_at),
            floor: probe_floor,
            judged: broken.is_none(),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::profile::Profile;

    fn default() -> Profile {
        Profile::built_in("default").expect("default")
    }

    #[test]
    fn is_a_pure_function_of_seed_index_and_profile() {
        let p = default();
        assert_eq!(generate(1, 5, &p), generate(1, 5, &p));
        assert_ne!(generate(1, 5, &p), generate(1, 6, &p));
        assert_ne!(generate(1, 5, &p), generate(2, 5, &p));
        assert_ne!(run_seed(1, 0), run_seed(0, 1));
    }

    #[test]
    fn generated_scenarios_are_valid_files() {
        for profile in ["default", "noisy", "smoke", "quiet"] {
            let p = Profile::built_in(profile).expect(profile);
            for i in 0..150 {
                let g = generate(3, i, &p);
                let text = g.scenario.to_toml();
                let mut back = Scenario::from_toml("gen.toml", &text)
                    .unwrap_or_else(|e| panic!("{profile} run {i}: {e}\n{text}"));
                back.events.iter_mut().for_each(|e| e.line = 0);
                assert_eq!(back, g.scenario, "{profile} run {i}");
            }
        }
    }

    #[test]
    fn runs_keep_the_rules_of_the_generator() {
        let p = default();
        for i in 0..300 {
            let g = generate(11, i, &p);
            let sc = &g.scenario;
            let ctx = format!("run {i}:\n{}", sc.to_toml());
            assert!((2..=4).contains(&sc.floors), "{ctx}");
            assert!(start_range_mm(sc.floors).contains(&sc.start_mm), "{ctx}");
            assert!(
                sc.duration >= p.duration.0 && sc.duration <= p.duration.1,
                "{ctx}"
            );
            assert!(sc.events.windows(2).all(|w| w[0].at <= w[1].at), "{ctx}");
            assert_eq!(g.tail.len(), sc.events.len());
            // The tail comes last and ends with the probe, probe_lead before the end; only the
            // operator's start procedure, for starts that need it, comes before the activity.
            let first_tail = recovery_index(&g.tail, &sc.events).expect("a tail");
            assert!(g.tail[first_tail..].iter().all(|t| *t), "{ctx}");
            let preamble = g.tail.iter().take_while(|t| **t).count().min(first_tail);
            assert_eq!(preamble > 0, needs_rescue(sc.floors, sc.start_mm), "{ctx}");
            let probe = g.probe.expect("a probe");
            let last = sc.events.last().expect("events");
            assert_eq!(last.at, probe.at);
            assert_eq!(
                last.action,
                Action::Press {
                    button: Button::Cabin(probe.floor),
                    hold: crate::scenario::DEFAULT_HOLD
                }
            );
            assert_eq!(SimTime::ZERO + sc.duration - probe.at, p.probe_lead);
            // Every hold and power fail of the activity ends before the recovery.
            let recovery = sc.events[first_tail].at;
            let mut crank = 0.0;
            let mut offline = BTreeSet::new();
            let mut vanes = [SensorFault::None; 2];
            let mut load = sc.load;
            let mut door_closed = sc.door_closed;
            let mut attended = false;
            for (e, tail) in sc.events.iter().zip(&g.tail) {
                if !tail {
                    let busy = match e.action {
                        Action::Press { hold, .. } => hold,
                        Action::Fault(Fault::PowerFail { duration })
                        | Action::Fault(Fault::SafeLinkDrop { duration }) => duration,
                        _ => SimDuration::ZERO,
                    };
                    assert!(e.at + busy < recovery, "{ctx}");
                } else if e.action == Action::Attend {
                    assert_eq!(
                        e.at, recovery,
                        "the attendant comes with the repairs: {ctx}"
                    );
                    attended = true;
                }
                match e.action {
                    Action::Crank { mm } if !tail => crank += mm,
                    Action::Fault(Fault::SlaveOffline { slave }) => {
                        assert!(lab::address::ALL.contains(&slave));
                        offline.insert(slave);
                    }
                    Action::Fault(Fault::SlaveOnline { slave }) => {
                        offline.remove(&slave);
                    }
                    Action::Fault(Fault::Vane { sensor, fault }) => {
                        vanes[sensor_index(sensor) as usize] = fault;
                    }
                    Action::Load(l) => load = l,
                    Action::Door { closed } => door_closed = closed,
                    _ => {}
                }
                assert!(f64::abs(crank) <= MAX_CRANK_SUM_MM + 1e-9, "{ctx}");
            }
            assert!(offline.is_empty(), "{ctx}");
            assert!(load != LoadLevel::Overloaded && door_closed, "{ctx}");
            assert!(attended, "{ctx}");
            let broken = vanes.iter().filter(|f| **f != SensorFault::None).count();
            assert_eq!(broken, usize::from(!probe.judged), "{ctx}");
        }
    }

    #[test]
    fn a_campaign_covers_every_kind_of_event_and_setting() {
        let p = default();
        let mut seen = BTreeSet::new();
        let mut see = |s: String| {
            seen.insert(s);
        };
        let (mut lowest, mut highest) = (f64::MAX, f64::MIN);
        for i in 0..400 {
            let g = generate(1, i, &p);
            let sc = &g.scenario;
            see(format!("floors {}", sc.floors));
            see(format!("algorithm {:?}", sc.algorithm));
            see(format!("noise {}", sc.pulse_error_rate));
            see(format!("scan {}", sc.plc_scan));
            see(format!("extra {}", sc.extra_slaves > 0));
            see(format!("door {}", sc.door_closed));
            see(format!("power-on reset {}", sc.power_on_reset));
            see(format!("load {:?}", sc.load));
            see(format!("judged {}", g.probe.is_some_and(|p| p.judged)));
            if sc.floors == 4 {
                lowest = lowest.min(sc.start_mm);
                highest = highest.max(sc.start_mm);
            }
            for e in &sc.events {
                see(match &e.action {
                    Action::Press { button, hold } => format!(
                        "press {} {}",
                        button.key().split(':').next().unwrap_or(""),
                        *hold == crate::scenario::DEFAULT_HOLD
                    ),
                    Action::Load(l) => format!("load to {l:?}"),
                    Action::Door { closed } => format!("door to {closed}"),
                    Action::Crank { mm } => format!("crank {}", *mm > 0.0),
                    Action::Reset => "reset".into(),
                    Action::Rescue => "rescue".into(),
                    Action::Ack => "ack".into(),
                    Action::Attend => "attend".into(),
                    Action::Fault(Fault::SlaveOffline { slave }) => format!("offline {slave}"),
                    Action::Fault(Fault::SlaveOnline { slave }) => format!("online {slave}"),
                    Action::Fault(Fault::PowerFail { .. }) => "power-fail".into(),
                    Action::Fault(Fault::SafeLinkDrop { .. }) => "safe-link-drop".into(),
                    Action::Fault(Fault::Vane { sensor, fault }) => {
                        format!("vane {sensor:?} {fault:?}")
                    }
                    Action::Fault(
                        f @ (Fault::ConverterRunaway { .. }
                        | Fault::ConverterRepaired
                        | Fault::EncoderFailed
                        | Fault::EncoderRepaired
                        | Fault::LineNoise { .. }),
                    ) => {
                        format!("{f:?}")
                    }
                });
            }
        }
        let mut want: Vec<String> = vec![
            "floors 2",
            "floors 3",
            "floors 4",
            "algorithm Fifo",
            "algorithm Collective",
            "noise 0",
            "noise 0.001",
            "scan 10 ms",
            "scan 1 ms",
            "scan 20 ms",
            "extra true",
            "extra false",
            "door false",
            "power-on reset false",
            "load Overloaded",
            "judged false",
            "judged true",
            "press cabin true",
            "press cabin false",
            "press hall-up true",
            "press hall-down true",
            "press stop false",
            "press bell true",
            "load to Empty",
            "load to Loaded",
            "load to Full",
            "load to Overloaded",
            "door to false",
            "door to true",
            "crank true",
            "crank false",
            "reset",
            "rescue",
            "ack",
            "attend",
            "power-fail",
            "safe-link-drop",
            "vane Left StuckOn",
            "vane Left StuckOff",
            "vane Right StuckOn",
            "vane Right StuckOff",
            "vane Left None",
            "vane Right None",
        ]
        .into_iter()
        .map(String::from)
        .collect();
        for a in lab::address::ALL {
            want.push(format!("offline {a}"));
            want.push(format!("online {a}"));
        }
        let missing: Vec<&String> = want.iter().filter(|w| !seen.contains(*w)).collect();
        assert!(missing.is_empty(), "never generated: {missing:?}");
        // Start positions cover the whole legal range.
        let range = start_range_mm(4);
        assert!(lowest < range.start() + 60.0 && highest > range.end() - 60.0);
    }
}
