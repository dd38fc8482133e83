//! A second front end: the protocol of the TTK4145 lab elevator (NTNU's real-time course and
//! its Simulator-v2), mapped onto the lab lift (the book, "The TTK4145 front end").
//!
//! Every message is 4 bytes, `[opcode, a, b, c]`; reads get a 4-byte answer, writes none.
//! Floors count from 0 (lab floor 1 is TTK floor 0); buttons are 0 hall up, 1 hall down,
//! 2 cabin. The mapping:
//!
//! | opcode | TTK4145 | on the lab lift |
//! |---|---|---|
//! | 0 | reload config | nothing |
//! | 1 | motor direction `a` = 1 up, 0 stop, 255 (−1) down | the converter (slave 7: D0 run, D1 up) and the speed set-point (slave 10) through the AS-i output image: travel 10000 µA, stop = run off and 4000 µA (a ramp stop); a move while the STOP circuit waits for its restart pulses the restart first |
//! | 2 | button lamp `a` type, `b` floor, `c` value | recorded (the lab lift has no call lamps) |
//! | 3 | floor indicator `a` | the lab's displays (floor stations 1..4, cabin display 5): the front end runs the PLC side of their handshakes (tables 4.2–4.5 of the lift thesis) every 10 ms, showing the indicator's floor, the arrow of the motor's direction and "moving"; also recorded |
//! | 4 | door open lamp `a` | recorded |
//! | 5 | stop lamp `a` | recorded |
//! | 6 | read button `a` type, `b` floor → `[6, pressed, 0, 0]` | the plant's button, held or not |
//! | 7 | read floor sensor → `[7, at, floor, 0]` | at = the cabin stands in a floor's level zone (both vane sensors on its vane, ±10 mm) |
//! | 8 | read stop → `[8, pressed, 0, 0]` | the cabin's STOP button |
//! | 9 | read obstruction → `[9, active, 0, 0]` | the door is open |
//!
//! The overload goes to the safety logic from the load sensor's nibble as the built-in program
//! reads it ([`LoadReading`]: D1..D0 = 3, or D2 "operation ready" = 0 when the sensor is off
//! the bus or not ready, the unsafe value of an unreadable input), at every message. Unknown opcodes and reads of a floor or button that does
//! not exist get no answer and count as exceptions.

use crate::map::Gateway;
use asi_master::plc_handshake::{CabinDisplayMaster, FloorStationMaster};
use asi_phy::{SimDuration, SimTime, SlaveAddr};
use controller::plc::{LoadReading, ToSafety};
use lab::address::{CABIN_DISPLAY, CONVERTER, FLOOR_1, FLOOR_STATIONS, SPEED_SETPOINT};
use lab::display::DisplayWord;
use lab::setpoint::STANDSTILL_UA;
use lift_model::Button;
use rig::report::{Actor, ClientLog};
use rig::Rig;
use std::collections::BTreeMap;

/// The set-point of a TTK4145 move: the lab program's travel speed (59.4 mm/s; its braking
/// distance, about 8 mm, ends inside the ±10 mm level zone when the client stops at the
/// floor sensor).
pub const TRAVEL_UA: u16 = 10_000;

/// How long the restart pulse of a move lasts: several PLC scans and safety scans.
const RESTART_PULSE: SimDuration = SimDuration::from_millis(50);

/// How often the front end steps the display handshakes: the built-in program's scan.
const DISPLAY_SCAN: SimDuration = SimDuration::from_millis(10);

/// The TTK4145 front end's state: the motor command, the lamps the client set, and the PLC
/// side of the display handshakes once a client has spoken.
#[derive(Clone, Debug, Default)]
pub struct Ttk {
    /// A TTK4145 client has sent a message: the front end drives the displays.
    active: bool,
    /// The floor indicator, lab floors (1..).
    indicator: Option<u8>,
    /// The PLC side of the floor stations' and the cabin display's handshakes.
    floors: Vec<FloorStationMaster>,
    cabin_display: CabinDisplayMaster,
    /// The word last handed to the handshakes.
    shown: Option<u16>,
    /// When the handshakes step next.
    next_scan: SimTime,
    /// The last motor direction: 1 up, 0 stop, −1 down.
    motor: i8,
    /// Lamps by name, as the client last set them.
    lamps: BTreeMap<String, u8>,
    /// Until when the restart pulse of a move lasts.
    restart_until: Option<SimTime>,
}

