//! What the program reads at the start of a scan and writes at its end (table 4.1 of the lift
//! thesis, the cabin word of table 4.6, the displays of tables 4.2/4.4), and the vane sensor edges
//! derived from the inputs.

use lab::DisplayWord;

/// The cabin's 32-bit word (table 4.6 of the lift thesis), as the PLC assembles it from the two
/// halves.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CabinWord {
    /// Floor buttons, bit `f − 1` for floor `f` (1..=24).
    pub buttons: u32,
    /// The bell button.
    pub bell: bool,
    /// The STOP button's standard contact (pressed).
    pub stop: bool,
    /// SnZavD: the door is closed.
    pub door_closed: bool,
    /// Snimac_1, the left vane sensor.
    pub vane_left: bool,
    /// Snimac_2, the right vane sensor.
    pub vane_right: bool,
}

/// What the program reads at the start of a scan.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Inputs {
    /// A cabin word completed since the last scan, if any.
    pub cabin: Option<CabinWord>,
    /// Hall up calls received since the last scan, bit `f − 1`.
    pub hall_up: u32,
    /// Hall down calls received since the last scan, bit `f − 1`.
    pub hall_down: u32,
    /// Zatizeni_Kabiny: 0 empty, 1 loaded, 2 full, 3 overloaded.
    pub load: u8,
    /// The load cannot be read (the load sensor is off the bus or not ready): it counts as
    /// overloaded, its unsafe value.
    pub load_lost: bool,
    /// The safety logic's EStopOut: `true` = no STOP demand.
    pub estop_ok: bool,
    /// The converter reports ready (it has power and no fault).
    pub converter_ready: bool,
    /// The converter reports a fault.
    pub converter_fault: bool,
    /// The slaves the cabin cannot move without are on the bus (in LAS; see
    /// [`crate::plc`]).
    pub bus_ok: bool,
    /// No AS-i power fail (flag F1 of word 0).
    pub power_ok: bool,
}

/// What the program writes at the end of a scan.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Outputs {
    /// Start1: the converter's run input.
    pub run: bool,
    /// Smer_Motoru: 1 up, 0 down.
    pub up: bool,
    /// Rychlost, the speed set-point in µA.
    pub setpoint_ua: u16,
    /// The display word content.
    pub display: DisplayWord,
    /// The Restart input of the safety logic's STOP circuit (pulsed).
    pub restart: bool,
    /// The overload signal for the safety logic's AND input.
    pub overloaded: bool,
}

/// Edges seen in this scan's inputs.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Edges {
    pub(super) left_rise: bool,
    pub(super) right_rise: bool,
    pub(super) left_fall: bool,
    pub(super) right_fall: bool,
    /// "Left OR right in log. 1" rose: the cabin reaches a floor's vane (tables 6.4/6.5).
    pub(super) vane_rise: bool,
    /// "Left OR right" fell: the cabin leaves a vane.
    pub(super) vane_fall: bool,
    /// At a vane rise: `Some(true)` if the left sensor came first (floor 1's turned vane, §6.4 of
    /// the lift thesis), `Some(false)` if the right one did (floors 2..), `None` if both came in
    /// one word.
    pub(super) floor1_vane: Option<bool>,
    /// One sensor fell while the other stayed on: `Some(true)` for the left one.
    pub(super) left_fell_first: Option<bool>,
    /// Any sensor changed.
    pub(super) any: bool,
}

/// Overloaded, or the load cannot be read: its unsafe value.
pub(super) fn overloaded(inp: &Inputs) -> bool {
    inp.load >= 3 || inp.load_lost
}

/// The floors whose bits are set, ascending.
pub(super) fn floors(bits: u32, n: u8) -> impl Iterator<Item = u8> {
    (1..=n).filter(move |f| bits & (1 << (f - 1)) != 0)
}
