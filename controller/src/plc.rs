//! The PLC around the program: the routines that read and write the AS-i master's process image
//! (seed 003 §6.2, "Komunikuj"), the master side of the handshakes of seed tables 4.2–4.7, and
//! the standard signals exchanged with the safety logic.
//!
//! The program reads and writes only the image words of seed table 4.1: the flag nibble of
//! word 0, one nibble per slave, and the analog output word of the speed set-point.

use crate::program::{
    CabinWord, ControllerConfig, ControllerConfigError, Inputs, Outputs, Program,
};
use asi_master::handshake::{
    CabinDisplayMaster, CabinPanelMaster, DisplayWord, FloorStationMaster,
};
use asi_master::image::{F0_CONFIG_ERROR, F1_APF};
use asi_master::{ProcessImage, SlaveAddr};
use asi_phy::{Nibble, SimTime};

/// The lab lift's slave addresses (SPEC §3 table).
pub mod addr {
    /// Floor station of floor 1; floor `f` is at address `f` (1..=4).
    pub const FLOOR_1: u8 = 1;
    /// The cabin display (handshake of tables 4.4/4.5).
    pub const CABIN_DISPLAY: u8 = 5;
    /// The cabin buttons and sensors (tables 4.6/4.7).
    pub const CABIN_PANEL: u8 = 6;
    /// The converter I/O module: out D0 run, D1 direction; in D0 ready, D1 fault.
    pub const CONVERTER: u8 = 7;
    /// The load sensor: in D1..D0 = 0 empty .. 3 overloaded.
    pub const LOAD: u8 = 8;
    /// The current-loop output of the speed set-point, channel 1.
    pub const SPEED: u8 = 10;
    /// The lab bus has floor stations for this many floors.
    pub const FLOOR_STATIONS: u8 = 4;
}

/// Scans without the echo of the PLC's own K after which the PLC starts a new cabin button
/// word (seed 003 table 4.7; SPEC §3): a step normally completes within a scan or two; a panel
/// that was reset or re-admitted in the middle of a word refuses the request out of sequence,
/// which only a new word recovers (250 ms instead of the engine's default 2.5 s at a 10 ms
/// scan).
pub const PANEL_STALL_LIMIT: u32 = 25;

/// Standard signals from the safety logic.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FromSafety {
    /// ESTOP's EStopOut: `true` = no STOP demand.
    pub estop_out: bool,
}

/// Standard signals to the safety logic.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ToSafety {
    /// Restart of the STOP circuit (pulsed).
    pub restart: bool,
    /// The cabin is overloaded (AND input 1).
    pub overloaded: bool,
}

/// The lab lift's PLC: the program and its I/O routines.
#[derive(Clone, Debug)]
pub struct Plc {
    program: Program,
    floors: Vec<FloorStationMaster>,
    cabin_display: CabinDisplayMaster,
    panel: CabinPanelMaster,
    /// The bus was healthy (no configuration error, no AS-i power fail) at the last scan.
    bus_healthy: bool,
    shown: Option<DisplayWord>,
}

impl Plc {
    /// A PLC with the program set to RUN.
    pub fn new(cfg: ControllerConfig) -> Result<Plc, ControllerConfigError> {
        if cfg.floors > addr::FLOOR_STATIONS {
            return Err(ControllerConfigError {
                field: "floors",
                value: cfg.floors.to_string(),
                rule: "the lab bus has floor stations for 4 floors (addresses 1..4)",
            });
        }
        let floors = (0..cfg.floors).map(|_| FloorStationMaster::new()).collect();
        Ok(Plc {
            program: Program::new(cfg)?,
            floors,
            cabin_display: CabinDisplayMaster::new(),
            panel: CabinPanelMaster::new().with_stall_limit(PANEL_STALL_LIMIT),
            bus_healthy: false,
            shown: None,
        })
    }

    /// The program.
    pub fn program(&self) -> &Program {
        &self.program
    }

    /// The program, to drain its events.
    pub fn program_mut(&mut self) -> &mut Program {
        &mut self.program
    }