impl Ttk {
    /// Serves one message at `at`; the answer, if the message is a read.
    pub fn serve(
        &mut self,
        rig: &mut Rig,
        gw: &mut Gateway,
        at: SimTime,
        msg: [u8; 4],
    ) -> Option<[u8; 4]> {
        gw.requests += 1;
        if !self.active {
            self.active = true;
            self.floors = (0..FLOOR_STATIONS)
                .map(|_| FloorStationMaster::new())
                .collect();
            self.next_scan = at;
        }
        if self.restart_until.is_some_and(|t| at >= t) {
            self.restart_until = None;
        }
        let answer = self.dispatch(rig, at, msg);
        // The controller's signals to the safety logic: the restart pulse of a move, and the
        // overload as the built-in program reads it (a load sensor that is off the bus or not
        // ready counts as overloaded), at every message.
        let load = LoadReading::of(&rig.lab().bus().image().input);
        gw.set_signals(
            rig,
            ToSafety {
                restart: self.restart_until.is_some(),
                overloaded: load.overloaded(),
            },
        );
        if answer.is_none() && !(0..=5).contains(&msg[0]) {
            gw.exceptions += 1;
        }
        // Any message is a sign of life: a TTK4145 client writes the motor only when it
        // changes, so reads keep the watchdog quiet too.
        gw.alive(rig, at);
        answer
    }

    fn dispatch(&mut self, rig: &mut Rig, at: SimTime, [op, a, b, c]: [u8; 4]) -> Option<[u8; 4]> {
        let floors = rig.lift().config().floors;
        let lift = rig.lift();
        match op {
            0 => None,
            1 => {
                self.motor(rig, at, a as i8);
                None
            }
            2 => {
                let kind = match a {
                    0 => "hall-up",
                    1 => "hall-down",
                    _ => "cabin",
                };
                self.lamp(rig, format!("{kind} lamp {}", u16::from(b) + 1), c);
                None
            }
            3 => {
                let floor = a.saturating_add(1);
                self.indicator = Some(floor);
                self.lamp(rig, "floor indicator".into(), floor);
                None
            }
            4 => {
                self.lamp(rig, "door lamp".into(), a);
                None
            }
            5 => {
                self.lamp(rig, "stop lamp".into(), a);
                None
            }
            6 => {
                let floor = b.checked_add(1).filter(|f| *f <= floors)?;
                let button = match a {
                    0 => Button::HallUp(floor),
                    1 => Button::HallDown(floor),
                    2 => Button::Cabin(floor),
                    _ => return None,
                };
                Some([6, u8::from(lift.is_pressed(button)), 0, 0])
            }
            7 => {
                let level = lift
                    .in_level_zone()
                    .then(|| lift.config().level_floor(lift.position_mm()))
                    .flatten();
                Some(match level {
                    Some(f) => [7, 1, f - 1, 0],
                    None => [7, 0, 0, 0],
                })
            }
            8 => Some([8, u8::from(lift.stop_pressed()), 0, 0]),
            9 => Some([9, u8::from(!lift.door_closed()), 0, 0]),
            _ => None,
        }
    }

    /// Motor direction `dir`: the converter's nibble and the set-point in the output image,
    /// and the controller's signals to the safety logic.
    fn motor(&mut self, rig: &mut Rig, at: SimTime, dir: i8) {
        let dir = dir.signum();
        let moving = dir != 0;
        let image = &mut rig.lab_mut().bus_mut().image_mut();
        if let Some(a) = SlaveAddr::a(CONVERTER) {
            let nibble = u8::from(moving) | u8::from(dir > 0) << 1;
            if let Some(n) = asi_phy::Nibble::new(nibble) {
                image.output.set_nibble(a, n);
            }
        }
        image.output.set_analog(
            SPEED_SETPOINT,
            1,
            if moving { TRAVEL_UA } else { STANDSTILL_UA },
        );
        // A move while the STOP circuit is not running asks for its restart, as the built-in
        // program does after a cabin request; the safety logic decides.
        if moving && !rig.estop_out() && !rig.lift().stop_pressed() && self.restart_until.is_none()
        {
            self.restart_until = Some(at + RESTART_PULSE);
        }
        if dir != self.motor {
            self.motor = dir;
            rig.log_now(Actor::Ttk4145, ClientLog::Motor(dir.signum()));
        }
    }

    /// A lamp the lab lift lacks: logged when it changes.
    fn lamp(&mut self, rig: &mut Rig, name: String, value: u8) {
        if self.lamps.get(&name) != Some(&value) {
            let lamp = ClientLog::Lamp {
                name: name.clone(),
                value,
            };
            rig.log_now(Actor::Ttk4145, lamp);
            self.lamps.insert(name, value);
        }
    }

