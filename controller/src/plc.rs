//! The PLC around the program: the routines that read and write the AS-i master's process image
//! (§6.2 of the lift thesis, "Komunikuj"), the master side of the handshakes of tables 4.2–4.7 of
//! the lift thesis, and the standard signals exchanged with the safety logic.
//!
//! The program reads and writes only the image words of table 4.1 of the lift thesis: the flag
//! nibble of word 0, one nibble per slave, the analog output word of the speed set-point, and the
//! command mailbox (words 32..49) to read the LAS when the master flags a configuration error.
//!
//! **Which slaves the lift needs** (decision): F0 (ConfigError) says that *some* projected
//! slave is missing, not which. While F0 is set the PLC reads the LAS with the mailbox command
//! Read_List (as a PLC asks a Bihl+Wiedemann master through its command interface; the master
//! answers from its lists, no bus call) once per scan, and the bus counts as usable while the
//! slaves the cabin cannot move without are in LAS: the cabin panel (6: vanes, door, STOP,
//! buttons), the converter I/O (7), the load sensor (8) and the speed set-point output (10).
//! A floor station or the cabin display dropping out costs only its calls and its display.
//! The answer arrives one scan after the question, so for the first scan of a configuration
//! error the PLC keeps its last verdict (at most one scan, 10 ms, later than the flag); a
//! mailbox that has not answered for [`LAS_STALE_SCANS`] scans counts as "essential slave
//! missing". The overtravel sensors (11, 12) are not the PLC's business: the safety monitor
//! and the safety logic take K1 away when they are not heard.

use crate::program::{
    CabinWord, ControllerConfig, ControllerConfigError, Inputs, Outputs, Program,
};
use asi_master::image::{F0_CONFIG_ERROR, F1_APF};
use asi_master::mailbox::{self, Command, JobResult};
use asi_master::plc_handshake::{CabinDisplayMaster, CabinPanelMaster, FloorStationMaster};
use asi_master::{Image, ProcessImage, SlaveList};
use asi_phy::{Nibble, SimTime, SlaveAddr};
use lab::address;

/// Scans without an answer from the mailbox after which the LAS counts as unknown, and the
/// essential slaves as missing.
pub const LAS_STALE_SCANS: u32 = 3;

/// Reads the LAS through the command mailbox while the master flags a configuration error.
#[derive(Clone, Debug, Default)]
struct LasReader {
    /// A Read_List job is posted and not answered yet.
    pending: bool,
    /// Scans since the job was posted.
    waited: u32,
    /// The LAS of the last answer in this configuration error.
    las: Option<SlaveList>,
    /// The last verdict: every essential slave in LAS.
    essential_ok: bool,
}

impl LasReader {
    fn new() -> LasReader {
        LasReader {
            essential_ok: true,
            ..LasReader::default()
        }
    }

    /// Whether the essential slaves are in LAS, given F0; posts or collects a Read_List job.
    fn essential_present(&mut self, config_error: bool, input: &Image, output: &mut Image) -> bool {
        if self.pending {
            if let Some((cmd, result, bytes)) = mailbox::completed(input, output) {
                if cmd == Command::ReadList as u8 {
                    self.pending = false;
                    self.las = (result == JobResult::Ok).then(|| {
                        let mut b = [0u8; 8];
                        b.copy_from_slice(&bytes[..8]);
                        SlaveList::from_bits(u64::from_le_bytes(b))
                    });
                }
            } else {
                self.waited += 1;
            }
        }
        if !config_error {
            self.las = None;
            self.essential_ok = true;
            return true;
        }
        if !self.pending {
            mailbox::post(output, Command::ReadList, &[1]);
            self.pending = true;
            self.waited = 0;
        }
        self.essential_ok = match self.las {
            _ if self.waited >= LAS_STALE_SCANS => false,
            Some(las) => address::ESSENTIAL
                .iter()
                .all(|&n| SlaveAddr::a(n).is_some_and(|a| las.contains(a))),
            None => self.essential_ok,
        };
        self.essential_ok
    }
}

/// Scans without the echo of the PLC's own K after which the PLC starts a new cabin button
/// word (table 4.7 of the lift thesis; docs/lab-bus.md): a step normally completes within a scan or
/// two; a panel that was reset or re-admitted in the middle of a word refuses the request out of
/// sequence, which only a new word recovers (250 ms instead of the engine's default 2.5 s at a
/// 10 ms scan).
pub const PANEL_STALL_LIMIT: u32 = 25;

