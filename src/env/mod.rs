//! Flow environments: where solvers (`hgym-solvers`) meet the `Env` contract (`hgym-agents`).
//!
//! Built so far: [`actuation`], the paper's actuators (synthetic jets, surface rotation) and the
//! temporal smoothing of control actions, applied to a solver's wall links. The families, the
//! registry of IDs and the `Env` implementations come next (issue "Flow environments").

pub mod actuation;
