//! What the floor and cabin displays show (tables 6.3–6.5 of the lift thesis; docs/controller.md):
//! the program against the lift plant, without the bus, every display word of every 10 ms scan
//! recorded.
//!
//! The rule the tables give: the current floor is shown at departure and on arrival
//! ("Aktuální patro → Jede", "Dobrždění → Aktuální patro"), not while floors are passed;
//! initialisation shows floor 1 and "down", its last step ("Brzdí → 1. Patro") included.

use crate::common;

use asi_phy::{SimDuration, SimTime};
use controller::{ControllerConfig, Program, ProgramEventKind, State};
use lab::DisplayWord;
use lift_model::{Button, Lift, LiftConfig, LoadLevel};

const SCAN: SimDuration = SimDuration::from_millis(10);

struct Loop {
    lift: Lift,
    prog: Program,
    now: SimTime,
    bus_ok: bool,
    /// (scan time, display, events of that scan).
    scans: Vec<(SimTime, DisplayWord, Vec<ProgramEventKind>)>,
}

impl Loop {
    fn new(start_mm: f64) -> Loop {
        let lift = Lift::new({
            let mut cfg = LiftConfig::default();
            cfg.initial_position_mm = start_mm;
            cfg
        })
        .expect("lift");
        let prog = Program::new(ControllerConfig::default()).expect("program");
        let mut l = Loop {
            lift,
            prog,
            now: SimTime::ZERO,
            bus_ok: true,
            scans: Vec::new(),
        };
        l.lift.set_contactor(SimTime::ZERO, true).expect("K1");
        l
    }

    fn scan(&mut self) {
        self.now += SCAN;
        let _ = self.lift.advance_to(self.now).expect("plant").count();
        let inp = common::plant_inputs(&self.lift, true, self.bus_ok);
        let out = self.prog.scan(self.now, &inp);
        self.lift
            .set_converter(self.now, out.run, out.up, out.setpoint_ua)
            .expect("converter");
        let events = self.prog.drain_events().map(|e| e.kind).collect();
        self.scans.push((self.now, out.display, events));
    }

    fn run_until(&mut self, limit: SimDuration, mut done: impl FnMut(&Loop) -> bool) {
        let end = self.now + limit;
        while self.now < end {
            self.scan();
            if done(self) {
                return;
            }
        }
        panic!("not done within {limit:?}");
    }

    fn run_for(&mut self, d: SimDuration) {
        let end = self.now + d;
        while self.now < end {
            self.scan();
        }
    }

    fn press(&mut self, b: Button) {
        self.lift
            .press(self.now, b, SimDuration::from_millis(300))
            .expect("press");
    }

    fn saw(&self, want: impl Fn(&ProgramEventKind) -> bool) -> bool {
        self.scans.iter().any(|(_, _, e)| e.iter().any(&want))
    }

    /// The display in the scan of the first event matching `want`, from scan `from` on.
    fn display_at(&self, from: usize, want: impl Fn(&ProgramEventKind) -> bool) -> DisplayWord {
        self.scans[from..]
            .iter()
            .find(|(_, _, e)| e.iter().any(&want))
            .map(|(_, d, _)| *d)
            .expect("event")
    }

    /// The distinct displays from scan `from` on, in order, repeats folded.
    fn shown(&self, from: usize) -> Vec<Shown> {
        let mut v: Vec<Shown> = Vec::new();
        for (_, d, _) in &self.scans[from..] {
            let s = Shown::of(d);
            if v.last() != Some(&s) {
                v.push(s);
            }
        }
        v
    }
}

/// A display word in short: floor, arrow ('↑', '↓' or '-'), moving, fault.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Shown(u8, char, bool, bool);

impl Shown {
    fn of(d: &DisplayWord) -> Shown {
        let arrow = match (d.up, d.down) {
            (true, false) => '↑',
            (false, true) => '↓',
            (false, false) => '-',
            _ => '?',
        };
        Shown(d.floor, arrow, d.moving, d.fault)
    }
}

const MOVING: bool = true;
const STANDING: bool = false;
const FAULT: bool = true;
const OK: bool = false;

fn initialised(start_mm: f64) -> Loop {
    let mut l = Loop::new(start_mm);
    l.run_until(SimDuration::from_secs(60), |l| l.prog.is_initialised());
    l.run_for(SimDuration::from_secs(3));
    l
}

/// Table 6.3: "Jede" shows floor 1 and "down"; "Brzdí" keeps them; "Brzdí → 1. Patro"
/// ("Zobrazení směru jízdy dolů") stops the motor and still shows floor 1 and "down".
#[test]
fn initialisation_shows_floor_1_and_down_to_its_last_step() {
    // Between floors 2 and 3: the lift thesis' routine runs down past floor 2's vane to floor 1.
    let l = initialised(650.0);
    assert_eq!(
        l.shown(0),
        [Shown(1, '↓', MOVING, OK), Shown(1, '↓', STANDING, OK)],
        "{:?}",
        l.shown(0)
    );
    let last_step = l.display_at(0, |e| *e == ProgramEventKind::Initialised);
    assert_eq!(Shown::of(&last_step), Shown(1, '↓', STANDING, OK));
}

/// The starts asi-lift adds to table 6.3 (level at a floor, inside floor 1's vane above or
/// below level) creep up as well as down; the displays show floor 1 and "down" all the same.
#[test]
fn every_initialisation_shows_floor_1_and_down() {
    for start in [0.0, 25.0, -25.0, 400.0, 1100.0] {
        let l = initialised(start);
        assert_eq!(
            l.shown(0),
            [Shown(1, '↓', MOVING, OK), Shown(1, '↓', STANDING, OK)],
            "from {start} mm"
        );
    }
}