    /// The master side of the cabin panel handshake (its word log tells when 32-bit words
    /// arrive, for timing studies).
    pub fn cabin_panel(&self) -> &CabinPanelMaster {
        &self.panel
    }

    /// One PLC scan: read the input image, run the handshakes and the program, write the
    /// output image. Returns the signals for the safety logic.
    pub fn scan(&mut self, now: SimTime, image: &mut ProcessImage, safety: FromSafety) -> ToSafety {
        let input = &image.input;
        let output = &mut image.output;
        let flags = input.word(0);

        // Komunikuj: the master side of the floor, cabin display and cabin button handshakes.
        let mut hall_up = 0u32;
        let mut hall_down = 0u32;
        for (i, station) in self.floors.iter_mut().enumerate() {
            let Some(a) = SlaveAddr::a(addr::FLOOR_1 + i as u8) else {
                continue;
            };
            output.set_nibble(a, station.step(input.nibble(a)));
            let calls = station.take_presses();
            hall_up |= (calls.up as u32) << i;
            hall_down |= (calls.down as u32) << i;
        }
        if let Some(a) = SlaveAddr::a(addr::CABIN_DISPLAY) {
            output.set_nibble(a, self.cabin_display.step(input.nibble(a)));
        }
        let mut cabin = None;
        let healthy = flags & (F0_CONFIG_ERROR | F1_APF) == 0;
        if healthy != self.bus_healthy {
            // A slave left or joined LAS (or the power failed or returned). The cabin word in
            // progress may hold a nibble the master zeroed when the panel left LAS, which looks
            // like an echo of K = 0, or an answer to the activation's default outputs 1111,
            // which look like "K = 1, step 111": start a new word, with the K that differs
            // from the D3 in the image.
            self.panel.reset();
            self.bus_healthy = healthy;
        }
        if let Some(a) = SlaveAddr::a(addr::CABIN_PANEL) {
            output.set_nibble(a, self.panel.step(input.nibble(a)));
            cabin = self.panel.take_update().map(|s| CabinWord {
                buttons: s.floor_buttons,
                bell: s.bell,
                stop: s.stop,
                door_closed: s.door_closed,
                vane_left: s.vane_left,
                vane_right: s.vane_right,
            });
        }
        let converter = SlaveAddr::a(addr::CONVERTER).map_or(Nibble::ZERO, |a| input.nibble(a));
        // D2 is the load sensor's "operation ready" bit (S-1.1): 0 when the slave is off the
        // bus, without power or not ready, and then the load counts as unknown (overloaded).
        let load_nibble = SlaveAddr::a(addr::LOAD).map_or(Nibble::ZERO, |a| input.nibble(a));
        let load = load_nibble.get() & 0b11;
        let load_lost = !load_nibble.bit(2);

        let out = self.program.scan(
            now,
            &Inputs {
                cabin,
                hall_up,
                hall_down,
                load,
                load_lost,
                estop_ok: safety.estop_out,
                converter_ready: converter.bit(0),
                converter_fault: converter.bit(1),
                bus_ok: flags & F0_CONFIG_ERROR == 0,
                power_ok: flags & F1_APF == 0,
            },
        );
        self.write_outputs(&out, output);
        ToSafety {
            restart: out.restart,
            overloaded: out.overloaded,
        }
    }

    /// OvladaniMotoru and the display words: converter nibble, speed set-point, displays.
    fn write_outputs(&mut self, out: &Outputs, output: &mut asi_master::Image) {
        if let Some(a) = SlaveAddr::a(addr::CONVERTER) {
            let n = Nibble::ZERO.with_bit(0, out.run).with_bit(1, out.up);
            output.set_nibble(a, n);
        }
        output.set_analog(addr::SPEED, 1, out.setpoint_ua);
        let d = out.display;
        if let Ok(word) = DisplayWord::new(d.floor, d.up, d.down, d.moving, d.fault) {
            if self.shown != Some(word) {
                self.shown = Some(word);
                for station in &mut self.floors {
                    station.set_word(word);
                }
                self.cabin_display.set_word(word);
            }
        }
    }
}
