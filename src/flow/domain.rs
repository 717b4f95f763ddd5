//! The rectangular domain, the kind of each edge, and absorbing layers along edges.

use serde::{Deserialize, Serialize};

use hgym_solvers::lbm::{Side, Sides};

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DomainSpec {
    #[serde(deserialize_with = "super::pair")]
    pub x: [f64; 2],
    #[serde(deserialize_with = "super::pair")]
    pub y: [f64; 2],
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum BoundaryKind {
    Inlet,
    Outlet,
    Periodic,
    Wall,
    FreeSlip,
}

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    pub west: BoundaryKind,
    pub east: BoundaryKind,
    pub south: BoundaryKind,
    pub north: BoundaryKind,
}

impl BoundarySpec {
    /// The solver's domain edges; `inlet` is the lattice velocity profile of the (west) inlet,
    /// one value per row.
    pub fn sides(&self, inlet: &[[f32; 2]]) -> Sides {
        let side = |k: BoundaryKind| match k {
            BoundaryKind::Inlet => Side::Velocity { profile: inlet.to_vec() },
            BoundaryKind::Outlet => Side::Outlet,
            BoundaryKind::Periodic => Side::Periodic,
            BoundaryKind::Wall => Side::Wall,
            BoundaryKind::FreeSlip => Side::FreeSlip,
        };
        Sides {
            west: side(self.west),
            east: side(self.east),
            south: side(self.south),
            north: side(self.north),
        }
    }
}

/// An edge of the rectangular domain, by compass direction.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case")]
pub enum EdgeName {
    West,
    East,
    South,
    North,
}

impl EdgeName {
    pub fn lattice(self) -> hgym_solvers::lbm::Edge {
        use hgym_solvers::lbm::Edge;
        match self {
            EdgeName::West => Edge::West,
            EdgeName::East => Edge::East,
            EdgeName::South => Edge::South,
            EdgeName::North => Edge::North,
        }
    }
}

/// An absorbing layer (see `hgym_solvers::lbm::sponge`): `thickness` in reference lengths,
/// `strength` the relaxation per lattice step at the edge (the ramp is quadratic), target the
/// free stream `(rho, u) = (1, U)`. Used by environment specs (`sponge`) and validation cases
/// (`[[sponge]]`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SpongeSpec {
    pub edge: EdgeName,
    pub thickness: f64,
    pub strength: f64,
}

impl SpongeSpec {
    /// The solver's layer at `cells_per_length` cells per reference length, free stream at lattice
    /// speed `u`: at least one node thick.
    pub fn lattice(&self, cells_per_length: f64, u: f64) -> hgym_solvers::lbm::Sponge {
        hgym_solvers::lbm::Sponge {
            edge: self.edge.lattice(),
            width: ((self.thickness * cells_per_length).round() as usize).max(1),
            strength: self.strength,
            rho: 1.0,
            u: [u, 0.0],
        }
    }
}
