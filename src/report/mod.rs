//! Reports: plots (plotters, PNG, with an embedded DejaVu Sans so no system fonts are needed)
//! and the machine facts every manifest carries.

pub mod leaderboard;
pub mod manifest;
pub mod plots;
