//! The plant: state, inputs, outputs and the event loop (SPEC §4).

use std::collections::VecDeque;

use asi_phy::{SimDuration, SimTime};

use crate::config::{ConfigError, LiftConfig};
use crate::controls::{Button, Buttons, ContactFault, LoadLevel, SensorFault, StopChannel};
use crate::display::{DisplayId, DisplayState};
use crate::event::{Crash, EventKind, PlantEvent};
use crate::motion::{Segment, SegmentEnd};
use crate::shaft::{End, Levels, Shaft, VaneSensor};

/// Why an input was refused. The plant is unchanged by a refused input, except that time has
/// moved on to `now` if it was later than the plant's time.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PlantError {
    /// An input or `advance_to` earlier than the plant's own time.
    #[error("input at {now} is earlier than the plant's time {plant_time}: simulated time only moves forward")]
    TimeReversed {
        /// The time given.
        now: SimTime,
        /// The plant's time.
        plant_time: SimTime,
    },
    /// A button the lift does not have.
    #[error("the {floors}-floor lift has no {button} (there is no hall up at the top floor and no hall down at floor 1)")]
    NoSuchButton {
        /// The button asked for.
        button: Button,
        /// The lift's floors.
        floors: u8,
    },
    /// A press of zero duration, which no one could observe.
    #[error("a press of the {button} must last at least 1 ns")]
    EmptyPress {
        /// The button asked for.
        button: Button,
    },
    /// A display the lift does not have.
    #[error("the {floors}-floor lift has no display at floor {floor}")]
    NoSuchDisplay {
        /// The floor asked for.
        floor: u8,
        /// The lift's floors.
        floors: u8,
    },
    /// A crank distance that is NaN or infinite.
    #[error("crank distance {distance_mm:?} mm is not a finite number")]
    CrankDistance {
        /// The distance given.
        distance_mm: f64,
    },
    /// The crank needs the drive without power (seed 003 §6.3).
    #[error("the hand crank is refused while contactor K1 is closed: the drive has power")]
    CrankWhilePowered,
    /// The crank needs the cabin at rest.
    #[error("the hand crank is refused while the cabin moves ({velocity_mm_s:.3} mm/s)")]
    CrankWhileMoving {
        /// The cabin's velocity.
        velocity_mm_s: f64,
    },
    /// The cabin already touches the mechanical end in the direction asked.
    #[error(
        "the cabin stands against the {end} mechanical end: it cannot be cranked further that way"
    )]
    CrankBlocked {
        /// Which end.
        end: End,
    },
}

/// What moves the cabin now; a change of goal re-plans the motion.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Goal {
    /// The converter has power and no fault: it ramps to this velocity (0 when not running).
    Drive { v_target: f64 },
    /// No drive power, or the converter is faulted: the brake holds or stops the cabin.
    Brake,
    /// A person turns the motor by hand to this position.
    Crank { target_mm: f64 },
}

/// Contactor K1 between the mains and the converter (SPEC §4, §6).
#[derive(Clone, Copy, Debug)]
struct Contactor {
    coil: bool,
    main_closed: bool,
    weld_fault: bool,
}

/// The converter's inputs and internal faults.
#[derive(Clone, Copy, Debug)]
struct Converter {
    run: bool,
    up: bool,
    setpoint_ua: u16,
    injected_fault: bool,
    stalled: bool,
}

/// The events queued since the caller last drained them, in time order.
pub struct Events<'a>(std::collections::vec_deque::Drain<'a, PlantEvent>);

impl Iterator for Events<'_> {
    type Item = PlantEvent;
    fn next(&mut self) -> Option<PlantEvent> {
        self.0.next()
    }
    fn size_hint(&self) -> (usize, Option<usize>) {
        self.0.size_hint()
    }
}

impl ExactSizeIterator for Events<'_> {}

