//! The program against the lift plant directly, without the bus: each 10 ms scan reads the plant's
//! signals and writes the converter. Tests the logic of tables 6.3–6.5 of the lift thesis; the full
//! rig with the AS-i handshakes and the safety logic is tested in the workspace's tests crate.

use crate::common;

use asi_phy::{SimDuration, SimTime};
use controller::{Algorithm, ControllerConfig, Program, ProgramEventKind, Source, State};
use lift_model::{Button, Lift, LiftConfig, LoadLevel};

struct Loop {
    lift: Lift,
    prog: Program,
    now: SimTime,
    events: Vec<(SimTime, ProgramEventKind)>,
    estop_ok: bool,
}

const SCAN: SimDuration = SimDuration::from_millis(10);

impl Loop {
    fn new(start_mm: f64, algorithm: Algorithm) -> Loop {
        let lift = Lift::new({
            let mut cfg = LiftConfig::default();
            cfg.initial_position_mm = start_mm;
            cfg
        })
        .expect("lift");
        let prog = Program::new({
            let mut cfg = ControllerConfig::default();
            cfg.algorithm = algorithm;
            cfg
        })
        .expect("program");
        let mut l = Loop {
            lift,
            prog,
            now: SimTime::ZERO,
            events: Vec::new(),
            estop_ok: true,
        };
        l.lift.set_contactor(SimTime::ZERO, true).expect("K1");
        l
    }

    fn scan(&mut self) {
        self.now += SCAN;
        let _ = self.lift.advance_to(self.now).expect("plant").count();
        let inp = common::plant_inputs(&self.lift, self.estop_ok, true);
        let out = self.prog.scan(self.now, &inp);
        self.lift
            .set_converter(self.now, out.run, out.up, out.setpoint_ua)
            .expect("converter");
        let now = self.now;
        self.events
            .extend(self.prog.drain_events().map(|e| (now, e.kind)));
    }

    fn run_for(&mut self, d: SimDuration) {
        let end = self.now + d;
        while self.now < end {
            self.scan();
        }
    }

    fn run_until(&mut self, limit: SimDuration, mut done: impl FnMut(&Loop) -> bool) -> bool {
        let end = self.now + limit;
        while self.now < end {
            self.scan();
            if done(self) {
                return true;
            }
        }
        false
    }

    fn press(&mut self, b: Button) {
        self.lift
            .press(self.now, b, SimDuration::from_millis(300))
            .expect("press");
    }

    fn arrivals(&self) -> Vec<u8> {
        self.events
            .iter()
            .filter_map(|(_, e)| match e {
                ProgramEventKind::Arrived { floor } => Some(*floor),
                _ => None,
            })
            .collect()
    }

    fn served(&self) -> Vec<(u8, Source)> {
        self.events
            .iter()
            .filter_map(|(_, e)| match e {
                ProgramEventKind::Served(s) => Some((s.floor, s.source)),
                _ => None,
            })
            .collect()
    }

    fn level_at(&self, floor: u8) -> bool {
        let level = (floor as f64 - 1.0) * 400.0;
        (self.lift.position_mm() - level).abs() <= 10.0 && self.lift.velocity_mm_s() == 0.0
    }
}

fn initialised(start_mm: f64) -> Loop {
    let mut l = Loop::new(start_mm, Algorithm::Fifo);
    assert!(
        l.run_until(SimDuration::from_secs(60), |l| l.prog.is_initialised()),
        "not initialised from {start_mm} mm: {:?}",
        l.events
    );
    l.run_for(SimDuration::from_secs(1));
    l
}

#[test]
fn initialises_from_every_kind_of_start_height() {
    // Between floors, in floor 1's long track above and below level, level at floor 1 (the
    // case the lift thesis' routine cannot handle), level at floors 2 and 4, inside floor 3's vane.
    for start in [650.0, 25.0, -25.0, 0.0, 400.0, 1200.0, 830.0, 1100.0] {
        let l = initialised(start);
        assert!(
            l.level_at(1),
            "from {start} mm: ended at {} mm",
            l.lift.position_mm()
        );
        assert!(
            l.lift.overtravel_bottom_free(),
            "from {start} mm: overtravel tripped"
        );
        assert_eq!(l.prog.current_floor(), 1);
    }
}

