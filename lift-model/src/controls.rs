//! What people operate: buttons, the STOP switch, the load (docs/lab-bus.md, §4; tables
//! 4.3, 4.6 and 6.2 of the lift thesis).

use core::fmt;

use asi_phy::SimTime;
use serde::{Deserialize, Serialize};

/// A push button of the lift (docs/lift-plant.md "other signals").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Button {
    /// Cabin button for floor `n` (1-based; `TlacitkoKabina<n>`).
    Cabin(u8),
    /// Hall call "up" at floor `n`; every floor but the top one has it (`TPN`).
    HallUp(u8),
    /// Hall call "down" at floor `n`; every floor but floor 1 has it (`TPD`).
    HallDown(u8),
    /// The bell in the cabin (`Zvonek`).
    Bell,
    /// The STOP switch in the cabin (`Stop_1`): one standard contact read by the cabin slave
    /// and two NC channels for the safety logic.
    Stop,
}

impl fmt::Display for Button {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Button::Cabin(n) => write!(f, "cabin button {n}"),
            Button::HallUp(n) => write!(f, "hall up button at floor {n}"),
            Button::HallDown(n) => write!(f, "hall down button at floor {n}"),
            Button::Bell => f.write_str("bell"),
            Button::Stop => f.write_str("STOP"),
        }
    }
}

impl Button {
    /// The button as scenario files and reports name it: `cabin:3`, `hall-up:2`,
    /// `hall-down:4`, `bell`, `stop`.
    pub fn key(self) -> String {
        match self {
            Button::Cabin(f) => format!("cabin:{f}"),
            Button::HallUp(f) => format!("hall-up:{f}"),
            Button::HallDown(f) => format!("hall-down:{f}"),
            Button::Bell => "bell".into(),
            Button::Stop => "stop".into(),
        }
    }

    /// The floor a call button belongs to (`None` for the bell and STOP).
    pub fn floor(self) -> Option<u8> {
        match self {
            Button::Cabin(f) | Button::HallUp(f) | Button::HallDown(f) => Some(f),
            Button::Bell | Button::Stop => None,
        }
    }
}

/// The load sensor's reading (IG5886, docs/lab-bus.md slave 8; the lift thesis' `Zatizeni_Kabiny`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum LoadLevel {
    /// 0: empty.
    #[default]
    Empty,
    /// 1: loaded.
    Loaded,
    /// 2: full.
    Full,
    /// 3: overloaded; the lift must not start (§6.3 of the lift thesis).
    Overloaded,
}

impl LoadLevel {
    /// Every level, lightest first.
    pub const ALL: [LoadLevel; 4] = [
        LoadLevel::Empty,
        LoadLevel::Loaded,
        LoadLevel::Full,
        LoadLevel::Overloaded,
    ];

    /// The level's name in scenario files and reports: `empty`, `loaded`, `full`,
    /// `overloaded`.
    pub const fn name(self) -> &'static str {
        match self {
            LoadLevel::Empty => "empty",
            LoadLevel::Loaded => "loaded",
            LoadLevel::Full => "full",
            LoadLevel::Overloaded => "overloaded",
        }
    }

    /// The level of a name ([`LoadLevel::name`]).
    pub fn from_name(name: &str) -> Option<LoadLevel> {
        LoadLevel::ALL.into_iter().find(|l| l.name() == name)
    }

    /// The 2-bit code on the sensor's D1..D0 (docs/lab-bus.md): 0 empty .. 3 overloaded.
    pub fn code(self) -> u8 {
        match self {
            LoadLevel::Empty => 0,
            LoadLevel::Loaded => 1,
            LoadLevel::Full => 2,
            LoadLevel::Overloaded => 3,
        }
    }
}

/// One of the two NC channels of the STOP switch wired to the safety logic (docs/safety.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum StopChannel {
    /// The first NC contact (ESTOP input 1).
    One,
    /// The second NC contact (ESTOP input 2).
    Two,
}

/// A fault of one contact, for testing the safety logic's discrepancy check.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum ContactFault {
    /// The contact works.
    #[default]
    None,
    /// Welded or bridged: reads closed whatever the button does.
    StuckClosed,
    /// Broken wire: reads open whatever the button does.
    StuckOpen,
}

/// A fault of a sensor's output, injected to test what the controller and the safety logic do
/// when a sensor fails.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum SensorFault {
    /// The sensor works.
    #[default]
    None,
    /// The output reads "on" whatever the sensor sees.
    StuckOn,
    /// The output reads "off" whatever the sensor sees (a broken wire).
    StuckOff,
}