/// The laboratory lift of seed 003 as a plant: shaft, cabin, converter, motor, brake, K1,
/// sensors, buttons, door, load and displays (SPEC §4). Sans-IO: time is passed in.
///
/// # Time and events
///
/// The plant has its own time [`Lift::now`]. [`Lift::next_event`] says when the next edge
/// happens under the present inputs; [`Lift::advance_to`] moves to a later time and returns
/// every edge up to and including it, in time order, each at the first nanosecond at which
/// its new state holds (see the crate documentation for the rounding rule). Edges at one
/// nanosecond come in this order: button releases, sensor edges in the order the cabin meets
/// them, then the end of the motion segment. The result does not depend on how the caller
/// steps: one call to `t`, a million small ones, or jumps from event to event give the same
/// events at the same times and the same state.
///
/// Every input method takes `now ≥` [`Lift::now`], first brings the plant to `now` (queuing the
/// edges on the way, returned by the next `advance_to`), then applies the input at `now`.
#[derive(Clone, Debug)]
pub struct Lift {
    config: LiftConfig,
    shaft: Shaft,
    ramp_mm_s2: f64,
    now: SimTime,
    motion: Segment,
    /// Boundaries `shaft.boundaries[..split]` are below the cabin.
    split: usize,
    /// The next crossing is searched from here (the last change of motion or crossing).
    search_from: SimTime,
    next_crossing: Option<SimTime>,
    levels: Levels,
    goal: Goal,
    k1: Contactor,
    converter: Converter,
    crank_target_mm: Option<f64>,
    buttons: Buttons,
    stop_faults: [ContactFault; 2],
    /// Faults of the left and right vane sensors' outputs.
    vane_faults: [SensorFault; 2],
    door_closed: bool,
    load: LoadLevel,
    /// Floors 1..N, then the cabin.
    displays: Vec<DisplayState>,
    crashes: Vec<Crash>,
    events: VecDeque<PlantEvent>,
}

impl Lift {
    /// Builds the plant at time zero, the cabin at rest at `config.initial_position_mm`,
    /// K1 open, converter stopped at 4000 µA, door closed, cabin empty, displays blank.
    pub fn new(config: LiftConfig) -> Result<Lift, ConfigError> {
        config.validate()?;
        let shaft = Shaft::new(&config);
        let x = config.initial_position_mm;
        let split = shaft.split_at(x);
        let levels = shaft.levels_below(split);
        let floors = config.floors;
        Ok(Lift {
            ramp_mm_s2: config.drive.ramp_mm_s2(),
            shaft,
            now: SimTime::ZERO,
            motion: Segment::rest(SimTime::ZERO, x),
            split,
            search_from: SimTime::ZERO,
            next_crossing: None,
            levels,
            goal: Goal::Brake,
            k1: Contactor {
                coil: false,
                main_closed: false,
                weld_fault: false,
            },
            converter: Converter {
                run: false,
                up: false,
                setpoint_ua: crate::drive::STANDSTILL_UA,
                injected_fault: false,
                stalled: false,
            },
            crank_target_mm: None,
            buttons: Buttons::new(floors),
            stop_faults: [ContactFault::None; 2],
            vane_faults: [SensorFault::None; 2],
            door_closed: true,
            load: LoadLevel::Empty,
            displays: vec![DisplayState::Blank; usize::from(floors) + 1],
            crashes: Vec::new(),
            events: VecDeque::with_capacity(64),
            config,
        })
    }

    /// The configuration the plant was built from.
    pub fn config(&self) -> &LiftConfig {
        &self.config
    }

    /// The plant's time: the last `advance_to` or input.
    pub fn now(&self) -> SimTime {
        self.now
    }

    // ---------------------------------------------------------------- time

    /// When the next edge happens under the present inputs (vane edge, overtravel trip or
    /// clear, end of a ramp, stop, mechanical end, button release); `None` when nothing will
    /// change until an input does. May equal [`Lift::now`] right after an input.
    pub fn next_event(&self) -> Option<SimTime> {
        [
            self.buttons.next_release(),
            self.next_crossing,
            self.motion.end.map(|(t, _)| t),
        ]
        .into_iter()
        .flatten()
        .min()
    }

