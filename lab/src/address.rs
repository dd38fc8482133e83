//! The lab lift's AS-i slaves and their addresses (§2.2.3 of the lift thesis; docs/lab-bus.md
//! §3.1).

/// Floor station of floor 1; the floor station of floor `f` is at address `f`.
pub const FLOOR_1: u8 = 1;
/// The lab bus has floor stations for this many floors (addresses 1..=4).
pub const FLOOR_STATIONS: u8 = 4;
/// The cabin display (handshake of tables 4.4/4.5).
pub const CABIN_DISPLAY: u8 = 5;
/// The cabin panel: cabin buttons, bell, STOP, door contact, vane sensors (tables 4.6/4.7).
pub const CABIN_PANEL: u8 = 6;
/// The converter I/O module: out D0 run, D1 direction; in D0 ready, D1 fault.
pub const CONVERTER: u8 = 7;
/// The load sensor: in D1..D0 = 0 empty .. 3 overloaded.
pub const LOAD_SENSOR: u8 = 8;
/// The S-7.3 current-loop output of the speed set-point (channel 1).
pub const SPEED_SETPOINT: u8 = 10;
/// The bottom overtravel Safety-at-Work sensor.
pub const SAFETY_BOTTOM: u8 = 11;
/// The top overtravel Safety-at-Work sensor.
pub const SAFETY_TOP: u8 = 12;

/// Every slave of the lab lift, in address order.
pub const ALL: [u8; 11] = [
    FLOOR_1,
    2,
    3,
    FLOOR_STATIONS,
    CABIN_DISPLAY,
    CABIN_PANEL,
    CONVERTER,
    LOAD_SENSOR,
    SPEED_SETPOINT,
    SAFETY_BOTTOM,
    SAFETY_TOP,
];

/// The slaves the cabin cannot move without: the cabin panel (STOP, door, vanes), the
/// converter, the load sensor and the speed set-point (book/src/controller-under-faults.md).
pub const ESSENTIAL: [u8; 4] = [CABIN_PANEL, CONVERTER, LOAD_SENSOR, SPEED_SETPOINT];

/// The addresses the lab lift leaves free, in the order extra I/O modules take them.
pub const FREE: [u8; 20] = [
    9, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30, 31,
];

/// The floor station's address of floor `floor`, if the lab bus has one.
pub const fn floor_station(floor: u8) -> Option<u8> {
    if floor >= FLOOR_1 && floor <= FLOOR_STATIONS {
        Some(floor)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lab_and_the_free_addresses_are_the_whole_single_address_range() {
        let mut all: Vec<u8> = ALL.iter().chain(FREE.iter()).copied().collect();
        all.sort_unstable();
        assert_eq!(all, (1..=31).collect::<Vec<u8>>());
        assert!(ESSENTIAL.iter().all(|a| ALL.contains(a)));
        assert_eq!(floor_station(4), Some(4));
        assert_eq!(floor_station(5), None);
        assert_eq!(floor_station(0), None);
    }
}