/// Table 6.5, a journey 1 → 3: "Aktuální patro → Jede nahoru" shows floor 1 and "up";
/// passing floor 2 and braking for floor 3 change nothing; "Dobrždění → Aktuální patro"
/// shows floor 3 without an arrow.
#[test]
fn a_journey_up_shows_the_departure_floor_until_the_arrival() {
    let mut l = initialised(650.0);
    let from = l.scans.len() - 1;
    l.press(Button::Cabin(3));
    l.run_until(SimDuration::from_secs(30), |l| {
        l.saw(|e| *e == ProgramEventKind::Arrived { floor: 3 })
    });
    l.run_for(SimDuration::from_secs(1));
    assert_eq!(
        l.shown(from),
        [
            Shown(1, '↓', STANDING, OK), // left from initialisation
            Shown(1, '↑', MOVING, OK),   // departure
            Shown(3, '-', STANDING, OK), // arrival
        ]
    );
    let departed = l.display_at(from, |e| matches!(e, ProgramEventKind::Departed { .. }));
    assert_eq!(Shown::of(&departed), Shown(1, '↑', MOVING, OK));
    let passed = l.display_at(from, |e| *e == ProgramEventKind::Passed { floor: 2 });
    assert_eq!(
        Shown::of(&passed),
        Shown(1, '↑', MOVING, OK),
        "passing floor 2"
    );
    let braking = l.display_at(from, |e| *e == ProgramEventKind::Braking { floor: 3 });
    assert_eq!(
        Shown::of(&braking),
        Shown(1, '↑', MOVING, OK),
        "braking for 3"
    );
    let arrived = l.display_at(from, |e| *e == ProgramEventKind::Arrived { floor: 3 });
    assert_eq!(Shown::of(&arrived), Shown(3, '-', STANDING, OK));
}

/// Table 6.4, a journey 4 → 1: floor 4 and "down" until the arrival at floor 1.
#[test]
fn a_journey_down_shows_the_departure_floor_until_the_arrival() {
    let mut l = initialised(650.0);
    l.press(Button::Cabin(4));
    l.run_until(SimDuration::from_secs(40), |l| {
        l.saw(|e| *e == ProgramEventKind::Arrived { floor: 4 })
    });
    l.run_for(SimDuration::from_secs(3));
    let from = l.scans.len() - 1;
    l.press(Button::Cabin(1));
    l.run_until(SimDuration::from_secs(40), |l| {
        l.saw(|e| *e == ProgramEventKind::Arrived { floor: 1 })
    });
    l.run_for(SimDuration::from_secs(1));
    assert_eq!(
        l.shown(from),
        [
            Shown(4, '-', STANDING, OK),
            Shown(4, '↓', MOVING, OK),
            Shown(1, '-', STANDING, OK),
        ]
    );
}

/// Tables 6.4/6.5, "Aktuální patro ↔ Porucha přetížení": the floor number, no arrow, both
/// ways; here it also clears the "down" left from initialisation.
#[test]
fn overload_shows_the_floor_without_an_arrow() {
    let mut l = initialised(650.0);
    let from = l.scans.len() - 1;
    l.lift.set_load(l.now, LoadLevel::Overloaded).expect("load");
    l.run_for(SimDuration::from_secs(2));
    l.lift.set_load(l.now, LoadLevel::Loaded).expect("load");
    l.run_for(SimDuration::from_secs(2));
    assert_eq!(
        l.shown(from),
        [
            Shown(1, '↓', STANDING, OK),
            Shown(1, '-', STANDING, FAULT),
            Shown(1, '-', STANDING, OK),
        ]
    );
}

/// STOP while travelling 1 → 4 (tables 6.4/6.5, "Jede → Porucha Stop → Dobrždění → Aktuální
/// patro"): the departure floor and "up" until the cabin stops at floor 3, then floor 3
/// without an arrow, with the fault bit while it waits for a cabin request.
#[test]
fn stop_shows_the_floor_it_stops_at_on_arrival() {
    let mut l = initialised(650.0);
    l.press(Button::Cabin(4));
    l.run_until(SimDuration::from_secs(20), |l| l.lift.position_mm() > 450.0);
    let from = l.scans.len();
    l.press(Button::Stop);
    l.run_until(SimDuration::from_secs(20), |l| {
        l.saw(|e| *e == ProgramEventKind::Arrived { floor: 3 })
    });
    l.run_for(SimDuration::from_secs(1));
    assert_eq!(
        l.shown(from),
        [Shown(1, '↑', MOVING, OK), Shown(3, '-', STANDING, FAULT)]
    );
    assert_eq!(l.prog.state(), State::StopFault);
}

/// A bus fault during travel (the tables are silent): the floor and arrow shown stay, the
/// cabin is shown standing, with the fault bit.
#[test]
fn a_bus_fault_keeps_the_floor_and_arrow_shown() {
    let mut l = initialised(650.0);
    l.press(Button::Cabin(3));
    l.run_until(SimDuration::from_secs(20), |l| l.lift.position_mm() > 200.0);
    let from = l.scans.len();
    l.bus_ok = false;
    l.run_for(SimDuration::from_millis(500));
    assert_eq!(l.shown(from), [Shown(1, '↑', STANDING, FAULT)]);
}
