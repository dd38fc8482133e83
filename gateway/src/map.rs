//! The gateway's Modbus register map: the AS-i master's process image, lists, flags and
//! diagnostics, the safety logic's signals to and from the PLC, and the simulator's command
//! registers (the book, "The gateway's register map").
//!
//! The map follows the Bihl+Wiedemann AS-i/Modbus gateways: the images word for word in the layout
//! of table 4.1 of the lift thesis (four slaves per register, the lowest address in the highest
//! bits), one coil or discrete input per data bit, the lists as bit lists. Every request is checked
//! whole before anything is written: a request is served completely or answered with an exception
//! and changes nothing.
//!
//! | table | addresses | content | access |
//! |---|---|---|---|
//! | coils | 0..255 | output image bits: coil 4·s + k is D_k of slot s (slot = address for A slaves, 32 + address for B; slot 0 the host flags, slot 32 reserved) | read/write |
//! | coils | 1000, 1001 | to the safety logic: restart of the STOP circuit, cabin overloaded | read/write |
//! | discrete inputs | 0..255 | input image bits, same order (slot 0 = flags F0..F3) | read |
//! | discrete inputs | 256..511 | LAS, LDS, LPS, LPF: 64 bits each, bit n = slave n (A), 32 + n (B) | read |
//! | discrete inputs | 512..520 | Config_OK, LDS.0, Auto_Address_Assign, Auto_Address_Available, Configuration_Active, Normal_Operation_Active, APF, Offline_Ready, Periphery_OK | read |
//! | discrete inputs | 1000..1004 | EStopOut, K1 commanded, K1 aux closed, safety group in RUN, gateway watchdog tripped | read |
//! | input registers | 0..243 | the input data image (table 4.1): flags and slaves 0..15, mailbox 32..49, analog inputs 68..155 | read |
//! | input registers | 1000..1015 | LAS, LDS, LPS, LPF, four registers each (bits 0..15 of the first = slaves 0..15 A) | read |
//! | input registers | 1016, 1017 | execution-control flags (bits as discrete inputs 512..520); configuration error (1 = LDS ≠ LPS) | read |
//! | input registers | 1020..1035 | receiver errors per check (start, alternation, pause, information, parity, end, length) and no response: 32-bit, high word first | read |
//! | input registers | 1040..1042 | AS-i cycle time µs: last mean, minimum, maximum | read |
//! | input registers | 1050..1053 | simulated time, ms, 64-bit, high word first | read |
//! | input registers | 1054 | safety bits: as discrete inputs 1000..1004 in bits 0..4 | read |
//! | input registers | 1055 | the load sensor's level (slave 8, D1..D0: 0 empty .. 3 overloaded) | read |
//! | input registers | 1060..1066 | the master's LEDs (seed 003 table 3.2): PWR, OK, SYS, AS-i, AS-i active, prg, prj; 0 off, 1 green, 2 green flashing, 3 red, 4 red flashing, 5 yellow | read |
//! | input registers | 1070..1076 | how often each LED changed since the start, same order (at most 65535) | read |
//! | input registers | 1100..1163 | each slave's traffic light as the analyser shows it, register 1100 + n for list place n (0..31 = 0/0A..31/31A, 33..63 = 1B..31B; 32 reads 0): 0 none, 1 green, 2 yellow, 3 red | read |
//! | input registers | 1200..1327 | calls per slave, 32-bit, high word first: place n at 1200 + 2n | read |
//! | input registers | 1400..1527 | repeats per slave, 32-bit, as calls | read |
//! | input registers | 1600..1727 | calls failed after their repeat per slave, 32-bit, as calls | read |
//! | input registers | 1800..1863 | drop-outs from LAS per slave, place n at 1800 + n (at most 65535) | read |
//! | holding registers | 0..243 | the output data image (table 4.1): host flags and slaves, mailbox 32..49, analog outputs 68..155 (S-7.3 set-point: word 68) | read/write |
//! | holding registers | 1000 | to the safety logic: bit 0 restart, bit 1 overloaded (as coils 1000, 1001) | read/write |
//! | holding registers | 1008 | watchdog time, ms (0 = off): outputs not written for this long go to zero, and the signals to the safety logic to their safe values, restart 0 and overloaded 1, until the next write | read/write |
//! | holding registers | 2000..2009 | simulator commands (write only, read as 0): press a button, slave off/on line, load, door, reset, acknowledge, power fail, safe-link drop, rescue | write |
//! | holding registers | 3000..3243 | the input data image again, for clients that read holding registers only | read |

use asi_master::image::{F0_CONFIG_ERROR, IMAGE_WORDS};
use asi_master::leds::LED_COUNT;
use asi_master::{EcFlags, Light, PlcLink, SlaveList, SlaveStats, SlaveTable};
use asi_phy::{SimDuration, SimTime, SlaveAddr};
use bitvec::prelude::*;
use controller::plc::ToSafety;
use controller::Outside;
use lab::address::LOAD_SENSOR;
use lift_model::{Button, LoadLevel};
use rig::report::{Actor, ClientLog};
use rig::scenario::{Action, Fault, DEFAULT_HOLD};
use rig::Rig;
use tokio_modbus::{ExceptionCode, Request, Response};