/// Standard signals from the safety logic.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FromSafety {
    /// ESTOP's EStopOut: `true` = no STOP demand.
    pub estop_out: bool,
}

/// The load sensor's reading in the input image (slave 8): the level in D1..D0 (0 empty,
/// 1 loaded, 2 full, 3 overloaded), and D2, "operation ready" (S-1.1), which is 0 when the
/// slave is off the bus (the master zeroes the inputs of a slave not in LAS), without power or
/// not ready. The built-in program and the TTK4145 front end both read it here.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LoadReading {
    /// D1..D0: 0 empty .. 3 overloaded.
    pub level: u8,
    /// The load cannot be read: D2 ("operation ready") is 0.
    pub lost: bool,
}

impl LoadReading {
    /// The load sensor's nibble in `input`.
    pub fn of(input: &Image) -> LoadReading {
        let nibble = SlaveAddr::a(address::LOAD_SENSOR).map_or(Nibble::ZERO, |a| input.nibble(a));
        LoadReading {
            level: nibble.get() & 0b11,
            lost: !nibble.bit(2),
        }
    }

    /// What the safety logic's "overloaded" input gets: overloaded, or a load that cannot be
    /// read, which counts as its unsafe value.
    pub fn overloaded(self) -> bool {
        self.level >= 3 || self.lost
    }
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
    io: PlcIo,
}

