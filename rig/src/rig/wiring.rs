//! The wiring of the lab: the plant's signals on the slaves' peripheral inputs, and what the
//! slaves drive (converter run and direction, the speed set-point, the display words) to the
//! plant, at the moment they drive it.

use asi_bus::lab::LabLift;
use asi_phy::SimTime;
use lab::address::{
    self, CABIN_DISPLAY, CONVERTER, FLOOR_STATIONS, SAFETY_BOTTOM, SAFETY_TOP, SPEED_SETPOINT,
};
use lift_model::{Button, DisplayId, Lift, PlantError};

/// The slaves whose outputs drive the plant: the floor displays, the cabin display, the
/// converter I/O and the speed set-point; as a mask of addresses.
pub(super) fn drives_plant() -> u32 {
    (address::FLOOR_1..=FLOOR_STATIONS)
        .chain([CABIN_DISPLAY, CONVERTER, SPEED_SETPOINT])
        .fold(0, |m, a| m | 1 << a)
}

/// What the rig last handed the plant from the slaves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub(super) struct Applied {
    pub run: bool,
    pub up: bool,
    pub setpoint_ua: u16,
    /// Floor displays 1..4, then the cabin display.
    pub displays: [Option<u16>; 5],
}

/// The plant's signals on the slaves' peripheral inputs.
pub(super) fn plant_to_slaves(l: &Lift, lab: &mut LabLift, floors: u8) {
    for f in 1..=floors.min(FLOOR_STATIONS) {
        let up = l.is_pressed(Button::HallUp(f));
        let down = l.is_pressed(Button::HallDown(f));
        if let Some(st) = lab.floor_mut(f) {
            st.set_buttons(up, down);
        }
    }
    if let Some(p) = lab.cabin_panel_mut() {
        for f in 1..=floors {
            p.set_floor_button(f, l.is_pressed(Button::Cabin(f)));
        }
        p.set_bell(l.is_pressed(Button::Bell));
        p.set_stop(l.stop_pressed());
        p.set_door_closed(l.door_closed());
        p.set_vane_left(l.vane_left());
        p.set_vane_right(l.vane_right());
    }
    if let Some(c) = lab.converter_mut() {
        c.set_ready(l.converter_ready());
        c.set_fault(l.converter_fault());
    }
    if let Some(s) = lab.load_sensor_mut() {
        s.set_level(l.load().code());
    }
    if let Some(s) = lab.safety_sensor_mut(SAFETY_BOTTOM) {
        s.set_free(l.overtravel_bottom_free());
    }
    if let Some(s) = lab.safety_sensor_mut(SAFETY_TOP) {
        s.set_free(l.overtravel_top_free());
    }
}

/// Whether the output image, as the controller last wrote it, commands the converter to run
/// (slave 7, D0): the command before the bus carries it to the slave.
pub(super) fn run_commanded(lab: &LabLift) -> bool {
    asi_phy::SlaveAddr::a(CONVERTER).is_some_and(|a| {
        asi_slaves::devices::Converter::relays(lab.bus().image().output.nibble(a)).bit(0)
    })
}

/// What the slaves drive now.
pub(super) fn slave_outputs(lab: &LabLift) -> Applied {
    let (run, up) = lab
        .converter()
        .map_or((false, false), |c| (c.run(), c.direction_up()));
    let setpoint_ua = lab.analog_output().map_or(0, |a| a.current_ua(1));
    let mut displays = [None; 5];
    for f in 1..=FLOOR_STATIONS {
        displays[f as usize - 1] = lab.floor(f).and_then(|s| s.display());
    }
    displays[4] = lab.cabin_display().and_then(|d| d.display());
    Applied {
        run,
        up,
        setpoint_ua,
        displays,
    }
}

/// Hands the plant at `t` what changed between `before` and `new`.
pub(super) fn apply_to_plant(
    lift: &mut Lift,
    t: SimTime,
    before: &Applied,
    new: &Applied,
    floors: u8,
) -> Result<(), PlantError> {
    let mut result = Ok(());
    if (new.run, new.up) != (before.run, before.up) {
        result = result.and(lift.set_run_direction(t, new.run, new.up));
    }
    if new.setpoint_ua != before.setpoint_ua {
        result = result.and(lift.set_setpoint(t, new.setpoint_ua));
    }
    for (i, d) in new.displays.iter().enumerate() {
        if *d != before.displays[i] {
            if let Some(raw) = d {
                let id = if i < 4 {
                    DisplayId::Floor(i as u8 + 1)
                } else {
                    DisplayId::Cabin
                };
                if i < 4 && i as u8 >= floors {
                    continue;
                }
                result = result.and(lift.set_display(t, id, *raw));
            }
        }
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;
    use lift_model::LiftConfig;
    use proptest::prelude::*;

    fn applied() -> impl Strategy<Value = Applied> {
        (
            any::<(bool, bool)>(),
            prop_oneof![Just(4000u16), 0..24_000u16],
            prop::array::uniform5(prop::option::of(0..0x400u16)),
        )
            .prop_map(|((run, up), setpoint_ua, displays)| Applied {
                run,
                up,
                setpoint_ua,
                displays,
            })
    }

    proptest! {
        /// The rig skips `apply_to_plant` when the slaves drive what they drove: handing the
        /// plant the same outputs again must change nothing, and a change must reach it.
        #[test]
        fn the_same_outputs_again_leave_the_plant_as_it_is(
            before in applied(),
            new in applied(),
            floors in 2..=4u8,
        ) {
            let t = SimTime::from_millis(5);
            let mut lift = Lift::new(LiftConfig::default()).expect("the default lift");
            let _ = apply_to_plant(&mut lift, SimTime::from_millis(1), &Applied::default(), &before, floors);
            let was = format!("{lift:?}");
            let mut again = lift.clone();
            prop_assert!(apply_to_plant(&mut again, t, &before, &before, floors).is_ok());
            prop_assert_eq!(format!("{again:?}"), was.clone());
            let _ = apply_to_plant(&mut lift, t, &before, &new, floors);
            if new.run != before.run || new.up != before.up || new.setpoint_ua != before.setpoint_ua {
                prop_assert_ne!(format!("{lift:?}"), was);
            }
        }
    }
}
