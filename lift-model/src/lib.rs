//! lift-model: the laboratory lift of seed 003 as a physical plant (SPEC §4).