/// Coils and discrete inputs of the image bits: 16 words × 16 bits.
pub const IMAGE_BITS: u16 = 256;
/// First coil and discrete input of the safety signals.
pub const SAFETY_BITS: u16 = 1000;
/// First discrete input of the lists (LAS, LDS, LPS, LPF).
pub const LIST_BITS: u16 = 256;
/// First discrete input of the execution-control flags.
pub const FLAG_BITS: u16 = 512;
/// The execution-control flags in the order of their bits.
pub const EC_FLAGS: [u16; 9] = [
    EcFlags::CONFIG_OK,
    EcFlags::LDS0,
    EcFlags::AUTO_ADDRESS_ASSIGN,
    EcFlags::AUTO_ADDRESS_AVAILABLE,
    EcFlags::CONFIGURATION_ACTIVE,
    EcFlags::NORMAL_OPERATION_ACTIVE,
    EcFlags::APF,
    EcFlags::OFFLINE_READY,
    EcFlags::PERIPHERY_OK,
];
/// First input register of the lists.
pub const LIST_REGISTERS: u16 = 1000;
/// Input register of the execution-control flags.
pub const FLAGS_REGISTER: u16 = 1016;
/// Input register of the configuration error.
pub const CONFIG_ERROR_REGISTER: u16 = 1017;
/// First input register of the error counters.
pub const ERROR_REGISTERS: u16 = 1020;
/// First input register of the cycle times.
pub const CYCLE_REGISTERS: u16 = 1040;
/// First input register of the simulated time.
pub const TIME_REGISTERS: u16 = 1050;
/// Input register of the safety bits.
pub const SAFETY_REGISTER: u16 = 1054;
/// Input register of the load sensor's level (slave 8, D1..D0: 0 empty .. 3 overloaded).
pub const LOAD_REGISTER: u16 = 1055;
/// First input register of the master's LEDs (PWR, OK, SYS, AS-i, AS-i active, prg, prj).
pub const LED_REGISTERS: u16 = 1060;
/// First input register of the LEDs' change counts.
pub const LED_CHANGE_REGISTERS: u16 = 1070;
/// First input register of the slaves' traffic lights, one per list place 0..63.
pub const SLAVE_LIGHT_REGISTERS: u16 = 1100;
/// First input register of the calls per slave (two per list place).
pub const SLAVE_CALL_REGISTERS: u16 = 1200;
/// First input register of the repeats per slave (two per list place).
pub const SLAVE_REPEAT_REGISTERS: u16 = 1400;
/// First input register of the calls failed after their repeat per slave (two per place).
pub const SLAVE_FAILED_REGISTERS: u16 = 1600;
/// First input register of the drop-outs per slave (one per list place).
pub const SLAVE_DROPOUT_REGISTERS: u16 = 1800;
/// List places of the per-slave registers: 0A..31A, 0B..31B.
const PLACES: u16 = 64;
/// Holding register of the signals to the safety logic.
pub const PLC_SIGNALS_REGISTER: u16 = 1000;
/// Holding register of the watchdog time.
pub const WATCHDOG_REGISTER: u16 = 1008;
/// First holding register of the simulator commands.
pub const COMMAND_REGISTERS: u16 = 2000;
/// The simulator commands, in register order.
pub const COMMANDS: [&str; 10] = [
    "press",
    "offline",
    "online",
    "load",
    "door",
    "reset",
    "ack",
    "power-fail",
    "link-drop",
    "rescue",
];
/// First holding register of the input image's mirror.
pub const INPUT_MIRROR: u16 = 3000;
/// The input registers and holding registers of the images.
const IMAGE_REGISTERS: u16 = IMAGE_WORDS as u16;

/// Modbus limits of one request (Modbus application protocol v1.1b3, §6).
const MAX_READ_BITS: u16 = 2000;
const MAX_READ_REGISTERS: u16 = 125;
const MAX_WRITE_BITS: u16 = 1968;
const MAX_WRITE_REGISTERS: u16 = 123;
const MAX_READ_WRITE_REGISTERS: u16 = 121;

/// The default watchdog: outputs not written for this long go to zero.
pub const DEFAULT_WATCHDOG: SimDuration = SimDuration::from_millis(1000);

/// The signals to the safety logic while the watchdog is tripped: the safe values, as an
/// unreadable safety input counts as its unsafe one (no restart of the STOP circuit; the
/// cabin counts as overloaded, so K1 gets no power).
pub const WATCHDOG_SIGNALS: ToSafety = ToSafety {
    restart: false,
    overloaded: true,
};

/// Who owns the output image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Owner {
    /// The built-in PLC program: the gateway only watches.
    Builtin,
    /// The Modbus client is the PLC.
    External,
}

