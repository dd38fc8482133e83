//! The master's indicators: the LEDs of the Bihl+Wiedemann BWU1488 master of the lab lift
//! (seed 003, table 3.2 "Seznam LED indikačních prvků a jejich popis"; docs/master.md §2.8).
//!
//! Bihl+Wiedemann's masters light their LEDs from their flags once the self-test after
//! power-on is over (the AS-i/Modbus Gateway manual, §6.2 "Master Start-Up"), so the
//! indicators here are a view of the execution-control flags ([`EcFlags`]) and of what the
//! application tells about the PLC ([`PlcLink`]), nothing of their own. [`LedWatch`] keeps
//! what an engineer standing at the master over the run would have noted: how often each LED
//! changed and how long it was away from the state of undisturbed operation.

use crate::lists::EcFlags;
use asi_phy::{SimDuration, SimTime};
use core::fmt;

/// One LED's light: a colour, steady or flashing, or off.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Led {
    /// Dark.
    #[default]
    Off,
    /// Steady green.
    Green,
    /// Flashing green.
    GreenFlashing,
    /// Steady red.
    Red,
    /// Flashing red.
    RedFlashing,
    /// Steady yellow.
    Yellow,
}

impl Led {
    /// Every light, in the order of [`Led::code`].
    pub const ALL: [Led; 6] = [
        Led::Off,
        Led::Green,
        Led::GreenFlashing,
        Led::Red,
        Led::RedFlashing,
        Led::Yellow,
    ];

    /// `off`, `green`, `green_flashing`, `red`, `red_flashing`, `yellow`: the words of the
    /// report, the VCD and the live view.
    pub const fn name(self) -> &'static str {
        match self {
            Led::Off => "off",
            Led::Green => "green",
            Led::GreenFlashing => "green_flashing",
            Led::Red => "red",
            Led::RedFlashing => "red_flashing",
            Led::Yellow => "yellow",
        }
    }

    /// The light as a number 0..5 (off, green, green flashing, red, red flashing, yellow),
    /// for a Modbus register.
    pub const fn code(self) -> u16 {
        match self {
            Led::Off => 0,
            Led::Green => 1,
            Led::GreenFlashing => 2,
            Led::Red => 3,
            Led::RedFlashing => 4,
            Led::Yellow => 5,
        }
    }
}

impl fmt::Display for Led {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// What the application tells the master about its PLC: the backplane connection and the
/// PLC's operating mode (the SYS and OK LEDs of table 3.2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct PlcLink {
    /// A PLC is connected to the master (SYS green).
    pub connected: bool,
    /// The PLC is in run mode (OK green).
    pub run: bool,
}

impl PlcLink {
    /// No PLC.
    pub const NONE: PlcLink = PlcLink {
        connected: false,
        run: false,
    };
    /// A PLC connected and in run mode.
    pub const RUN: PlcLink = PlcLink {
        connected: true,
        run: true,
    };
}

/// The LEDs of the master (seed 003, table 3.2), one field per row of the table.
///
/// | LED | seed 003 table 3.2 | from |
/// |---|---|---|
/// | `pwr` | green: the master's power is OK | green while the AS-i supply is above the APF threshold (APF = 0), else off |
/// | `ok` | green: OK, PLC in run mode; red: internal error, self test | green while the PLC runs ([`PlcLink::run`]), else off; red is never shown (no internal error or self test is simulated) |
/// | `sys` | green: connection to the PLC exists; none: no connection | green while a PLC is connected ([`PlcLink::connected`]), else off |
/// | `asi` | green: AS-i is OK; red: configuration error | green with Config_OK = 1 and Periphery_OK = 1; red with Config_OK = 0; red flashing with Config_OK = 1 and Periphery_OK = 0 |
/// | `asi_active` | green: active normal operation | green with Normal_Operation_Active = 1, else off |
/// | `prg` | green: automatic addressing enabled | green with Auto_Address_Assign = 1; green flashing with Auto_Address_Available = 1 in normal operation too (one projected slave missing: a new slave at address 0 will take its address); else off |
/// | `prj` | yellow: the master is in configuration mode | yellow with Configuration_Active = 1, else off |
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct MasterLeds {
    /// PWR: the master's power.
    pub pwr: Led,
    /// OK: the PLC in run mode.
    pub ok: Led,
    /// SYS: the connection to the PLC.
    pub sys: Led,
    /// AS-i: the configuration (green OK, red configuration error).
    pub asi: Led,
    /// AS-i: normal operation active.
    pub asi_active: Led,
    /// prg: automatic addressing enabled.
    pub prg: Led,
    /// prj mode: configuration mode.
    pub prj: Led,
}

