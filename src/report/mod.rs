//! Reports: plots (plotters, PNG, with an embedded DejaVu Sans so no system fonts are needed),
//! the machine facts every manifest carries, the evaluation report's format and the leaderboard
//! that aggregates them. Depends on no other module of the crate but `flow` (its field type).

pub mod eval;
pub mod leaderboard;
pub mod manifest;
pub mod plots;
pub mod table;