/// The gateway's own state beside the rig: who writes the outputs, the watchdog, counters.
#[derive(Clone, Debug)]
pub struct Gateway {
    owner: Owner,
    signals: ToSafety,
    watchdog: SimDuration,
    last_write: Option<SimTime>,
    tripped: bool,
    /// Requests served.
    pub requests: u64,
    /// Requests answered with an exception.
    pub exceptions: u64,
    /// Watchdog trips.
    pub watchdog_trips: u64,
}

/// A check of one address of a write, before anything is written.
type Checked = Result<(), ExceptionCode>;

impl Gateway {
    /// A gateway for `owner` with the watchdog time `watchdog` (zero = off).
    pub fn new(owner: Owner, watchdog: SimDuration) -> Gateway {
        Gateway {
            owner,
            signals: ToSafety::default(),
            watchdog,
            last_write: None,
            tripped: false,
            requests: 0,
            exceptions: 0,
            watchdog_trips: 0,
        }
    }

    /// Who owns the output image.
    pub fn owner(&self) -> Owner {
        self.owner
    }

    /// Whether the watchdog has zeroed the outputs and no write has come since.
    pub fn watchdog_tripped(&self) -> bool {
        self.tripped
    }

    /// Serves one request at simulated time `now` (the time the simulation has reached).
    pub fn serve(
        &mut self,
        rig: &mut Rig,
        now: SimTime,
        req: &Request<'_>,
    ) -> Result<Response, ExceptionCode> {
        self.requests += 1;
        let r = self.dispatch(rig, now, req);
        if r.is_err() {
            self.exceptions += 1;
        }
        r
    }

    fn dispatch(
        &mut self,
        rig: &mut Rig,
        now: SimTime,
        req: &Request<'_>,
    ) -> Result<Response, ExceptionCode> {
        match req {
            Request::ReadCoils(a, n) => {
                let bits = read(*a, *n, MAX_READ_BITS, |i| self.coil(rig, i))?;
                Ok(Response::ReadCoils(bits))
            }
            Request::ReadDiscreteInputs(a, n) => {
                let bits = read(*a, *n, MAX_READ_BITS, |i| self.discrete_input(rig, i))?;
                Ok(Response::ReadDiscreteInputs(bits))
            }
            Request::ReadInputRegisters(a, n) => {
                // The statistics per slave are worked out once per request, if it asks any.
                let table = std::cell::OnceCell::new();
                let words = read(*a, *n, MAX_READ_REGISTERS, |i| {
                    self.input_register(rig, now, i, &table)
                })?;
                Ok(Response::ReadInputRegisters(words))
            }
            Request::ReadHoldingRegisters(a, n) => {
                let words = read(*a, *n, MAX_READ_REGISTERS, |i| self.holding(rig, i))?;
                Ok(Response::ReadHoldingRegisters(words))
            }
            Request::WriteSingleCoil(a, v) => {
                self.write_coils(rig, now, *a, &[*v])?;
                Ok(Response::WriteSingleCoil(*a, *v))
            }
            Request::WriteMultipleCoils(a, vs) => {
                if vs.is_empty() || vs.len() > MAX_WRITE_BITS as usize {
                    return Err(ExceptionCode::IllegalDataValue);
                }
                self.write_coils(rig, now, *a, vs)?;
                Ok(Response::WriteMultipleCoils(*a, vs.len() as u16))
            }
            Request::WriteSingleRegister(a, v) => {
                self.write_registers(rig, now, *a, &[*v])?;
                Ok(Response::WriteSingleRegister(*a, *v))
            }
            Request::WriteMultipleRegisters(a, vs) => {
                if vs.is_empty() || vs.len() > MAX_WRITE_REGISTERS as usize {
                    return Err(ExceptionCode::IllegalDataValue);
                }
                self.write_registers(rig, now, *a, vs)?;
                Ok(Response::WriteMultipleRegisters(*a, vs.len() as u16))
            }
            Request::ReadWriteMultipleRegisters(ra, rn, wa, vs) => {
                if vs.is_empty() || vs.len() > MAX_READ_WRITE_REGISTERS as usize {
                    return Err(ExceptionCode::IllegalDataValue);
                }
                // Both halves are checked before the write; the read comes after it.
                read(*ra, *rn, MAX_READ_REGISTERS, |i| self.holding(rig, i))?;
                self.write_registers(rig, now, *wa, vs)?;
                let words = read(*ra, *rn, MAX_READ_REGISTERS, |i| self.holding(rig, i))?;
                Ok(Response::ReadWriteMultipleRegisters(words))
            }
            _ => Err(ExceptionCode::IllegalFunction),
        }
    }

    // ----- reads -------------------------------------------------------------------------

    fn coil(&self, rig: &Rig, i: u16) -> Option<bool> {
        if i < IMAGE_BITS {
            return Some(image_bit(rig.lab().bus().image().output.words(), i));
        }
        match i.checked_sub(SAFETY_BITS)? {
            0 => Some(self.signals.restart),
            1 => Some(self.signals.overloaded),
            _ => None,
        }
    }