    /// Steps the display handshakes every 10 ms up to `at`, once a client has spoken: the
    /// floor stations and the cabin display show the indicator's floor, the arrow of the
    /// motor's direction and "moving" while the motor runs.
    pub fn scan(&mut self, rig: &mut Rig, at: SimTime) {
        if !self.active || at < self.next_scan {
            return;
        }
        self.next_scan = at + DISPLAY_SCAN;
        if let Some(floor) = self.indicator {
            let word = DisplayWord {
                floor,
                up: self.motor > 0,
                down: self.motor < 0,
                moving: self.motor != 0,
                fault: false,
            };
            if let Ok(w) = word.encode() {
                if self.shown != Some(w) {
                    self.shown = Some(w);
                    for station in &mut self.floors {
                        station.set_word(w);
                    }
                    self.cabin_display.set_word(w);
                }
            }
        }
        let image = rig.lab_mut().bus_mut().image_mut();
        for (i, station) in self.floors.iter_mut().enumerate() {
            if let Some(a) = SlaveAddr::a(FLOOR_1 + i as u8) {
                image
                    .output
                    .set_nibble(a, station.step(image.input.nibble(a)));
            }
        }
        if let Some(a) = SlaveAddr::a(CABIN_DISPLAY) {
            image
                .output
                .set_nibble(a, self.cabin_display.step(image.input.nibble(a)));
        }
    }

    /// The lamps as the client left them.
    pub fn lamps(&self) -> &BTreeMap<String, u8> {
        &self.lamps
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::Owner;
    use lift_model::{DisplayId, DisplayState};
    use rig::Scenario;

    #[test]
    fn a_load_sensor_off_the_bus_counts_as_overloaded_and_the_cabin_stays() {
        let toml = "name = \"t\"\nduration = \"10s\"\n[lift]\nstart_mm = 0.0\n";
        let sc = Scenario::from_toml("t.toml", toml).expect("a scenario");
        let mut rig = Rig::new(sc).expect("a rig").with_external_controller();
        let mut gw = Gateway::new(Owner::External, SimDuration::from_secs(1));
        let mut ttk = Ttk::default();
        let mut at = SimTime::ZERO;
        let mut run_to = |rig: &mut Rig, gw: &mut Gateway, ttk: &mut Ttk, until: SimTime| {
            while at < until {
                let next = at + SimDuration::from_millis(1);
                at = crate::live::advance(rig, gw, ttk, at, next);
                // A client polls the stop button, as course programs do.
                ttk.serve(rig, gw, at, [8, 0, 0, 0]);
            }
            at
        };
        let t = run_to(&mut rig, &mut gw, &mut ttk, SimTime::from_millis(500));
        rig.act_now(
            Actor::Rig,
            &rig::scenario::Action::Fault(rig::scenario::Fault::SlaveOffline {
                slave: lab::address::LOAD_SENSOR,
            }),
        );
        let t = run_to(
            &mut rig,
            &mut gw,
            &mut ttk,
            t + SimDuration::from_millis(500),
        );
        let start_mm = rig.lift().position_mm();
        ttk.serve(&mut rig, &mut gw, t, [1, 1, 0, 0]);
        run_to(
            &mut rig,
            &mut gw,
            &mut ttk,
            t + SimDuration::from_millis(4_000),
        );
        assert!(!rig.lift().k1_closed(), "K1 closed with the load unknown");
        let moved = rig.lift().position_mm() - start_mm;
        assert!(moved.abs() < 1.0, "the cabin moved {moved} mm");
    }

    #[test]
    fn the_floor_indicator_and_the_motor_show_on_the_labs_displays() {
        let toml = "name = \"t\"\nduration = \"10s\"\n[lift]\nstart_mm = 0.0\n";
        let sc = Scenario::from_toml("t.toml", toml).expect("a scenario");
        let mut rig = Rig::new(sc).expect("a rig").with_external_controller();
        let mut gw = Gateway::new(Owner::External, SimDuration::from_secs(1));
        let mut ttk = Ttk::default();
        let t0 = SimTime::ZERO;
        assert_eq!(ttk.serve(&mut rig, &mut gw, t0, [3, 2, 0, 0]), None);
        assert_eq!(ttk.serve(&mut rig, &mut gw, t0, [1, 1, 0, 0]), None);
        let mut at = t0;
        while at < SimTime::from_millis(3_000) {
            let next = at + SimDuration::from_millis(1);
            at = crate::live::advance(&mut rig, &mut gw, &mut ttk, at, next);
        }
        let shown = DisplayState::Showing(DisplayWord {
            floor: 3,
            up: true,
            down: false,
            moving: true,
            fault: false,
        });
        for id in [DisplayId::Floor(1), DisplayId::Floor(4), DisplayId::Cabin] {
            assert_eq!(rig.lift().display(id), Some(shown), "{id:?}");
        }
        // Stopped: the floor without arrows.
        assert_eq!(ttk.serve(&mut rig, &mut gw, at, [1, 0, 0, 0]), None);
        let until = at + SimDuration::from_millis(1_000);
        while at < until {
            let next = at + SimDuration::from_millis(1);
            at = crate::live::advance(&mut rig, &mut gw, &mut ttk, at, next);
        }
        let Some(DisplayState::Showing(w)) = rig.lift().display(DisplayId::Cabin) else {
            panic!("the cabin display shows a word");
        };
        assert_eq!((w.floor, w.up, w.down, w.moving), (3, false, false, false));
    }
}
