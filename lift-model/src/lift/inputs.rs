//! The plant's inputs: K1, the converter, buttons, door, load, the hand crank, displays and
//! injected faults. Each brings the plant to `now` first.

use asi_phy::{SimDuration, SimTime};

use super::{Converter, Lift, PlantError};
use crate::controls::{Button, ContactFault, LoadLevel, SensorFault, StopChannel};
use crate::display::{DisplayId, DisplayState};
use crate::sensor::{End, VaneSensor};

impl Lift {
    /// The coil of contactor K1, driven by the safety logic (docs/safety.md): `true` energised.
    ///
    /// K1 feeds the converter (a decision: docs/lift-plant.md says only "power only while K1 is closed").
    /// Opening it removes drive power: the converter goes dark (ready and fault outputs 0,
    /// a latched stall fault is cleared) and the brake stops the cabin at
    /// `drive.brake_decel_mm_s2`. Closing it again restarts the converter at once, catching
    /// the still-moving motor at its present speed (flying restart), so the velocity never
    /// jumps. Closing it also ends a hand-crank turn in progress.
    pub fn set_contactor(&mut self, now: SimTime, energised: bool) -> Result<(), PlantError> {
        self.input_at(now)?;
        self.k1.coil = energised;
        self.k1.main_closed = energised || (self.k1.main_closed && self.k1.weld_fault);
        self.power_changed();
        Ok(())
    }

    /// Fault injection: K1's main contacts weld (docs/lift-plant.md, for testing EDM, docs/safety.md).
    ///
    /// Welded contacts are closed and stay closed when the coil drops. If the contacts are
    /// open when the fault is set, they weld the next time they close (welding happens
    /// under current, at closing). `false` repairs the contactor: the contacts follow the coil
    /// again at once. The auxiliary contact is a mirror contact, see [`Lift::k1_aux_closed`].
    pub fn set_contactor_welded(&mut self, now: SimTime, welded: bool) -> Result<(), PlantError> {
        self.input_at(now)?;
        self.k1.weld_fault = welded;
        if !welded {
            self.k1.main_closed = self.k1.coil;
        }
        self.power_changed();
        Ok(())
    }

    pub(super) fn power_changed(&mut self) {
        if self.k1.main_closed {
            self.crank_target_mm = None;
        } else {
            self.converter.stalled = false;
        }
        self.update_goal();
    }

    /// The converter's inputs: run, direction (`up`: 1 up, 0 down; slave 7 outputs D0, D1,
    /// docs/lab-bus.md) and the current-loop set-point `Rychlost` in µA (slave 10, table 6.6 of the
    /// lift thesis).
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
        self.input_at(now)?;
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
        self.input_at(now)?;
        self.converter.injected_fault = fault;
        self.update_goal();
        Ok(())
    }

    /// Fault injection: the converter runs away — its control has failed and it drives the
    /// motor `Some(up)` (`true` up, `false` down) at its highest frequency
    /// ([`crate::drive::MAX_SETPOINT_UA`], 34.3 Hz, 153.2 mm/s), ramping as usual, whatever its
    /// run, direction and set-point inputs say; `None` repairs it. It still needs power:
    /// opening K1 stops it (the brake), closing K1 again starts it again. Its ready and fault
    /// outputs show nothing wrong: the converter does not know it has failed.
    pub fn set_converter_runaway(
        &mut self,
        now: SimTime,
        runaway: Option<bool>,
    ) -> Result<(), PlantError> {
        self.input_at(now)?;
        self.converter.runaway = runaway;
        self.update_goal();
        Ok(())
    }

    /// The converter's runaway fault, if one is injected: `Some(true)` up.
    pub fn converter_runaway(&self) -> Option<bool> {
        self.converter.runaway
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
        self.input_at(now)?;
        self.buttons.press(index, now + duration);
        self.next_event_changed();
        Ok(())
    }

    /// Lets go of `button` at `now`, ending any press early (not reported as an event).
    pub fn release(&mut self, now: SimTime, button: Button) -> Result<(), PlantError> {
        let index = self.button_index(button)?;
        self.input_at(now)?;
        self.buttons.release(index);
        self.next_event_changed();
        Ok(())
    }

    pub(super) fn button_index(&self, button: Button) -> Result<usize, PlantError> {
        self.buttons.index(button).ok_or(PlantError::NoSuchButton {
            button,
            floors: self.config.floors,
        })
    }

    /// Fault injection on one NC channel of the STOP switch (for the safety logic's
    /// discrepancy check, docs/safety.md).
    pub fn set_stop_channel_fault(
        &mut self,
        now: SimTime,
        channel: StopChannel,
        fault: ContactFault,
    ) -> Result<(), PlantError> {
        self.input_at(now)?;
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
        self.input_at(now)?;
        self.vane_faults[sensor as usize] = fault;
        Ok(())
    }

    /// The lab door, moved by hand (docs/lift-plant.md): `true` closed.
    pub fn set_door(&mut self, now: SimTime, closed: bool) -> Result<(), PlantError> {
        self.input_at(now)?;
        self.door_closed = closed;
        Ok(())
    }

    /// The load in the cabin (docs/lab-bus.md slave 8). It does not change the drive's speed: the
    /// the lift thesis' slip is a constant 0.1.
    pub fn set_load(&mut self, now: SimTime, load: LoadLevel) -> Result<(), PlantError> {
        self.input_at(now)?;
        self.load = load;
        Ok(())
    }

    /// A person turns the motor by hand (§6.3 of the lift thesis) so the cabin moves `distance_mm`
    /// (positive up) at `crank_speed_mm_s`, passing vanes and overtravel zones with their
    /// edges like any motion.
    ///
    /// Only without drive power (K1's main contacts open; turning implies releasing the brake
    /// by hand) and with the cabin at rest. A turn past a mechanical end stops at the end: the
    /// impact is recorded as a [`Crash`](crate::Crash) at crank speed and the rest of the distance is
    /// dropped. A cabin already touching an end cannot be cranked further into it. Closing K1
    /// ends the turn where the cabin is.
    pub fn crank(&mut self, now: SimTime, distance_mm: f64) -> Result<(), PlantError> {
        if !distance_mm.is_finite() {
            return Err(PlantError::CrankDistance { distance_mm });
        }
        self.input_at(now)?;
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
    /// handshake (tables 4.3, 4.5 of the lift thesis); the display shows it from `now` on.
    pub fn set_display(&mut self, now: SimTime, id: DisplayId, raw: u16) -> Result<(), PlantError> {
        let index = self.display_index(id).ok_or(PlantError::NoSuchDisplay {
            floor: match id {
                DisplayId::Floor(f) => f,
                DisplayId::Cabin => 0,
            },
            floors: self.config.floors,
        })?;
        self.input_at(now)?;
        self.displays[index] = DisplayState::from_raw(raw);
        Ok(())
    }

    pub(super) fn display_index(&self, id: DisplayId) -> Option<usize> {
        let n = self.config.floors;
        match id {
            DisplayId::Floor(f) if (1..=n).contains(&f) => Some(usize::from(f) - 1),
            DisplayId::Floor(_) => None,
            DisplayId::Cabin => Some(usize::from(n)),
        }
    }
}