#[test]
fn a_cabin_call_takes_the_cabin_level_to_its_floor() {
    let mut l = initialised(650.0);
    l.press(Button::Cabin(3));
    assert!(l.run_until(SimDuration::from_secs(30), |l| l.arrivals().contains(&3)));
    l.run_for(SimDuration::from_secs(1));
    assert!(l.level_at(3), "at {} mm", l.lift.position_mm());
    assert_eq!(l.prog.state(), State::AtFloor);
}

#[test]
fn cabin_calls_are_served_first_in_order_then_hall_calls() {
    let mut l = initialised(650.0);
    l.press(Button::Cabin(4));
    l.run_for(SimDuration::from_millis(500));
    l.press(Button::HallUp(2));
    l.run_for(SimDuration::from_millis(500));
    l.press(Button::Cabin(3));
    l.run_for(SimDuration::from_millis(500));
    l.press(Button::HallDown(4));
    assert!(l.run_until(SimDuration::from_secs(120), |l| l.arrivals().len() >= 3));
    l.run_for(SimDuration::from_secs(10));
    // The cabin call to 4, then the cabin call to 3 pressed later, then the hall call at 2;
    // the hall call at 4 is served by the first stop there.
    assert_eq!(l.arrivals(), [4, 3, 2]);
    let served = l.served();
    assert_eq!(
        served,
        [
            (4, Source::Cabin),
            (4, Source::Hall),
            (3, Source::Cabin),
            (2, Source::Hall)
        ]
    );
}

#[test]
fn stop_while_moving_stops_at_the_next_floor_and_waits_for_a_cabin_request() {
    let mut l = initialised(650.0);
    l.press(Button::Cabin(4));
    // Leave floor 1 and pass floor 2's vane, then STOP.
    assert!(l.run_until(SimDuration::from_secs(20), |l| l.lift.position_mm() > 450.0));
    l.press(Button::Stop);
    assert!(l.run_until(SimDuration::from_secs(20), |l| l.arrivals().contains(&3)));
    l.run_for(SimDuration::from_secs(2));
    assert!(l.level_at(3));
    assert_eq!(l.prog.state(), State::StopFault);
    // Nothing happens without a cabin request ...
    l.press(Button::HallDown(2));
    l.run_for(SimDuration::from_secs(5));
    assert!(l.level_at(3));
    // ... a cabin request resumes service.
    l.press(Button::Cabin(1));
    assert!(l.run_until(SimDuration::from_secs(40), |l| l
        .arrivals()
        .ends_with(&[1, 2])));
}

#[test]
fn overload_and_an_open_door_block_departure() {
    let mut l = initialised(650.0);
    l.lift.set_load(l.now, LoadLevel::Overloaded).expect("load");
    l.press(Button::Cabin(2));
    l.run_for(SimDuration::from_secs(5));
    assert!(l.level_at(1));
    assert_eq!(l.prog.state(), State::OverloadFault);
    l.lift.set_load(l.now, LoadLevel::Loaded).expect("load");
    l.lift.set_door(l.now, false).expect("door");
    l.run_for(SimDuration::from_secs(5));
    assert!(l.level_at(1), "left with the door open");
    l.lift.set_door(l.now, true).expect("door");
    assert!(l.run_until(SimDuration::from_secs(20), |l| l.arrivals().contains(&2)));
}

#[test]
fn collective_control_stops_on_the_way_in_the_direction_of_travel() {
    let mut l = Loop::new(650.0, Algorithm::Collective);
    assert!(l.run_until(SimDuration::from_secs(60), |l| l.prog.is_initialised()));
    l.press(Button::Cabin(4));
    l.run_for(SimDuration::from_millis(300));
    l.press(Button::HallDown(3));
    l.press(Button::HallUp(2));
    assert!(l.run_until(SimDuration::from_secs(120), |l| l.arrivals().len() >= 3));
    // Up: 2 (hall up), 4 (cabin), then down: 3 (hall down).
    assert_eq!(l.arrivals(), [2, 4, 3]);
    let served = l.served();
    assert_eq!(
        served,
        [(2, Source::Hall), (4, Source::Cabin), (3, Source::Hall)]
    );
}
