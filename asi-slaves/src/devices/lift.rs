//! The lift's AC2726 modules with the floor and cabin electronics behind them (§4 of the lift
//! thesis, tables 4.2–4.7).
//!
//! The electronics sit behind a plain I/O module: the module samples its input pins when it
//! receives a Data_Exchange and then drives its outputs; the electronics react to the new
//! outputs and set the input pins for the next Data_Exchange.

use super::any_impls;
use crate::device_handshake::{CabinDisplaySlave, CabinPanelSlave, FloorStationSlave};
use crate::slave::Peripheral;
use asi_phy::handshake_words::CabinPanelState;
use asi_phy::{Nibble, SimTime};
use core::fmt::Debug;

/// The device side of a handshake, stepped with the output bits it receives.
pub trait HandshakeEngine: Clone + Debug + Default + Send + 'static {
    /// The new outputs in, the input pins to set out.
    fn step(&mut self, outputs: Nibble) -> Nibble;
    /// Power-up reset.
    fn reset(&mut self);
}

macro_rules! engine {
    ($t:ty) => {
        impl HandshakeEngine for $t {
            fn step(&mut self, outputs: Nibble) -> Nibble {
                <$t>::step(self, outputs)
            }
            fn reset(&mut self) {
                <$t>::reset(self)
            }
        }
    };
}
engine!(FloorStationSlave);
engine!(CabinDisplaySlave);
engine!(CabinPanelSlave);

/// An AC2726 module with handshake electronics `E` behind its ports.
#[derive(Clone, Debug, Default)]
pub struct HandshakeModule<E> {
    engine: E,
    pins: Nibble,
}

impl<E: HandshakeEngine> HandshakeModule<E> {
    /// A module that has just powered up.
    pub fn new() -> Self {
        Self::default()
    }
    /// The electronics.
    pub fn engine(&self) -> &E {
        &self.engine
    }
}

impl<E: HandshakeEngine> Peripheral for HandshakeModule<E> {
    fn exchange(&mut self, _now: SimTime, outputs: Nibble) -> Nibble {
        let sampled = self.pins;
        self.pins = self.engine.step(outputs);
        sampled
    }
    fn reset(&mut self) {
        self.engine.reset();
        self.pins = Nibble::ZERO;
    }
    any_impls!();
}

/// A floor station (addresses 1..4): up/down call buttons in, the display word out.
pub type FloorStation = HandshakeModule<FloorStationSlave>;
/// The cabin display (address 5): the display word in.
pub type CabinDisplay = HandshakeModule<CabinDisplaySlave>;
/// The cabin panel (address 6): floor buttons 1..24, bell, STOP, door closed (SnZavD) and the
/// vane sensors Snimac_1 (left) and Snimac_2 (right), sent as one 32-bit word.
pub type CabinPanel = HandshakeModule<CabinPanelSlave>;

impl FloorStation {
    /// The call buttons' levels (a press is latched until reported).
    pub fn set_buttons(&mut self, up: bool, down: bool) {
        self.engine.set_buttons(up, down);
    }
    /// The display word shown (last good word received), `None` while blank.
    pub fn display(&self) -> Option<u16> {
        self.engine.display()
    }
}

impl CabinDisplay {
    /// The display word shown, `None` while blank.
    pub fn display(&self) -> Option<u16> {
        self.engine.display()
    }
}

impl CabinPanel {
    /// All signal levels at once.
    pub fn signals_mut(&mut self) -> &mut CabinPanelState {
        self.engine.signals_mut()
    }
    /// All signal levels.
    pub fn signals(&self) -> &CabinPanelState {
        self.engine.signals()
    }
    /// The button of `floor` (1..=24; others are ignored).
    pub fn set_floor_button(&mut self, floor: u8, pressed: bool) {
        if (1..=24).contains(&floor) {
            let s = self.engine.signals_mut();
            let bit = 1u32 << (floor - 1);
            s.floor_buttons = if pressed {
                s.floor_buttons | bit
            } else {
                s.floor_buttons & !bit
            };
        }
    }
    /// Bell (Zvonek).
    pub fn set_bell(&mut self, on: bool) {
        self.engine.signals_mut().bell = on;
    }
    /// STOP.
    pub fn set_stop(&mut self, on: bool) {
        self.engine.signals_mut().stop = on;
    }
    /// Door closed (SnZavD).
    pub fn set_door_closed(&mut self, on: bool) {
        self.engine.signals_mut().door_closed = on;
    }
    /// Left vane sensor Snimac_1.
    pub fn set_vane_left(&mut self, on: bool) {
        self.engine.signals_mut().vane_left = on;
    }
    /// Right vane sensor Snimac_2.
    pub fn set_vane_right(&mut self, on: bool) {
        self.engine.signals_mut().vane_right = on;
    }
}