    fn discrete_input(&self, rig: &Rig, i: u16) -> Option<bool> {
        if i < IMAGE_BITS {
            return Some(image_bit(rig.lab().bus().image().input.words(), i));
        }
        if (LIST_BITS..FLAG_BITS).contains(&i) {
            let k = i - LIST_BITS;
            let list = lists(rig)[usize::from(k / 64)];
            return Some(list_bits(list)[usize::from(k % 64)]);
        }
        if (FLAG_BITS..FLAG_BITS + EC_FLAGS.len() as u16).contains(&i) {
            let flags = rig.lab().bus().master().flags();
            return Some(flags.has(EC_FLAGS[usize::from(i - FLAG_BITS)]));
        }
        let k = i.checked_sub(SAFETY_BITS)?;
        (k < 5).then(|| self.safety_bits(rig) & (1 << k) != 0)
    }

    /// EStopOut, K1 commanded, K1 aux closed, group in RUN, watchdog tripped.
    fn safety_bits(&self, rig: &Rig) -> u16 {
        let diag = rig.safety_diag();
        let k1_commanded = diag.is_some_and(|d| d.k1_open_cause.is_none());
        let run = diag.is_some_and(|d| d.group.state.name() == "RUN");
        u16::from(rig.estop_out())
            | u16::from(k1_commanded) << 1
            | u16::from(rig.lift().k1_aux_closed()) << 2
            | u16::from(run) << 3
            | u16::from(self.tripped) << 4
    }

    fn input_register(
        &self,
        rig: &Rig,
        now: SimTime,
        i: u16,
        table: &std::cell::OnceCell<SlaveTable>,
    ) -> Option<u16> {
        if i < IMAGE_REGISTERS {
            return Some(rig.lab().bus().image().input.word(usize::from(i)));
        }
        if i >= SLAVE_LIGHT_REGISTERS {
            return slave_register(i, || table.get_or_init(|| rig.lab().bus().slave_stats()));
        }
        let master = rig.lab().bus().master();
        if (LIST_REGISTERS..FLAGS_REGISTER).contains(&i) {
            let k = i - LIST_REGISTERS;
            let list = lists(rig)[usize::from(k / 4)];
            return Some(list_words(list)[usize::from(k % 4)]);
        }
        match i {
            FLAGS_REGISTER => {
                let flags = master.flags();
                return Some(
                    EC_FLAGS
                        .iter()
                        .enumerate()
                        .fold(0, |w, (b, &f)| w | u16::from(flags.has(f)) << b),
                );
            }
            CONFIG_ERROR_REGISTER => {
                let config_error = rig.lab().bus().image().input.word(0) & F0_CONFIG_ERROR != 0;
                return Some(u16::from(config_error));
            }
            SAFETY_REGISTER => return Some(self.safety_bits(rig)),
            LOAD_REGISTER => {
                let nibble = SlaveAddr::a(LOAD_SENSOR)
                    .map_or(0, |a| rig.lab().bus().image().input.nibble(a).get());
                return Some(u16::from(nibble & 0b11));
            }
            _ => {}
        }
        if (ERROR_REGISTERS..ERROR_REGISTERS + 16).contains(&i) {
            let stats = rig.lab().bus().stats();
            let k = usize::from(i - ERROR_REGISTERS);
            let count = if k / 2 < 7 {
                stats.response_errors[k / 2] + stats.request_errors[k / 2]
            } else {
                stats.no_response
            };
            return Some(word_of(count, 2, k % 2));
        }
        if (CYCLE_REGISTERS..CYCLE_REGISTERS + 3).contains(&i) {
            let stats = rig.lab().bus().stats();
            let us = |d: SimDuration| (d.as_nanos() / 1000).min(u64::from(u16::MAX)) as u16;
            let mean = stats
                .cycle_total
                .as_nanos()
                .checked_div(stats.cycles)
                .map_or(SimDuration::ZERO, SimDuration::from_nanos);
            return Some(match i - CYCLE_REGISTERS {
                0 => us(mean),
                1 => us(stats.cycle_min),
                _ => us(stats.cycle_max),
            });
        }
        if (TIME_REGISTERS..TIME_REGISTERS + 4).contains(&i) {
            let ms = now.as_nanos() / 1_000_000;
            return Some(word_of(ms, 4, usize::from(i - TIME_REGISTERS)));
        }
        let leds = LED_COUNT as u16;
        if (LED_REGISTERS..LED_REGISTERS + leds).contains(&i) {
            let each = master.leds().each();
            return Some(each[usize::from(i - LED_REGISTERS)].code());
        }
        if (LED_CHANGE_REGISTERS..LED_CHANGE_REGISTERS + leds).contains(&i) {
            let changes = master.led_watch().changes();
            let n = changes[usize::from(i - LED_CHANGE_REGISTERS)];
            return Some(n.min(u32::from(u16::MAX)) as u16);
        }
        None
    }

