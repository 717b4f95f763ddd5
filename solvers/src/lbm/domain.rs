//! Domain edges and the node-to-physical map.

/// What happens at one edge of the rectangular domain. Walls sit half-way between the last node
/// and the (absent) next one, i.e. at `x = -1/2` or `x = nx - 1/2` in lattice units.
#[derive(Clone, Debug, PartialEq)]
pub enum Side {
    /// Wraps to the opposite side (both sides of an axis must be periodic).
    Periodic,
    /// Resting no-slip wall, half-way bounce-back.
    Wall,
    /// Free-slip (specular reflection) wall: zero normal velocity, zero shear.
    FreeSlip,
    /// Prescribed velocity by half-way bounce-back with a moving-wall term (Ladd 1994; the
    /// "UBB" of waLBerla): `f_k(x) = f*_{opp k}(x) + 6 w_k rho c_k . u_w`. One lattice velocity
    /// per boundary node along the side (index = the coordinate along the side). A velocity
    /// inlet, a moving lid and a resting wall (all zero) are all this.
    Velocity { profile: Vec<[f32; 2]> },
    /// Open boundary that lets vortices leave: the populations that enter from outside are the
    /// edge node's own post-collision ones (zero gradient), shifted to the equilibrium at
    /// `rho = 1` (the non-equilibrium extrapolation of Guo, Zheng & Shi, Chin. Phys. 11, 2002),
    /// which anchors the pressure.
    Outlet,
}

impl Side {
    pub fn name(&self) -> &'static str {
        match self {
            Side::Periodic => "periodic",
            Side::Wall => "wall",
            Side::FreeSlip => "free-slip",
            Side::Velocity { .. } => "velocity",
            Side::Outlet => "outlet",
        }
    }

    /// Walls of any kind (they win over an outlet at a corner).
    pub(crate) fn is_wall_like(&self) -> bool {
        matches!(self, Side::Wall | Side::FreeSlip | Side::Velocity { .. })
    }
}

/// One edge of the domain, by compass direction (west: `x = -1/2`, south: `y = -1/2`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Edge {
    West,
    East,
    South,
    North,
}

impl Edge {
    pub fn name(&self) -> &'static str {
        match self {
            Edge::West => "west",
            Edge::East => "east",
            Edge::South => "south",
            Edge::North => "north",
        }
    }
}

/// The four edges of the domain.
#[derive(Clone, Debug, PartialEq)]
pub struct Sides {
    /// `x = -1/2`
    pub west: Side,
    /// `x = nx - 1/2`
    pub east: Side,
    /// `y = -1/2`
    pub south: Side,
    /// `y = ny - 1/2`
    pub north: Side,
}

impl Sides {
    /// The rule at `edge`.
    pub fn get(&self, edge: Edge) -> &Side {
        match edge {
            Edge::West => &self.west,
            Edge::East => &self.east,
            Edge::South => &self.south,
            Edge::North => &self.north,
        }
    }

    pub fn get_mut(&mut self, edge: Edge) -> &mut Side {
        match edge {
            Edge::West => &mut self.west,
            Edge::East => &mut self.east,
            Edge::South => &mut self.south,
            Edge::North => &mut self.north,
        }
    }

    /// Periodic in both directions.
    pub fn periodic() -> Self {
        Sides {
            west: Side::Periodic,
            east: Side::Periodic,
            south: Side::Periodic,
            north: Side::Periodic,
        }
    }
}

/// Where lattice node `(i, j)` sits in physical space: `origin + (i, j) * dx`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    pub origin: [f64; 2],
    pub dx: f64,
}

impl Grid {
    /// Lattice units: node `(i, j)` at `(i, j)`.
    pub fn lattice() -> Self {
        Grid {
            origin: [0.0, 0.0],
            dx: 1.0,
        }
    }

    pub fn position(&self, x: f64, y: f64) -> [f64; 2] {
        [self.origin[0] + x * self.dx, self.origin[1] + y * self.dx]
    }
}
