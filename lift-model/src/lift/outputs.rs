//! The plant's outputs at [`Lift::now`]: position, sensors, K1, converter, buttons, door,
//! load, displays and crashes.

use super::Lift;
use crate::controls::{Button, LoadLevel};
use crate::display::{DisplayId, DisplayState};
use crate::event::Crash;
use crate::sensor::{End, VaneSensor};

impl Lift {
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

    /// The level of a vane sensor: `true` over a vane track (§6.4 of the lift thesis).
    pub fn vane(&self, sensor: VaneSensor) -> bool {
        let level = match sensor {
            VaneSensor::Left => self.levels.left,
            VaneSensor::Right => self.levels.right,
        };
        self.vane_faults[sensor as usize].reads(level)
    }

    /// `Snimac_1`, the left vane sensor (table 6.1 of the lift thesis).
    pub fn vane_left(&self) -> bool {
        self.vane(VaneSensor::Left)
    }

    /// `Snimac_2`, the right vane sensor (table 6.1 of the lift thesis).
    pub fn vane_right(&self) -> bool {
        self.vane(VaneSensor::Right)
    }

    /// The cabin is in the level zone of a floor, where both vane tracks overlap (tables 6.4, 6.5
    /// of the lift thesis: "Dobrždění → Aktuální patro"); the physical position, whatever the
    /// sensors report.
    pub fn in_level_zone(&self) -> bool {
        self.levels.left && self.levels.right
    }

    /// The overtravel safety sensor at `end` is free (not tripped); its safety slave sends its
    /// code sequence while free (docs/lab-bus.md slaves 11, 12).
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

    /// K1's auxiliary contact for EDM (docs/safety.md): an NC mirror contact (IEC 60947-4-1
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

    /// The standard contact of STOP read by the cabin slave (`Stop_1`, docs/lab-bus.md D11):
    /// `true` pressed.
    #[inline]
    pub fn stop_pressed(&self) -> bool {
        self.buttons.is_pressed(Button::Stop)
    }

    /// The two NC channels of STOP for the safety logic (docs/safety.md): `true` closed, i.e. not
    /// pressed, unless a channel fault is injected.
    ///
    /// Read at every rig moment and safety scan: inline (with the button lookup under it) so
    /// that STOP's slot is worked out where it is called, not looked up through a call.
    #[inline]
    pub fn stop_channels(&self) -> [bool; 2] {
        let pressed = self.stop_pressed();
        self.stop_faults.map(|fault| fault.nc_reads(pressed))
    }

    /// The door-closed sensor `SnZavD` (docs/lab-bus.md D13): `true` closed.
    pub fn door_closed(&self) -> bool {
        self.door_closed
    }

    /// The load in the cabin (docs/lab-bus.md slave 8).
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