    fn holding(&self, rig: &Rig, i: u16) -> Option<u16> {
        if i < IMAGE_REGISTERS {
            return Some(rig.lab().bus().image().output.word(usize::from(i)));
        }
        if (INPUT_MIRROR..INPUT_MIRROR + IMAGE_REGISTERS).contains(&i) {
            return Some(
                rig.lab()
                    .bus()
                    .image()
                    .input
                    .word(usize::from(i - INPUT_MIRROR)),
            );
        }
        if (COMMAND_REGISTERS..COMMAND_REGISTERS + COMMANDS.len() as u16).contains(&i) {
            return Some(0);
        }
        match i {
            PLC_SIGNALS_REGISTER => Some(signals_word(self.signals)),
            WATCHDOG_REGISTER => Some((self.watchdog.as_nanos() / 1_000_000) as u16),
            _ => None,
        }
    }

    // ----- writes ------------------------------------------------------------------------

    fn write_coils(&mut self, rig: &mut Rig, now: SimTime, a: u16, vs: &[bool]) -> Checked {
        let addrs = span(a, vs.len())?;
        for (i, &v) in addrs.clone().zip(vs) {
            self.check_coil(i, v)?;
        }
        for (i, &v) in addrs.zip(vs) {
            if i < IMAGE_BITS {
                let image = &mut rig.lab_mut().bus_mut().image_mut().output;
                let (w, bit) = image_bit_position(i);
                let word = image.word(w);
                image.set_word(
                    w,
                    if v {
                        word | 1 << bit
                    } else {
                        word & !(1 << bit)
                    },
                );
            } else if i == SAFETY_BITS {
                self.signals.restart = v;
            } else {
                self.signals.overloaded = v;
            }
        }
        self.wrote(rig, now);
        Ok(())
    }

    fn check_coil(&self, i: u16, v: bool) -> Checked {
        let known = i < IMAGE_BITS || (SAFETY_BITS..SAFETY_BITS + 2).contains(&i);
        if !known {
            return Err(ExceptionCode::IllegalDataAddress);
        }
        self.check_owner()?;
        // Slot 32 (0B) is reserved and stays 0 (table 4.1).
        if (128..132).contains(&i) && v {
            return Err(ExceptionCode::IllegalDataValue);
        }
        Ok(())
    }

    fn check_owner(&self) -> Checked {
        match self.owner {
            Owner::External => Ok(()),
            // The built-in program owns the outputs: a watching client may not write them.
            Owner::Builtin => Err(ExceptionCode::IllegalDataAddress),
        }
    }

    fn write_registers(&mut self, rig: &mut Rig, now: SimTime, a: u16, vs: &[u16]) -> Checked {
        let addrs = span(a, vs.len())?;
        for (i, &v) in addrs.clone().zip(vs) {
            self.check_register(rig, i, v)?;
        }
        let mut outputs = false;
        for (i, &v) in addrs.zip(vs) {
            if i < IMAGE_REGISTERS {
                rig.lab_mut()
                    .bus_mut()
                    .image_mut()
                    .output
                    .set_word(usize::from(i), v);
                outputs = true;
            } else if i == PLC_SIGNALS_REGISTER {
                self.signals = ToSafety {
                    restart: v & 1 != 0,
                    overloaded: v & 2 != 0,
                };
                outputs = true;
            } else if i == WATCHDOG_REGISTER {
                self.watchdog = SimDuration::from_millis(u64::from(v));
            } else {
                let action =
                    command(i - COMMAND_REGISTERS, v).ok_or(ExceptionCode::IllegalDataValue)?;
                rig.act_now(Actor::Client, &action);
            }
        }
        if outputs {
            self.wrote(rig, now);
        }
        Ok(())
    }

    fn check_register(&self, rig: &Rig, i: u16, v: u16) -> Checked {
        if i < IMAGE_REGISTERS || i == PLC_SIGNALS_REGISTER {
            self.check_owner()?;
            if i == 8 && v & 0xF000 != 0 {
                // Slot 0B of the output image is reserved (table 4.1).
                return Err(ExceptionCode::IllegalDataValue);
            }
            if i == PLC_SIGNALS_REGISTER && v > 3 {
                return Err(ExceptionCode::IllegalDataValue);
            }
            return Ok(());
        }
        if i == WATCHDOG_REGISTER {
            return Ok(());
        }
        if (COMMAND_REGISTERS..COMMAND_REGISTERS + COMMANDS.len() as u16).contains(&i) {
            let floors = rig.lift().config().floors;
            return match command(i - COMMAND_REGISTERS, v) {
                Some(Action::Press { button, .. }) => match button.floor() {
                    Some(f) if f > floors => Err(ExceptionCode::IllegalDataValue),
                    _ => Ok(()),
                },
                Some(_) => Ok(()),
                None => Err(ExceptionCode::IllegalDataValue),
            };
        }
        Err(ExceptionCode::IllegalDataAddress)
    }

    /// A sign of life from a client that writes only on change (the TTK4145 front end): the
    /// watchdog starts again, as after a write.
    pub fn alive(&mut self, rig: &mut Rig, now: SimTime) {
        self.wrote(rig, now);
    }

    /// The controller's signals to the safety logic, set by a front end.
    pub fn set_signals(&mut self, rig: &mut Rig, signals: ToSafety) {
        self.signals = signals;
        set_outside_signals(rig, signals);
    }

