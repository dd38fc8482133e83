//! What the program reads from the lift plant when it runs against it without the bus: the
//! cabin word and the hall calls straight from the plant's signals.

use controller::{CabinWord, Inputs};
use lift_model::{Button, Lift};

/// The bits of the `button` of floors 1..=4 that are pressed, bit `f − 1` for floor `f`.
fn pressed(l: &Lift, button: fn(u8) -> Button) -> u32 {
    (1..=4u8)
        .filter(|&f| l.is_pressed(button(f)))
        .fold(0, |bits, f| bits | 1 << (f - 1))
}

/// The program's inputs from the plant `l`: the cabin word when `bus_ok` (none otherwise),
/// STOP through the safety logic's EStopOut (`estop_ok` and the button released).
pub fn plant_inputs(l: &Lift, estop_ok: bool, bus_ok: bool) -> Inputs {
    Inputs {
        cabin: bus_ok.then_some(CabinWord {
            buttons: pressed(l, Button::Cabin),
            bell: false,
            stop: l.stop_pressed(),
            door_closed: l.door_closed(),
            vane_left: l.vane_left(),
            vane_right: l.vane_right(),
        }),
        hall_up: pressed(l, Button::HallUp),
        hall_down: pressed(l, Button::HallDown),
        load: l.load().code(),
        load_lost: false,
        estop_ok: estop_ok && !l.stop_pressed(),
        converter_ready: l.converter_ready(),
        converter_fault: l.converter_fault(),
        bus_ok,
        power_ok: true,
    }
}