impl Plc {
    /// A PLC with the program set to RUN.
    pub fn new(cfg: ControllerConfig) -> Result<Plc, ControllerConfigError> {
        let io = PlcIo::new(cfg.floors)?;
        Ok(Plc {
            program: Program::new(cfg)?,
            io,
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
        self.io.cabin_panel()
    }

    /// One PLC scan: read the input image, run the handshakes and the program, write the
    /// output image. Returns the signals for the safety logic.
    pub fn scan(&mut self, now: SimTime, image: &mut ProcessImage, safety: FromSafety) -> ToSafety {
        let inputs = self.io.read(image, safety);
        let out = self.program.scan(now, &inputs);
        self.io.write(&out, image)
    }
}

/// The PLC's I/O routines for the lab bus, for any program: the master side of the
/// handshakes of tables 4.2–4.7 of the lift thesis, the LAS through the command mailbox, the
/// load sensor, the converter and the S-7.3 speed set-point (§6.2 of the lift thesis,
/// "Komunikuj" and "OvladaniMotoru"). A scan reads the image into [`Inputs`] with
/// [`PlcIo::read`], runs its program, and writes the program's [`Outputs`] with
/// [`PlcIo::write`].
#[derive(Clone, Debug)]
pub struct PlcIo {
    floors: Vec<FloorStationMaster>,
    cabin_display: CabinDisplayMaster,
    panel: CabinPanelMaster,
    /// The bus was healthy (no configuration error, no AS-i power fail) at the last scan.
    bus_healthy: bool,
    /// The display word's bits last handed to the display handshakes.
    shown: Option<u16>,
    las: LasReader,
}

impl PlcIo {
    /// The I/O of a lift with `floors` floors (at most the lab bus's 4 floor stations).
    pub fn new(floors: u8) -> Result<PlcIo, ControllerConfigError> {
        if floors > address::FLOOR_STATIONS {
            return Err(ControllerConfigError {
                field: "floors",
                value: floors.to_string(),
                rule: "the lab bus has floor stations for 4 floors (addresses 1..4)",
            });
        }
        Ok(PlcIo {
            floors: (0..floors).map(|_| FloorStationMaster::new()).collect(),
            cabin_display: CabinDisplayMaster::new(),
            panel: CabinPanelMaster::new().with_stall_limit(PANEL_STALL_LIMIT),
            bus_healthy: false,
            shown: None,
            las: LasReader::new(),
        })
    }

    /// The master side of the cabin panel handshake.
    pub fn cabin_panel(&self) -> &CabinPanelMaster {
        &self.panel
    }

    /// The first half of a scan: the handshakes' next steps (they write their nibbles into
    /// the output image), and what the program reads: the cabin word completed since the
    /// last scan, the hall calls, the load, the converter, the bus and the safety logic's
    /// EStopOut (`safety`).
    pub fn read(&mut self, image: &mut ProcessImage, safety: FromSafety) -> Inputs {
        let input = &image.input;
        let output = &mut image.output;
        let flags = input.word(0);
        let bus_ok = self
            .las
            .essential_present(flags & F0_CONFIG_ERROR != 0, input, output);

        // Komunikuj: the master side of the floor, cabin display and cabin button handshakes.
        let mut hall_up = 0u32;
        let mut hall_down = 0u32;
        for (i, station) in self.floors.iter_mut().enumerate() {
            let Some(a) = SlaveAddr::a(address::FLOOR_1 + i as u8) else {
                continue;
            };
            output.set_nibble(a, station.step(input.nibble(a)));
            let calls = station.take_presses();
            hall_up |= (calls.up as u32) << i;
            hall_down |= (calls.down as u32) << i;
        }
        if let Some(a) = SlaveAddr::a(address::CABIN_DISPLAY) {
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
        if let Some(a) = SlaveAddr::a(address::CABIN_PANEL) {
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
        let converter = SlaveAddr::a(address::CONVERTER).map_or(Nibble::ZERO, |a| input.nibble(a));
        // A load that cannot be read counts as unknown (overloaded): see `LoadReading`.
        let LoadReading {
            level: load,
            lost: load_lost,
        } = LoadReading::of(input);

        Inputs {
            cabin,
            hall_up,
            hall_down,
            load,
            load_lost,
            estop_ok: safety.estop_out,
            converter_ready: converter.bit(0),
            converter_fault: converter.bit(1),
            bus_ok,
            power_ok: flags & F1_APF == 0,
        }
    }

    /// The second half of a scan: the program's outputs `out` into the output image (the
    /// converter's nibble, the speed set-point, the display word for the display
    /// handshakes); returns the signals for the safety logic.
    pub fn write(&mut self, out: &Outputs, image: &mut ProcessImage) -> ToSafety {
        self.write_outputs(out, &mut image.output);
        ToSafety {
            restart: out.restart,
            overloaded: out.overloaded,
        }
    }

    /// OvladaniMotoru and the display words: converter nibble, speed set-point, displays.
    fn write_outputs(&mut self, out: &Outputs, output: &mut asi_master::Image) {
        if let Some(a) = SlaveAddr::a(address::CONVERTER) {
            let n = Nibble::ZERO.with_bit(0, out.run).with_bit(1, out.up);
            output.set_nibble(a, n);
        }
        output.set_analog(address::SPEED_SETPOINT, 1, out.setpoint_ua);
        // The program shows floors 1..=floors (at most 24): every word it decides encodes.
        if let Ok(word) = out.display.encode() {
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

#[cfg(test)]
mod tests {
    use super::*;
    use asi_master::image::MAILBOX_WORD;

    /// The master's answer to the posted job: `las` (A slots) with result Ok.
    fn answer(input: &mut Image, output: &Image, las: &[u8]) {
        let bits = las.iter().fold(0u64, |m, &n| m | 1 << n);
        for (k, b) in bits.to_le_bytes().iter().enumerate() {
            input.set_mailbox_byte(k + 1, *b);
        }
        input.set_word(MAILBOX_WORD, output.word(MAILBOX_WORD) & 0xFF80);
    }

    #[test]
    fn the_las_decides_only_while_f0_is_set_and_only_for_the_essential_slaves() {
        let mut r = LasReader::new();
        let mut input = Image::default();
        let mut output = Image::default();
        assert!(r.essential_present(false, &input, &mut output));
        assert_eq!(output.word(MAILBOX_WORD), 0, "no job without F0");
        // F0 rises: a Read_List(LAS) job is posted; the last verdict holds for this scan.
        assert!(r.essential_present(true, &input, &mut output));
        assert_eq!(output.word(MAILBOX_WORD) >> 8, Command::ReadList as u16);
        assert_eq!(output.mailbox_byte(1), 1, "list 1 = LAS");
        // A floor station and the cabin display are out: the cabin may move.
        answer(&mut input, &output, &[1, 3, 4, 6, 7, 8, 10, 11, 12]);
        assert!(r.essential_present(true, &input, &mut output));
        // The converter I/O is out: hold.
        answer(&mut input, &output, &[1, 2, 3, 4, 5, 6, 8, 10, 11, 12]);
        assert!(!r.essential_present(true, &input, &mut output));
        // Back: the cabin may move again.
        answer(&mut input, &output, &[1, 2, 3, 4, 5, 6, 7, 8, 10, 11, 12]);
        assert!(r.essential_present(true, &input, &mut output));
        // The mailbox stops answering: the last verdict for two scans, then "missing".
        assert!(r.essential_present(true, &input, &mut output));
        assert!(r.essential_present(true, &input, &mut output));
        assert!(!r.essential_present(true, &input, &mut output));
        // F0 clears: every projected slave is there.
        assert!(r.essential_present(false, &input, &mut output));
    }
}