    /// The client wrote the outputs at `now`: the watchdog starts again.
    fn wrote(&mut self, rig: &mut Rig, now: SimTime) {
        self.last_write = Some(now);
        if self.tripped {
            self.tripped = false;
            rig.log_now(Actor::Gateway, ClientLog::WatchdogClear);
        }
        set_outside_signals(rig, self.signals);
        set_outside_link(rig, PlcLink::RUN);
    }

    /// Zeroes the output image and gives the safety logic [`WATCHDOG_SIGNALS`] if the outside
    /// controller has not written it for the watchdog time by `now`.
    pub fn watch(&mut self, rig: &mut Rig, now: SimTime) {
        let Some(last) = self.last_write else {
            return;
        };
        if self.owner != Owner::External || self.tripped || self.watchdog.is_zero() {
            return;
        }
        if now.saturating_duration_since(last) < self.watchdog {
            return;
        }
        self.tripped = true;
        self.watchdog_trips += 1;
        let image = &mut rig.lab_mut().bus_mut().image_mut().output;
        for w in 0..IMAGE_WORDS {
            image.set_word(w, 0);
        }
        self.signals = WATCHDOG_SIGNALS;
        set_outside_signals(rig, self.signals);
        // The client still holds its connection, but its program no longer runs the lift.
        set_outside_link(
            rig,
            PlcLink {
                connected: true,
                run: false,
            },
        );
        let expired = ClientLog::WatchdogExpired {
            after_ms: self.watchdog.as_nanos() / 1_000_000,
        };
        rig.log_now(Actor::Gateway, expired);
    }
}

/// The register or bit addresses `a .. a + n`, or exception 02 past the 16-bit space.
fn span(a: u16, n: usize) -> Result<impl Iterator<Item = u16> + Clone, ExceptionCode> {
    let end = usize::from(a) + n;
    if end > 1 << 16 {
        return Err(ExceptionCode::IllegalDataAddress);
    }
    // Counted in usize: a span that ends at the last address (65535) is not empty.
    Ok((usize::from(a)..end).map(|i| i as u16))
}

/// Reads `n` items from `a` with `get`; exception 03 for a count outside 1..=`max`, 02 if an
/// address is outside the map.
fn read<T>(
    a: u16,
    n: u16,
    max: u16,
    mut get: impl FnMut(u16) -> Option<T>,
) -> Result<Vec<T>, ExceptionCode> {
    if n == 0 || n > max {
        return Err(ExceptionCode::IllegalDataValue);
    }
    span(a, usize::from(n))?
        .map(&mut get)
        .collect::<Option<Vec<T>>>()
        .ok_or(ExceptionCode::IllegalDataAddress)
}

/// Where image bit `i` (coil or discrete input 0..255) sits: D_k of slot i / 4, in word
/// i / 16, the lowest slot in the highest bits (table 4.1).
pub fn image_bit_position(i: u16) -> (usize, u32) {
    let slot = u32::from(i / 4) % 4;
    let k = u32::from(i % 4);
    (usize::from(i / 16), 12 - 4 * slot + k)
}

fn image_bit(words: &[u16; IMAGE_WORDS], i: u16) -> bool {
    let (w, bit) = image_bit_position(i);
    words[w] >> bit & 1 != 0
}

/// LAS, LDS, LPS and LPF.
fn lists(rig: &Rig) -> [SlaveList; 4] {
    let m = rig.lab().bus().master();
    [m.las(), m.lds(), m.lps(), m.lpf()]
}

/// A list as bits: bit n = list bit n (A slaves 0..31, B slaves 32..63).
fn list_bits(list: SlaveList) -> BitArray<[u64; 1], Lsb0> {
    BitArray::new([list.bits()])
}

/// A list as four registers: the same bits, 16 per register, lowest first.
fn list_words(list: SlaveList) -> [u16; 4] {
    let bits = list_bits(list);
    let mut words = BitArray::<[u16; 4], Lsb0>::ZERO;
    words.clone_from_bitslice(&bits);
    words.into_inner()
}

/// Word `k` of `words` 16-bit words of `v`, the high word first.
/// One count of a slave's statistics.
type Count = fn(&SlaveStats) -> u64;

/// Input register `i` of the statistics per slave (from [`SLAVE_LIGHT_REGISTERS`] on), from
/// the table `table` gives; `None` outside them.
fn slave_register<'a>(i: u16, table: impl FnOnce() -> &'a SlaveTable) -> Option<u16> {
    let pair = |base: u16| {
        (base..base + 2 * PLACES)
            .contains(&i)
            .then(|| ((i - base) / 2, usize::from((i - base) % 2)))
    };
    let single = |base: u16| (base..base + PLACES).contains(&i).then(|| i - base);
    let stats = |place: u16| table().get(place as u8).cloned().unwrap_or_default();
    if let Some(place) = single(SLAVE_LIGHT_REGISTERS) {
        return Some(match stats(place).light {
            None => 0,
            Some(Light::Green) => 1,
            Some(Light::Yellow) => 2,
            Some(Light::Red) => 3,
        });
    }
    if let Some(place) = single(SLAVE_DROPOUT_REGISTERS) {
        return Some(stats(place).dropouts.min(u32::from(u16::MAX)) as u16);
    }
    let counters: [(u16, Count); 3] = [
        (SLAVE_CALL_REGISTERS, |s| s.calls),
        (SLAVE_REPEAT_REGISTERS, |s| s.repeats),
        (SLAVE_FAILED_REGISTERS, |s| s.failed_after_repeat),
    ];
    for (base, count) in counters {
        if let Some((place, k)) = pair(base) {
            let v = count(&stats(place)).min(u64::from(u32::MAX));
            return Some(word_of(v, 2, k));
        }
    }
    None
}

