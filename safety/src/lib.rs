//! safety: TwinSAFE KL6904 logic and PLCopen blocks guarding the lift (SPEC §6).