impl SensorFault {
    /// What the output reads when the sensor sees `level`.
    pub fn reads(self, level: bool) -> bool {
        match self {
            SensorFault::None => level,
            SensorFault::StuckOn => true,
            SensorFault::StuckOff => false,
        }
    }
}

impl ContactFault {
    /// What an NC contact reads (`true` = closed) when the button is `pressed`.
    #[inline]
    pub(crate) fn nc_reads(self, pressed: bool) -> bool {
        match self {
            ContactFault::None => !pressed,
            ContactFault::StuckClosed => true,
            ContactFault::StuckOpen => false,
        }
    }
}

/// The buttons' press state: for each button the instant it is released, `None` when up.
///
/// Layout: cabin 1..N, hall up 1..N, hall down 1..N, bell, STOP (hall up at the top floor
/// and hall down at floor 1 exist in the table but are never pressed).
#[derive(Clone, Debug)]
pub(crate) struct Buttons {
    floors: u8,
    release_at: Vec<Option<SimTime>>,
    /// The earliest finite release, cached: [`SimTime::MAX`] means held for ever.
    next_release: Option<SimTime>,
}

impl Buttons {
    pub fn new(floors: u8) -> Buttons {
        Buttons {
            floors,
            release_at: vec![None; 3 * usize::from(floors) + 2],
            next_release: None,
        }
    }

    /// The slot of `button`, or `None` if the lift does not have it.
    #[inline]
    pub fn index(&self, button: Button) -> Option<usize> {
        let n = self.floors;
        let floor = |f: u8| usize::from(f) - 1;
        match button {
            Button::Cabin(f) if (1..=n).contains(&f) => Some(floor(f)),
            Button::HallUp(f) if (1..n).contains(&f) => Some(usize::from(n) + floor(f)),
            Button::HallDown(f) if (2..=n).contains(&f) => Some(2 * usize::from(n) + floor(f)),
            Button::Bell => Some(3 * usize::from(n)),
            Button::Stop => Some(3 * usize::from(n) + 1),
            _ => None,
        }
    }

    fn button(&self, index: usize) -> Button {
        let n = usize::from(self.floors);
        // Every index below 3n is a floor button of a floor ≤ n ≤ 24: fits in a u8.
        let floor = |i: usize| (i % n + 1) as u8;
        match index / n {
            0 => Button::Cabin(floor(index)),
            1 => Button::HallUp(floor(index)),
            2 => Button::HallDown(floor(index)),
            _ if index == 3 * n => Button::Bell,
            _ => Button::Stop,
        }
    }

    #[inline]
    pub fn is_pressed(&self, button: Button) -> bool {
        self.index(button)
            .is_some_and(|i| self.release_at[i].is_some())
    }

    /// Pressed until `until` (extending a press in progress, never shortening it).
    pub fn press(&mut self, index: usize, until: SimTime) {
        let slot = &mut self.release_at[index];
        *slot = Some(slot.map_or(until, |t| t.max(until)));
        self.refresh();
    }

    /// Released now.
    pub fn release(&mut self, index: usize) {
        self.release_at[index] = None;
        self.refresh();
    }

    /// When the next press ends, if one ends at all.
    pub fn next_release(&self) -> Option<SimTime> {
        self.next_release
    }

    /// Releases every button whose press ends at `now`, reporting each in slot order.
    pub fn release_due(&mut self, now: SimTime, mut report: impl FnMut(Button)) {
        for index in 0..self.release_at.len() {
            if self.release_at[index] == Some(now) {
                self.release_at[index] = None;
                report(self.button(index));
            }
        }
        self.refresh();
    }

    fn refresh(&mut self) {
        self.next_release = self
            .release_at
            .iter()
            .flatten()
            .copied()
            .filter(|&t| t != SimTime::MAX)
            .min();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_fitted_button_has_its_own_slot_and_maps_back() {
        let buttons = Buttons::new(4);
        let mut fitted = Vec::new();
        for f in 0..=5 {
            fitted.extend([Button::Cabin(f), Button::HallUp(f), Button::HallDown(f)]);
        }
        fitted.extend([Button::Bell, Button::Stop]);
        let slots: Vec<(Button, usize)> = fitted
            .into_iter()
            .filter_map(|b| buttons.index(b).map(|i| (b, i)))
            .collect();
        // 4 cabin + 3 up + 3 down + bell + STOP.
        assert_eq!(slots.len(), 12);
        for (b, i) in slots {
            assert_eq!(buttons.button(i), b);
        }
        assert_eq!(buttons.index(Button::HallUp(4)), None);
        assert_eq!(buttons.index(Button::HallDown(1)), None);
        assert_eq!(buttons.index(Button::Cabin(0)), None);
        assert_eq!(buttons.index(Button::Cabin(5)), None);
    }
}