fn word_of(v: u64, words: usize, k: usize) -> u16 {
    (v >> (16 * (words - 1 - k))) as u16
}

fn signals_word(s: ToSafety) -> u16 {
    u16::from(s.restart) | u16::from(s.overloaded) << 1
}

/// The simulator command of register `2000 + k` with value `v`, if `v` is a valid value.
pub fn command(k: u16, v: u16) -> Option<Action> {
    let ms = |v: u16| SimDuration::from_millis(u64::from(v));
    let action = match k {
        0 => Action::Press {
            button: button(v)?,
            hold: DEFAULT_HOLD,
        },
        1 | 2 => {
            let slave = u8::try_from(v).ok().filter(|a| (1..=31).contains(a))?;
            Action::Fault(if k == 1 {
                Fault::SlaveOffline { slave }
            } else {
                Fault::SlaveOnline { slave }
            })
        }
        3 => Action::Load(match v {
            0 => LoadLevel::Empty,
            1 => LoadLevel::Loaded,
            2 => LoadLevel::Full,
            3 => LoadLevel::Overloaded,
            _ => return None,
        }),
        4 if v <= 1 => Action::Door { closed: v == 1 },
        5 if v == 1 => Action::Reset,
        6 if v == 1 => Action::Ack,
        7 if v > 0 => Action::Fault(Fault::PowerFail { duration: ms(v) }),
        8 if v > 0 => Action::Fault(Fault::SafeLinkDrop { duration: ms(v) }),
        9 if v == 1 => Action::Rescue,
        _ => return None,
    };
    Some(action)
}

/// The button of a press command: 0x01ff cabin f, 0x02ff hall up at f, 0x03ff hall down at
/// f, 0x0400 STOP, 0x0500 the bell.
pub fn button(v: u16) -> Option<Button> {
    let f = (v & 0xff) as u8;
    let floor = (1..=24).contains(&f);
    match v >> 8 {
        1 if floor => Some(Button::Cabin(f)),
        2 if floor => Some(Button::HallUp(f)),
        3 if floor => Some(Button::HallDown(f)),
        4 if f == 0 => Some(Button::Stop),
        5 if f == 0 => Some(Button::Bell),
        _ => None,
    }
}

/// Tells the rig's outside controller what the master sees of the client (its SYS and OK
/// LEDs); nothing while the built-in program runs.
fn set_outside_link(rig: &mut Rig, link: PlcLink) {
    if let Some(outside) = rig.controller_mut::<Outside>() {
        outside.set_link(link);
    }
}

