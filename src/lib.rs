//! asi-lift: the application that wires the simulated AS-i bus, the lab lift, its PLC program and
//! its safety logic together on one simulated clock (SPEC §0).

pub mod campaign;
pub mod capture;
pub mod phy_tools;
pub mod report;
pub mod rig;
pub mod scenario;
pub mod telegrams;
pub mod timing;
pub mod trace;
pub mod vcd;
pub mod vcd_write;
pub mod waves;
