//! lift-model: the laboratory lift of the lift thesis as a physical plant (docs/lift-plant.md).
//!
//! The plant knows nothing of AS-i. It exposes the signals the rig connects to slave ports and
//! to the safety logic:
//!
//! ```text
//!  safety logic ── K1 coil ──▶ ┌──────────── Lift ────────────┐ ──▶ K1 aux (NC mirror, EDM)
//!  slave 7 ── run, up ───────▶ │ converter ─ motor ─ gearbox  │ ──▶ ready, fault (slave 7)
//!  slave 10 ── Rychlost µA ──▶ │   ─ sprocket ─ cabin ─ brake │ ──▶ Snimac_1/2 (slave 6)
//!  rig ── display words ─────▶ │ shaft: vanes, overtravel,    │ ──▶ overtravel free (11, 12)
//!  scenario ── buttons, door, ▶│        mechanical ends       │ ──▶ buttons, bell, STOP,
//!     load, hand crank, faults │                              │     door, load (1..6, 8)
//!                              └──────────────────────────────┘ ──▶ displays, crashes
//! ```
//!
//! It is sans-IO: [`Lift`] is a state machine over simulated time ([`asi_phy::SimTime`]).
//! Inputs take `now`; [`Lift::next_event`] says when the plant will next change by itself;
//! [`Lift::advance_to`] moves time forward and returns every edge with its exact nanosecond,
//! whatever step the caller takes.
//!
//! # Time contract
//!
//! Between two changes the cabin moves with constant acceleration (converter ramp, brake) or
//! constant velocity (steady running, hand crank); its position at any nanosecond is evaluated
//! from the start of that piece, `x0 + v0·τ + a·τ²/2`, never integrated step by step. Every
//! sensor zone is closed: a vane sensor is on for `from ≤ x ≤ to`, an overtravel sensor is
//! tripped at its trip point and beyond, the cabin may touch a mechanical end but not pass it.
//!
//! **Rounding rule:** an edge happens at the first integer nanosecond at which the evaluated
//! position is past the zone boundary. The analytic root of the quadratic gives a candidate
//! (rounded up), and a short search makes the result agree with the evaluated position bit for
//! bit. So the getters report the new level at [`PlantEvent::at`] and the old level one
//! nanosecond before; ends of ramps and stops are likewise rounded up to the next nanosecond.
//! Since nothing depends on where the caller stopped on the way, one `advance_to` over an
//! hour, a million 1 µs steps or jumps from edge to edge give bit for bit the same edges,
//! times and state.
//!
//! ```
//! use asi_phy::SimTime;
//! use lift_model::{PlantEventKind, Lift, LiftConfig, VaneSensor};
//!
//! let mut lift = Lift::new(LiftConfig::default())?;
//! let t0 = SimTime::ZERO;
//! lift.set_contactor(t0, true)?;
//! lift.set_converter(t0, true, true, 10_000)?; // run up at Rychlost 10000
//! // Jump from edge to edge until the right sensor rises at floor 2.
//! while let Some(t) = lift.next_event() {
//!     let rose = lift
//!         .advance_to(t)?
//!         .any(|e| e.kind == PlantEventKind::Vane { sensor: VaneSensor::Right, on: true });
//!     if rose {
//!         break;
//!     }
//! }
//! // The long track of floor 2 starts 40 mm below its level at 400 mm.
//! assert!((lift.position_mm() - 360.0).abs() < 1e-6);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod config;
pub mod controls;
pub mod display;
pub mod drive;
pub mod event;
mod lift;
mod motion;
mod sensor;
mod shaft;

pub use config::{LiftConfig, LiftConfigError, LEVEL_WINDOW_MM};
pub use controls::{Button, ContactFault, LoadLevel, SensorFault, StopChannel};
pub use display::{DisplayId, DisplayState};
pub use drive::{converter_frequency_hz, DriveConfig};
pub use event::{Crash, PlantEvent, PlantEventKind};
pub use lift::{Events, Lift, PlantError};
pub use sensor::{End, VaneSensor};