/// Hands `signals` to the rig's outside controller; nothing while the built-in program runs.
fn set_outside_signals(rig: &mut Rig, signals: ToSafety) {
    if let Some(outside) = rig.controller_mut::<Outside>() {
        outside.set_signals(signals);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ttk::Ttk;
    use rig::Scenario;

    /// A rig with an outside controller at power-on, the cabin at floor 1.
    fn external_rig() -> Rig {
        let toml = "name = \"t\"\nduration = \"20s\"\n[lift]\nstart_mm = 0.0\n";
        let sc = Scenario::from_toml("t.toml", toml).expect("a scenario");
        Rig::new(sc).expect("a rig").with_external_controller()
    }

    /// Runs `rig` in 1 ms steps from `at` to `until`, as the live loop does.
    fn run_to(rig: &mut Rig, gw: &mut Gateway, at: SimTime, until: SimTime) -> SimTime {
        let mut ttk = Ttk::default();
        let mut at = at;
        while at < until {
            let next = at + SimDuration::from_millis(1);
            at = crate::live::advance(rig, gw, &mut ttk, at, next);
        }
        at
    }

    #[test]
    fn a_tripped_watchdog_gives_the_safety_logic_its_safe_values() {
        let mut rig = external_rig();
        let mut gw = Gateway::new(Owner::External, SimDuration::from_millis(1000));
        rig.act_now(Actor::Rig, &Action::Load(LoadLevel::Overloaded));
        let signals = |gw: &mut Gateway, rig: &mut Rig, at, v| {
            let w = Request::WriteSingleRegister(PLC_SIGNALS_REGISTER, v);
            assert!(gw.serve(rig, at, &w).is_ok());
        };
        // The client pulses the restart and says "overloaded" for 2 s, then goes quiet.
        let mut at = SimTime::ZERO;
        signals(&mut gw, &mut rig, at, 3);
        at = run_to(&mut rig, &mut gw, at, SimTime::from_millis(200));
        while at < SimTime::from_millis(2_000) {
            signals(&mut gw, &mut rig, at, 2);
            at = run_to(&mut rig, &mut gw, at, at + SimDuration::from_millis(100));
        }
        assert!(!rig.lift().k1_closed(), "overloaded: K1 stays open");
        at = run_to(&mut rig, &mut gw, at, SimTime::from_millis(6_000));
        assert!(gw.watchdog_tripped());
        // No restart, overloaded: K1 stays open; the map shows the values the safety logic has.
        assert!(
            !rig.lift().k1_closed(),
            "K1 closed after the watchdog's trip"
        );
        let coils = gw.serve(&mut rig, at, &Request::ReadCoils(SAFETY_BITS, 2));
        assert_eq!(coils, Ok(Response::ReadCoils(vec![false, true])));
        let word = gw.serve(
            &mut rig,
            at,
            &Request::ReadHoldingRegisters(PLC_SIGNALS_REGISTER, 1),
        );
        assert_eq!(word, Ok(Response::ReadHoldingRegisters(vec![2])));
    }

    #[test]
    fn image_bits_follow_table_4_1() {
        // Coil 4 is D0 of slave 1: word 0, bits 8..11 (slot 1).
        assert_eq!(image_bit_position(4), (0, 8));
        // Coil 7 is D3 of slave 1.
        assert_eq!(image_bit_position(7), (0, 11));
        // Coil 0 is D0 of slot 0 (the flags), bit 12.
        assert_eq!(image_bit_position(0), (0, 12));
        // Slave 7 (converter): word 1, slot 3, bits 0..3.
        assert_eq!(image_bit_position(28), (1, 0));
        // Slave 31B: slot 63, word 15, bits 0..3.
        assert_eq!(image_bit_position(255), (15, 3));
        // The same position as the master's own nibble position.
        for n in 1..32u8 {
            let a = asi_phy::SlaveAddr::a(n).expect("an address");
            let (w, shift) = asi_master::image::nibble_position(a).expect("a nibble");
            assert_eq!(image_bit_position(u16::from(n) * 4), (w, shift));
            let b = asi_phy::SlaveAddr::b(n).expect("a B address");
            let (w, shift) = asi_master::image::nibble_position(b).expect("a nibble");
            assert_eq!(image_bit_position((32 + u16::from(n)) * 4), (w, shift));
        }
    }

    #[test]
    fn lists_are_the_same_bits_as_bits_and_as_registers() {
        let mut l = SlaveList::EMPTY;
        for n in [1u8, 6, 12, 17, 31] {
            l.set(asi_phy::SlaveAddr::a(n).expect("an address"), true);
        }
        l.set(asi_phy::SlaveAddr::b(3).expect("a B address"), true);
        assert_eq!(
            list_words(l),
            [0b0001_0000_0100_0010, 0b1000_0000_0000_0010, 0b1000, 0]
        );
        let bits = list_bits(l);
        assert!(bits[6] && bits[35] && !bits[0]);
    }

    #[test]
    fn wide_values_go_high_word_first() {
        assert_eq!(word_of(0x0001_0002, 2, 0), 1);
        assert_eq!(word_of(0x0001_0002, 2, 1), 2);
        assert_eq!(word_of(0x0123_4567_89ab_cdef, 4, 3), 0xcdef);
    }

    #[test]
    fn press_codes_name_the_buttons() {
        assert_eq!(button(0x0103), Some(Button::Cabin(3)));
        assert_eq!(button(0x0201), Some(Button::HallUp(1)));
        assert_eq!(button(0x0304), Some(Button::HallDown(4)));
        assert_eq!(button(0x0400), Some(Button::Stop));
        assert_eq!(button(0x0500), Some(Button::Bell));
        assert_eq!(button(0x0100), None);
        assert_eq!(button(0x0401), None);
        assert_eq!(button(0x0600), None);
        assert!(command(3, 4).is_none());
        assert!(command(1, 32).is_none());
        assert!(command(10, 1).is_none());
        assert_eq!(
            command(1, 7),
            Some(Action::Fault(Fault::SlaveOffline { slave: 7 }))
        );
    }

    #[test]
    fn reads_check_count_and_addresses() {
        let get = |i: u16| (i < 10).then_some(i);
        assert_eq!(read(0, 3, 125, get), Ok(vec![0, 1, 2]));
        assert_eq!(read(8, 3, 125, get), Err(ExceptionCode::IllegalDataAddress));
        assert_eq!(read(0, 0, 125, get), Err(ExceptionCode::IllegalDataValue));
        assert_eq!(read(0, 126, 125, get), Err(ExceptionCode::IllegalDataValue));
        assert_eq!(
            read(65535, 2, 125, get),
            Err(ExceptionCode::IllegalDataAddress)
        );
        // A span that ends exactly at the last address is read, not taken as empty: 65530 + 6
        // must not wrap to 0.
        assert_eq!(read(65530, 6, 125, Some), Ok((65530..=65535).collect()));
        assert_eq!(
            read(65530, 6, 125, get),
            Err(ExceptionCode::IllegalDataAddress)
        );
    }
}