    /// Moves the plant to `t` and returns every edge since the last call (including those
    /// queued by inputs), in time order. Allocates nothing once the queue has grown to the
    /// largest burst.
    pub fn advance_to(&mut self, t: SimTime) -> Result<Events<'_>, PlantError> {
        self.catch_up(t)?;
        Ok(Events(self.events.drain(..)))
    }

    fn catch_up(&mut self, t: SimTime) -> Result<(), PlantError> {
        if t < self.now {
            return Err(PlantError::TimeReversed {
                now: t,
                plant_time: self.now,
            });
        }
        while let Some(next) = self.next_event().filter(|&next| next <= t) {
            self.now = next;
            if !self.step() {
                // Unreachable: `next_event` is the earliest of the three `step` handles.
                // Stopping here rather than spinning keeps a logic slip from hanging a run.
                break;
            }
        }
        self.now = t;
        Ok(())
    }

    /// Handles one edge due at `self.now`; `false` if none was due.
    fn step(&mut self) -> bool {
        let now = self.now;
        if self.buttons.next_release() == Some(now) {
            let events = &mut self.events;
            self.buttons.release_due(now, |button| {
                events.push_back(PlantEvent {
                    at: now,
                    kind: EventKind::Released { button },
                });
            });
        } else if self.next_crossing == Some(now) {
            self.cross();
        } else if let Some((_, how)) = self.motion.end.filter(|&(t, _)| t == now) {
            self.end_segment(how);
        } else {
            return false;
        }
        true
    }

    fn emit(&mut self, kind: EventKind) {
        // A failed sensor's output does not follow the vane: no edge to report.
        if let EventKind::Vane { sensor, .. } = kind {
            if self.vane_faults[sensor as usize] != SensorFault::None {
                return;
            }
        }
        self.events.push_back(PlantEvent { at: self.now, kind });
    }

    /// The cabin passes the next boundary in its direction of travel.
    fn cross(&mut self) {
        let up = self.motion.direction() > 0;
        let index = if up {
            Some(self.split)
        } else {
            self.split.checked_sub(1)
        };
        let Some(&b) = index.and_then(|i| self.shaft.boundaries.get(i)) else {
            self.next_crossing = None;
            return;
        };
        match self.levels.cross(&b, up) {
            Ok(kind) => {
                self.split = if up { self.split + 1 } else { self.split - 1 };
                self.emit(kind);
                self.search_from = self.now;
                self.next_crossing = self.find_crossing();
            }
            Err(end) => self.crash(end),
        }
    }

    /// The cabin hits a mechanical end: it stops there; under power the converter trips.
    fn crash(&mut self, end: End) {
        let impact_mm_s = self.motion.velocity_at(self.now).abs();
        let powered = self.k1.main_closed;
        self.crashes.push(Crash {
            at: self.now,
            end,
            impact_mm_s,
            powered,
        });
        self.emit(EventKind::Crash { end, impact_mm_s });
        self.crank_target_mm = None;
        if self.converter_driving() {
            self.converter.stalled = true;
            self.emit(EventKind::ConverterFault { fault: true });
        }
        self.goal = self.compute_goal();
        self.start_motion(self.config.end_position_mm(end), 0.0);
    }

    fn end_segment(&mut self, how: SegmentEnd) {
        let x = self.motion.position_at(self.now);
        let v = match how {
            SegmentEnd::RampEnd { v_end } => {
                self.emit(EventKind::RampEnd {
                    velocity_mm_s: v_end,
                });
                v_end
            }
            SegmentEnd::Stop | SegmentEnd::CrankDone => {
                if how == SegmentEnd::CrankDone {
                    self.crank_target_mm = None;
                    self.goal = self.compute_goal();
                }
                self.emit(EventKind::Stopped { position_mm: x });
                0.0
            }
        };
        self.start_motion(x, v);
    }

    /// The converter has power and no fault, so it drives the motor.
    fn converter_driving(&self) -> bool {
        self.k1.main_closed && !self.converter.injected_fault && !self.converter.stalled
    }

    fn compute_goal(&self) -> Goal {
        if let Some(target_mm) = self.crank_target_mm {
            return Goal::Crank { target_mm };
        }
        if !self.converter_driving() {
            return Goal::Brake;
        }
        let c = &self.converter;
        let speed = if c.run {
            self.config.drive.setpoint_velocity_mm_s(c.setpoint_ua)
        } else {
            0.0
        };
        let v_target = if speed == 0.0 || c.up { speed } else { -speed };
        Goal::Drive { v_target }
    }

    /// Re-plans the motion from the present state if the inputs changed what drives it.
    fn update_goal(&mut self) {
        let goal = self.compute_goal();
        if goal != self.goal {
            self.goal = goal;
            let x = self.motion.position_at(self.now);
            let v = self.motion.velocity_at(self.now);
            self.start_motion(x, v);
        }
    }

    /// A new motion segment from position `x` and velocity `v` at `self.now`.
    fn start_motion(&mut self, x: f64, v: f64) {
        let now = self.now;
        self.motion = match self.goal {
            Goal::Crank { target_mm } => {
                let speed = self.config.crank_speed_mm_s;
                let distance = target_mm - x;
                let v = if distance >= 0.0 { speed } else { -speed };
                let duration_s = distance.abs() / speed;
                Segment::steady(now, x, v, Some((duration_s, SegmentEnd::CrankDone)))
            }
            Goal::Drive { v_target } if v == v_target => Segment::steady(now, x, v, None),
            Goal::Drive { v_target } => {
                // A change of direction ramps through a momentary standstill.
                let reverses = v != 0.0 && (v_target == 0.0 || (v_target > 0.0) != (v > 0.0));
                let (v_end, how) = if reverses {
                    (0.0, SegmentEnd::Stop)
                } else {
                    (v_target, SegmentEnd::RampEnd { v_end: v_target })
                };
                let a = if v_end > v {
                    self.ramp_mm_s2
                } else {
                    -self.ramp_mm_s2
                };
                Segment::ramp(now, x, v, a, v_end, how)
            }
            Goal::Brake if v == 0.0 => Segment::rest(now, x),
            Goal::Brake => {
                let brake = self.config.drive.brake_decel_mm_s2;
                let a = if v > 0.0 { -brake } else { brake };
                Segment::ramp(now, x, v, a, 0.0, SegmentEnd::Stop)
            }
        };
        self.search_from = now;
        self.next_crossing = self.find_crossing();
    }

    fn find_crossing(&self) -> Option<SimTime> {
        let (index, up) = match self.motion.direction() {
            1 => (self.split, true),
            -1 => (self.split.checked_sub(1)?, false),
            _ => return None,
        };
        let b = self.shaft.boundaries.get(index)?;
        self.motion.crossing(b, up, self.search_from)
    }

    // ---------------------------------------------------------------- inputs

    /// The coil of contactor K1, driven by the safety logic (SPEC §6): `true` energised.
    ///
    /// K1 feeds the converter (a decision: SPEC §4 says only "power only while K1 is closed").
    /// Opening it removes drive power: the converter goes dark (ready and fault outputs 0,
    /// a latched stall fault is cleared) and the brake stops the cabin at
    /// `drive.brake_decel_mm_s2`. Closing it again restarts the converter at once, catching
    /// the still-moving motor at its present speed (flying restart), so the velocity never
    /// jumps. Closing it also ends a hand-crank turn in progress.
    pub fn set_contactor(&mut self, now: SimTime, energised: bool) -> Result<(), PlantError> {
        self.catch_up(now)?;
        self.k1.coil = energised;
        self.k1.main_closed = energised || (self.k1.main_closed && self.k1.weld_fault);
        self.power_changed();
        Ok(())
    }

    /// Fault injection: K1's main contacts weld (SPEC §4, for testing EDM, SPEC §6).
    ///
    /// Welded contacts are closed and stay closed when the coil drops. If the contacts are
    /// open when the fault is set, they weld the next time they close (welding happens
    /// under current, at closing). `false` repairs the contactor: the contacts follow the coil
    /// again at once. The auxiliary contact is a mirror contact, see [`Lift::k1_aux_closed`].
    pub fn set_contactor_welded(&mut self, now: SimTime, welded: bool) -> Result<(), PlantError> {
        self.catch_up(now)?;
        self.k1.weld_fault = welded;
        if !welded {
            self.k1.main_closed = self.k1.coil;
        }
        self.power_changed();
        Ok(())
    }

    fn power_changed(&mut self) {
        if self.k1.main_closed {
            self.crank_target_mm = None;
        } else {
            self.converter.stalled = false;
        }
        self.update_goal();
    }

    /// The converter's inputs: run, direction (`up`: 1 up, 0 down; slave 7 outputs D0, D1,
    /// SPEC §3) and the current-loop set-point `Rychlost` in µA (slave 10, seed 003 table 6.6).
    ///
    /// With power and no fault the converter ramps its frequency at `drive.ramp_hz_per_s`
    /// toward [`crate::converter_frequency_hz`] of the set-point in the given direction, or
    /// toward 0 Hz when `run` is off (a ramp stop); a change of direction ramps through zero.
    pub fn set_converter(
        &mut self,
        now: SimTime,
        run: bool,
        up: bool,
        setpoint_ua: u16,
    ) -> Result<(), PlantError> {
        self.catch_up(now)?;
        self.converter.run = run;
        self.converter.up = up;
        self.converter.setpoint_ua = setpoint_ua;
        self.update_goal();
        Ok(())
    }

    /// Run and direction alone (slave 7), keeping the set-point. See [`Lift::set_converter`].
    pub fn set_run_direction(
        &mut self,
        now: SimTime,
        run: bool,
        up: bool,
    ) -> Result<(), PlantError> {
        let setpoint = self.converter.setpoint_ua;
        self.set_converter(now, run, up, setpoint)
    }

    /// The set-point alone (slave 10), keeping run and direction. See [`Lift::set_converter`].
    pub fn set_setpoint(&mut self, now: SimTime, setpoint_ua: u16) -> Result<(), PlantError> {
        let Converter { run, up, .. } = self.converter;
        self.set_converter(now, run, up, setpoint_ua)
    }

    /// Fault injection: the converter reports a fault and stops driving (the brake stops the
    /// cabin) until the fault is cleared with `false`; it survives a power cycle.
    pub fn set_converter_fault(&mut self, now: SimTime, fault: bool) -> Result<(), PlantError> {
        self.catch_up(now)?;
        self.converter.injected_fault = fault;
        self.update_goal();
        Ok(())
    }

    /// A person presses `button` at `now` and holds it for `duration`: it reads pressed from
    /// `now` until the nanosecond before `now + duration`, and its release is reported as an
    /// event at `now + duration`. A press while it is held extends it; [`SimDuration::MAX`]
    /// holds it until [`Lift::release`].
    pub fn press(
        &mut self,
        now: SimTime,
        button: Button,
        duration: SimDuration,
    ) -> Result<(), PlantError> {
        let index = self.button_index(button)?;
        if duration.is_zero() {
            return Err(PlantError::EmptyPress { button });
        }
        self.catch_up(now)?;
        self.buttons.press(index, now + duration);
        Ok(())
    }

    /// Lets go of `button` at `now`, ending any press early (not reported as an event).
    pub fn release(&mut self, now: SimTime, button: Button) -> Result<(), PlantError> {
        let index = self.button_index(button)?;
        self.catch_up(now)?;
        self.buttons.release(index);
        Ok(())
    }

    fn button_index(&self, button: Button) -> Result<usize, PlantError> {
        self.buttons.index(button).ok_or(PlantError::NoSuchButton {
            button,
            floors: self.config.floors,
        })
    }

    /// Fault injection on one NC channel of the STOP switch (for the safety logic's
    /// discrepancy check, SPEC §6).
    pub fn set_stop_channel_fault(
        &mut self,
        now: SimTime,
        channel: StopChannel,
        fault: ContactFault,
    ) -> Result<(), PlantError> {
        self.catch_up(now)?;
        self.stop_faults[channel as usize] = fault;
        Ok(())
    }

    /// Makes a vane sensor's output fail (or work again, with [`SensorFault::None`]). While it
    /// fails, its output reads the stuck value and the plant reports no edges of it; the change
    /// itself is an input, not an event.
    pub fn set_vane_fault(
        &mut self,
        now: SimTime,
        sensor: VaneSensor,
        fault: SensorFault,
    ) -> Result<(), PlantError> {
        self.catch_up(now)?;
        self.vane_faults[sensor as usize] = fault;
        Ok(())
    }

    /// The lab door, moved by hand (SPEC §4): `true` closed.
    pub fn set_door(&mut self, now: SimTime, closed: bool) -> Result<(), PlantError> {
        self.catch_up(now)?;
        self.door_closed = closed;
        Ok(())
    }

    /// The load in the cabin (SPEC §3 slave 8). It does not change the drive's speed: the
    /// seed's slip is a constant 0.1.
    pub fn set_load(&mut self, now: SimTime, load: LoadLevel) -> Result<(), PlantError> {
        self.catch_up(now)?;
        self.load = load;
        Ok(())
    }

    /// A person turns the motor by hand (seed 003 §6.3) so the cabin moves `distance_mm`
    /// (positive up) at `crank_speed_mm_s`, passing vanes and overtravel zones with their
    /// edges like any motion.
    ///
    /// Only without drive power (K1's main contacts open; turning implies releasing the brake
    /// by hand) and with the cabin at rest. A turn past a mechanical end stops at the end: the
    /// impact is recorded as a [`Crash`] at crank speed and the rest of the distance is
    /// dropped. A cabin already touching an end cannot be cranked further into it. Closing K1
    /// ends the turn where the cabin is.
    pub fn crank(&mut self, now: SimTime, distance_mm: f64) -> Result<(), PlantError> {
        if !distance_mm.is_finite() {
            return Err(PlantError::CrankDistance { distance_mm });
        }
        self.catch_up(now)?;
        if self.k1.main_closed {
            return Err(PlantError::CrankWhilePowered);
        }
        let velocity_mm_s = self.velocity_mm_s();
        if velocity_mm_s != 0.0 {
            return Err(PlantError::CrankWhileMoving { velocity_mm_s });
        }
        let x = self.position_mm();
        for (end, toward) in [
            (End::Bottom, distance_mm < 0.0),
            (End::Top, distance_mm > 0.0),
        ] {
            if toward && x == self.config.end_position_mm(end) {
                return Err(PlantError::CrankBlocked { end });
            }
        }
        if distance_mm != 0.0 {
            self.crank_target_mm = Some(x + distance_mm);
            self.update_goal();
        }
        Ok(())
    }

    /// `true` while a hand-crank turn moves the cabin (the operator at the motor, K1 open):
    /// motion that is not the drive's.
    pub fn hand_cranking(&self) -> bool {
        self.crank_target_mm.is_some()
    }

    /// A complete display word for a display, as the rig received it through the AS-i
    /// handshake (seed 003 tables 4.3, 4.5); the display shows it from `now` on.
    pub fn set_display(&mut self, now: SimTime, id: DisplayId, raw: u16) -> Result<(), PlantError> {
        let index = self.display_index(id).ok_or(PlantError::NoSuchDisplay {
            floor: match id {
                DisplayId::Floor(f) => f,
                DisplayId::Cabin => 0,
            },
            floors: self.config.floors,
        })?;
        self.catch_up(now)?;
        self.displays[index] = DisplayState::from_raw(raw);
        Ok(())
    }

    fn display_index(&self, id: DisplayId) -> Option<usize> {
        let n = self.config.floors;
        match id {
            DisplayId::Floor(f) if (1..=n).contains(&f) => Some(usize::from(f) - 1),
            DisplayId::Floor(_) => None,
            DisplayId::Cabin => Some(usize::from(n)),
        }
    }

    // ---------------------------------------------------------------- outputs

    /// Cabin position in mm above the level of floor 1, at [`Lift::now`].
    pub fn position_mm(&self) -> f64 {
        self.motion.position_at(self.now)
    }

    /// Cabin velocity in mm/s, positive up, at [`Lift::now`].
    pub fn velocity_mm_s(&self) -> f64 {
        self.motion.velocity_at(self.now)
    }

    /// Cabin acceleration in mm/s², positive up, at [`Lift::now`].
    pub fn acceleration_mm_s2(&self) -> f64 {
        self.motion.a
    }

    /// The level of a vane sensor: `true` over a vane track (seed 003 §6.4).
    pub fn vane(&self, sensor: VaneSensor) -> bool {
        let level = match sensor {
            VaneSensor::Left => self.levels.left,
            VaneSensor::Right => self.levels.right,
        };
        self.vane_faults[sensor as usize].reads(level)
    }

    /// `Snimac_1`, the left vane sensor (seed 003 table 6.1).
    pub fn vane_left(&self) -> bool {
        self.vane(VaneSensor::Left)
    }

    /// `Snimac_2`, the right vane sensor (seed 003 table 6.1).
    pub fn vane_right(&self) -> bool {
        self.vane(VaneSensor::Right)
    }

    /// The cabin is in the level zone of a floor, where both vane tracks overlap (seed 003
    /// tables 6.4, 6.5: "Dobrždění → Aktuální patro"); the physical position, whatever the
    /// sensors report.
    pub fn in_level_zone(&self) -> bool {
        self.levels.left && self.levels.right
    }

    /// The overtravel safety sensor at `end` is free (not tripped); its safety slave sends its
    /// code sequence while free (SPEC §3 slaves 11, 12).
    pub fn overtravel_free(&self, end: End) -> bool {
        match end {
            End::Bottom => !self.levels.bottom_tripped,
            End::Top => !self.levels.top_tripped,
        }
    }

    /// The bottom overtravel sensor is free (safety slave 11).
    pub fn overtravel_bottom_free(&self) -> bool {
        self.overtravel_free(End::Bottom)
    }

    /// The top overtravel sensor is free (safety slave 12).
    pub fn overtravel_top_free(&self) -> bool {
        self.overtravel_free(End::Top)
    }

    /// K1's main contacts are closed: the drive has power.
    pub fn k1_closed(&self) -> bool {
        self.k1.main_closed
    }

    /// K1's auxiliary contact for EDM (SPEC §6): an NC mirror contact (IEC 60947-4-1
    /// Annex F), closed (`true`) exactly when the main contacts are open. So it reads `true`
    /// when K1 has dropped and stays `false` while welded main contacts hold, which is how
    /// the safety logic's EDM input (1 = contactor released) detects the weld.
    pub fn k1_aux_closed(&self) -> bool {
        !self.k1.main_closed
    }

    /// The converter's ready output (slave 7 input D0): powered and not faulted.
    pub fn converter_ready(&self) -> bool {
        self.converter_driving()
    }

    /// The converter's fault output (slave 7 input D1): powered and faulted (injected, or
    /// tripped by a crash under power). An unpowered converter shows neither.
    pub fn converter_fault(&self) -> bool {
        self.k1.main_closed && (self.converter.injected_fault || self.converter.stalled)
    }

    /// The converter's output frequency in Hz, positive driving up; 0 without power.
    pub fn converter_frequency_hz(&self) -> f64 {
        if self.converter_driving() {
            self.velocity_mm_s() / self.config.drive.cabin_velocity_mm_s(1.0)
        } else {
            0.0
        }
    }

    /// Whether `button` is pressed now; `false` for a button the lift does not have.
    pub fn is_pressed(&self, button: Button) -> bool {
        self.buttons.is_pressed(button)
    }

    /// The standard contact of STOP read by the cabin slave (`Stop_1`, SPEC §3 D11):
    /// `true` pressed.
    pub fn stop_pressed(&self) -> bool {
        self.buttons.is_pressed(Button::Stop)
    }

    /// The two NC channels of STOP for the safety logic (SPEC §6): `true` closed, i.e. not
    /// pressed, unless a channel fault is injected.
    pub fn stop_channels(&self) -> [bool; 2] {
        let pressed = self.stop_pressed();
        self.stop_faults.map(|fault| fault.nc_reads(pressed))
    }

    /// The door-closed sensor `SnZavD` (SPEC §3 D13): `true` closed.
    pub fn door_closed(&self) -> bool {
        self.door_closed
    }

    /// The load in the cabin (SPEC §3 slave 8).
    pub fn load(&self) -> LoadLevel {
        self.load
    }

    /// What a display shows; `None` for a display the lift does not have.
    pub fn display(&self, id: DisplayId) -> Option<DisplayState> {
        self.display_index(id).map(|i| self.displays[i])
    }

    /// Every impact on a mechanical end so far.
    pub fn crashes(&self) -> &[Crash] {
        &self.crashes
    }
}