/// The number of LEDs.
pub const LED_COUNT: usize = 7;

impl MasterLeds {
    /// The LEDs' names in the order of [`MasterLeds::each`]: `pwr`, `ok`, `sys`, `asi`,
    /// `asi_active`, `prg`, `prj`.
    pub const NAMES: [&'static str; LED_COUNT] =
        ["pwr", "ok", "sys", "asi", "asi_active", "prg", "prj"];

    /// What an undisturbed master in protected mode shows, with its PLC connected and
    /// running and automatic addressing enabled: every LED green but `prj` (off).
    pub const NORMAL: MasterLeds = MasterLeds {
        pwr: Led::Green,
        ok: Led::Green,
        sys: Led::Green,
        asi: Led::Green,
        asi_active: Led::Green,
        prg: Led::Green,
        prj: Led::Off,
    };

    /// The LEDs for the master's flags `flags` and the PLC link `plc` (the table of the type).
    pub fn of(flags: EcFlags, plc: PlcLink) -> MasterLeds {
        let lit = |on: bool, led: Led| if on { led } else { Led::Off };
        MasterLeds {
            pwr: lit(!flags.apf(), Led::Green),
            ok: lit(plc.run, Led::Green),
            sys: lit(plc.connected, Led::Green),
            asi: match (flags.config_ok(), flags.periphery_ok()) {
                (false, _) => Led::Red,
                (true, false) => Led::RedFlashing,
                (true, true) => Led::Green,
            },
            asi_active: lit(flags.normal_operation_active(), Led::Green),
            // Available shows only in normal operation, where the inclusion phase would
            // readdress a slave: while detection fills LDS one slave is briefly "missing".
            prg: match (
                flags.auto_address_assign(),
                flags.auto_address_available() && flags.normal_operation_active(),
            ) {
                (false, _) => Led::Off,
                (true, false) => Led::Green,
                (true, true) => Led::GreenFlashing,
            },
            prj: lit(flags.configuration_active(), Led::Yellow),
        }
    }

    /// The LEDs in the order of [`MasterLeds::NAMES`].
    pub const fn each(&self) -> [Led; LED_COUNT] {
        [
            self.pwr,
            self.ok,
            self.sys,
            self.asi,
            self.asi_active,
            self.prg,
            self.prj,
        ]
    }
}

impl fmt::Display for MasterLeds {
    /// `pwr green, ok green, …`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, (name, led)) in Self::NAMES.iter().zip(self.each()).enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{name} {led}")?;
        }
        Ok(())
    }
}

/// The LEDs over a run: how often each changed, and how long each was away from its state in
/// undisturbed operation ([`MasterLeds::NORMAL`]).
///
/// The state at the watch's start is where it begins; a change at that same moment (the
/// application telling about its PLC as it starts) sets the starting state and counts
/// nothing.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LedWatch {
    start: SimTime,
    shown: MasterLeds,
    since: SimTime,
    changes: [u32; LED_COUNT],
    away: [SimDuration; LED_COUNT],
}

impl LedWatch {
    /// A watch begun at `now` with the LEDs `leds`.
    pub fn new(now: SimTime, leds: MasterLeds) -> LedWatch {
        LedWatch {
            start: now,
            shown: leds,
            since: now,
            changes: [0; LED_COUNT],
            away: [SimDuration::ZERO; LED_COUNT],
        }
    }

    /// The LEDs show `leds` from `now` on.
    pub fn observe(&mut self, now: SimTime, leds: MasterLeds) {
        if leds == self.shown {
            return;
        }
        self.settle(now);
        if now > self.start {
            for ((c, old), new) in self
                .changes
                .iter_mut()
                .zip(self.shown.each())
                .zip(leds.each())
            {
                *c += u32::from(old != new);
            }
        }
        self.shown = leds;
    }

    /// Adds the time since the last look to the LEDs that are away from normal.
    fn settle(&mut self, now: SimTime) {
        let span = now - self.since;
        let normal = MasterLeds::NORMAL.each();
        for ((a, led), n) in self.away.iter_mut().zip(self.shown.each()).zip(normal) {
            if led != n {
                *a += span;
            }
        }
        self.since = self.since.max(now);
    }

    /// The LEDs shown now.
    pub fn shown(&self) -> MasterLeds {
        self.shown
    }

    /// How often each LED changed, in the order of [`MasterLeds::NAMES`].
    pub fn changes(&self) -> [u32; LED_COUNT] {
        self.changes
    }

