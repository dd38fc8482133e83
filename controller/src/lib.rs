//! controller: the lab lift's PLC program (§6 of the lift thesis; docs/controller.md).
//!
//! The program runs with a fixed scan (10 ms by default), asynchronous to the AS-i cycle, and reads
//! and writes only the master's process image (table 4.1 of the lift thesis) and the few standard
//! signals it exchanges with the safety logic. Its routines follow the lift thesis (figure 6.1):
//! read inputs and run the master side of the handshakes, safety checks, initialisation once
//! (table 6.3), the automat (tables 6.4, 6.5) with the FIFO request memories (§6.5), and write the
//! outputs (converter run and direction, speed set-point, displays).
//!
//! - [`program`]: the logic over plain inputs and outputs, testable on its own;
//! - [`dispatch`]: the lift thesis' FIFO memories and the collective selective control (§5.2.3);
//! - [`fifo`]: FIFO_Kabina and FIFO_Patra;
//! - [`plc`]: the I/O routines over the master's process image and the handshakes.

pub mod contract;
pub mod dispatch;
pub mod fifo;
pub mod plc;
pub mod program;
pub mod structured;

pub use asi_master::ProcessImage;
pub use contract::{Controller, ControllerClone, Outside, PendingCalls, Status};
pub use dispatch::{Algorithm, Dir, HallDir, ServedCall, Source};
pub use program::{
    CabinWord, ControllerConfig, ControllerConfigError, Event, HaltReason, InitStart, Inputs,
    LostReason, Outputs, Program, ProgramEventKind, State,
};