    /// How long each LED was away from [`MasterLeds::NORMAL`] up to `now`, in the order of
    /// [`MasterLeds::NAMES`].
    pub fn away(&self, now: SimTime) -> [SimDuration; LED_COUNT] {
        let mut w = self.clone();
        w.settle(now);
        w.away
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flags(bits: &[u16]) -> EcFlags {
        EcFlags::from_bits(bits.iter().fold(0, |a, b| a | b))
    }

    const RUNNING: [u16; 4] = [
        EcFlags::CONFIG_OK,
        EcFlags::AUTO_ADDRESS_ASSIGN,
        EcFlags::NORMAL_OPERATION_ACTIVE,
        EcFlags::PERIPHERY_OK,
    ];

    #[test]
    fn a_running_master_shows_the_normal_leds() {
        assert_eq!(
            MasterLeds::of(flags(&RUNNING), PlcLink::RUN),
            MasterLeds::NORMAL
        );
    }

    /// One row of table 3.2 at a time: the flag that turns each LED from its normal state.
    #[test]
    fn each_row_of_table_3_2_follows_its_flag() {
        let run = flags(&RUNNING);
        let with = |add: u16, clear: u16, plc: PlcLink| {
            MasterLeds::of(EcFlags::from_bits((run.bits() | add) & !clear), plc)
        };
        // PWR: AS-i power fail.
        assert_eq!(with(EcFlags::APF, 0, PlcLink::RUN).pwr, Led::Off);
        // OK and SYS: the PLC stopped, then gone.
        let stopped = PlcLink {
            connected: true,
            run: false,
        };
        assert_eq!(with(0, 0, stopped).ok, Led::Off);
        assert_eq!(with(0, 0, stopped).sys, Led::Green);
        assert_eq!(with(0, 0, PlcLink::NONE).sys, Led::Off);
        // AS-i: configuration error steady red, a peripheral fault flashing red.
        assert_eq!(with(0, EcFlags::CONFIG_OK, PlcLink::RUN).asi, Led::Red);
        assert_eq!(
            with(0, EcFlags::PERIPHERY_OK, PlcLink::RUN).asi,
            Led::RedFlashing
        );
        assert_eq!(
            with(0, EcFlags::CONFIG_OK | EcFlags::PERIPHERY_OK, PlcLink::RUN).asi,
            Led::Red
        );
        // AS-i active: off outside normal operation.
        assert_eq!(
            with(
                EcFlags::OFFLINE_READY,
                EcFlags::NORMAL_OPERATION_ACTIVE,
                PlcLink::RUN
            )
            .asi_active,
            Led::Off
        );
        // prg: off when not allowed, flashing when a slave can be readdressed.
        assert_eq!(
            with(0, EcFlags::AUTO_ADDRESS_ASSIGN, PlcLink::RUN).prg,
            Led::Off
        );
        assert_eq!(
            with(EcFlags::AUTO_ADDRESS_AVAILABLE, 0, PlcLink::RUN).prg,
            Led::GreenFlashing
        );
        assert_eq!(
            with(
                EcFlags::AUTO_ADDRESS_AVAILABLE,
                EcFlags::NORMAL_OPERATION_ACTIVE,
                PlcLink::RUN
            )
            .prg,
            Led::Green,
            "start-up: not yet"
        );
        // prj: yellow in configuration mode.
        assert_eq!(
            with(EcFlags::CONFIGURATION_ACTIVE, 0, PlcLink::RUN).prj,
            Led::Yellow
        );
    }

    #[test]
    fn the_watch_counts_changes_and_time_away_from_normal() {
        let t = |ms| SimTime::from_millis(ms);
        let off = MasterLeds {
            asi_active: Led::Off,
            ..MasterLeds::NORMAL
        };
        let mut w = LedWatch::new(t(0), MasterLeds::default());
        // At the start: the starting state, no change.
        w.observe(t(0), off);
        assert_eq!(w.changes(), [0; LED_COUNT]);
        w.observe(t(100), MasterLeds::NORMAL);
        w.observe(t(100), MasterLeds::NORMAL);
        w.observe(t(300), off);
        w.observe(t(350), MasterLeds::NORMAL);
        assert_eq!(w.changes(), [0, 0, 0, 0, 3, 0, 0]);
        let away = w.away(t(1000));
        assert_eq!(away[4], SimDuration::from_millis(150));
        assert_eq!(away[0], SimDuration::ZERO);
        assert_eq!(w.shown(), MasterLeds::NORMAL);
        assert_eq!(
            MasterLeds::NORMAL.to_string(),
            "pwr green, ok green, sys green, asi green, asi_active green, prg green, prj off"
        );
    }

    #[test]
    fn led_codes_are_distinct_and_in_order() {
        for (i, l) in Led::ALL.iter().enumerate() {
            assert_eq!(l.code() as usize, i);
        }
    }
}
