//! The six faces of the 3D box and what enters through them. Faces sit half-way between the
//! last node and the (absent) next one, as in 2D; the rules are those of the 2D
//! [`Side`](crate::lbm::Side), written for any direction of a 3D lattice.

use super::collision::moments;
use super::kernel::{Ctx, FaceMoments, FacePull};
use super::lattice::Lattice3;

/// What happens at one face of the box.
#[derive(Clone, Debug, PartialEq)]
pub enum Face {
    /// Wraps to the opposite face (both faces of an axis must be periodic).
    Periodic,
    /// Resting no-slip wall, half-way bounce-back.
    Wall,
    /// Free-slip (specular reflection): zero normal velocity, zero shear.
    FreeSlip,
    /// Velocity (lattice units) by half-way bounce-back with the moving-wall term
    /// `g_k = g*_{opp k} + 6 w_k rho c_k.u`: an inlet, scaled by the solver's velocity scale
    /// (ramps, gusts) and, node by node, by the face's profile (uniform unless set with
    /// `Lbm3::set_face_profile`: a pipe's Poiseuille inflow).
    Velocity([f32; 3]),
    /// Open boundary: zero gradient across the face, shifted to the equilibrium at `rho = 1`
    /// (non-equilibrium extrapolation, Guo, Zheng & Shi 2002), which anchors the pressure.
    Outlet,
}

impl Face {
    pub fn name(&self) -> &'static str {
        match self {
            Face::Periodic => "periodic",
            Face::Wall => "wall",
            Face::FreeSlip => "free-slip",
            Face::Velocity(_) => "velocity",
            Face::Outlet => "outlet",
        }
    }

    /// Whether what enters through the face is computed from the populations (velocity and
    /// outlet faces), not copied.
    pub(crate) fn is_computed(&self) -> bool {
        matches!(self, Face::Velocity(_) | Face::Outlet)
    }

    fn is_wall_like(&self) -> bool {
        matches!(self, Face::Wall | Face::FreeSlip | Face::Velocity(_))
    }
}

/// The faces of the box: `faces[2 a]` at the low end of axis `a` (x = -1/2), `faces[2 a + 1]`
/// at the high end.
#[derive(Clone, Debug, PartialEq)]
pub struct Faces(pub [Face; 6]);

impl Faces {
    /// Periodic along every axis.
    pub fn periodic() -> Self {
        Faces(std::array::from_fn(|_| Face::Periodic))
    }

    /// Whether axis `a` wraps.
    pub fn periodic_axis(&self, a: usize) -> bool {
        self.0[2 * a] == Face::Periodic
    }

    /// The first axis whose two faces disagree on being periodic.
    pub(crate) fn mismatched_axis(&self) -> Option<usize> {
        (0..3).find(|&a| (self.0[2 * a] == Face::Periodic) != (self.0[2 * a + 1] == Face::Periodic))
    }
}

/// The face beyond which the source `p - c_k` of node `p` lies; at an edge or corner a wall wins
/// over an outlet, then the last axis. `None` inside the box.
#[inline]
fn crossed_face<const Q: usize, L: Lattice3<Q>>(c: &Ctx, p: [usize; 3], k: usize) -> Option<usize> {
    let ck = L::C_REF[k];
    let mut face: Option<usize> = None;
    for a in 0..3 {
        let s = p[a] as isize - ck[a] as isize;
        if c.periodic[a] || (0..c.n[a] as isize).contains(&s) {
            continue;
        }
        let f = 2 * a + usize::from(s >= 0);
        let better = match face {
            None => true,
            Some(g) => c.faces.0[f].is_wall_like() || !c.faces.0[g].is_wall_like(),
        };
        if better {
            face = Some(f);
        }
    }
    face
}

/// Where the value entering fluid node `p` in direction `k` from beyond a face is copied from
/// (an index into the populations), for the faces whose value is a copy: periodic, wall and
/// free-slip. `None` for velocity and outlet faces, whose values [`face_value`] computes from
/// the populations of the step. The fast kernel plans these once (`FacePull`).
#[inline]
pub(crate) fn face_source<const Q: usize, L: Lattice3<Q>>(c: &Ctx, p: [usize; 3], k: usize) -> Option<usize> {
    let opp = L::OPP_REF[k];
    // Not outside: cannot happen (a solid source inside the box always has a link).
    let Some(f) = crossed_face::<Q, L>(c, p, k) else {
        return Some(c.idx::<Q>(p, opp));
    };
    match &c.faces.0[f] {
        Face::Periodic | Face::Wall => Some(c.idx::<Q>(p, opp)),
        Face::FreeSlip => {
            // Specular reflection: the population arriving with c_k left the neighbour along the
            // wall with its normal component reversed.
            let ck = L::C_REF[k];
            let a = f / 2;
            let mut m = ck;
            m[a] = -m[a];
            let mirrored = (0..Q).find(|&i| L::C_REF[i] == m).unwrap_or(opp);
            let mut d = ck.map(|v| -v);
            d[a] = 0;
            let b = c.neighbour(p, d).filter(|&b| !c.is_solid(b)).unwrap_or(p);
            Some(c.idx::<Q>(b, mirrored))
        }
        Face::Velocity(_) | Face::Outlet => None,
    }
}

/// Value entering fluid node `p` in direction `k` whose source `p - c_k` lies outside the box.
#[inline]
pub(crate) fn face_value<const Q: usize, L: Lattice3<Q>>(c: &Ctx, src: &[f32], p: [usize; 3], k: usize) -> f32 {
    if let Some(i) = face_source::<Q, L>(c, p, k) {
        return src[i];
    }
    let ck = L::C_REF[k];
    let opp = L::OPP_REF[k];
    let f = crossed_face::<Q, L>(c, p, k).unwrap_or(0);
    match &c.faces.0[f] {
        Face::Velocity(u) => {
            let g: [f32; Q] = std::array::from_fn(|i| src[c.idx::<Q>(p, i)]);
            velocity_value::<Q, L>(c, k, g[opp], moments::<Q, L>(&g).0, u, c.face_profile(f, p))
        }
        Face::Outlet => {
            let b = outlet_node(c, p, ck);
            let g: [f32; Q] = std::array::from_fn(|i| src[c.idx::<Q>(b, i)]);
            let (drho, j) = moments::<Q, L>(&g);
            outlet_value::<Q, L>(k, g[k], drho, j)
        }
        // Copies: answered by `face_source` above.
        Face::Periodic | Face::Wall | Face::FreeSlip => src[c.idx::<Q>(p, opp)],
    }
}

/// The plan of a value that a velocity or outlet face computes ([`FacePull`]): which
/// population and which node of the face's layer [`face_value`] reads.
pub(crate) fn plan_face_pull<const Q: usize, L: Lattice3<Q>>(c: &Ctx, p: [usize; 3], k: usize) -> FacePull {
    let f = crossed_face::<Q, L>(c, p, k).unwrap_or(0);
    let (b, i) = match &c.faces.0[f] {
        Face::Outlet => (outlet_node(c, p, L::C_REF[k]), k),
        _ => (p, L::OPP_REF[k]),
    };
    FacePull {
        src: c.idx::<Q>(b, i) as u32,
        at: FaceMoments::at(c.n, f, b) as u32,
        k: k as u8,
        face: f as u8,
    }
}

/// [`face_value`] for a velocity or outlet face, planned ([`plan_face_pull`]) and with the
/// moments of the face's layer gathered for the step ([`FaceMoments`]): the same arithmetic on
/// the same values.
#[inline]
pub(crate) fn face_value_planned<const Q: usize, L: Lattice3<Q>>(c: &Ctx, src: &[f32], fp: &FacePull) -> f32 {
    let (f, k, at) = (fp.face as usize, fp.k as usize, fp.at as usize);
    let m = c.face_moments.0[f][at];
    match &c.faces.0[f] {
        Face::Velocity(u) => {
            let profile = c.face_profiles[f].get(at).copied().unwrap_or(1.0);
            velocity_value::<Q, L>(c, k, src[fp.src as usize], m[0], u, profile)
        }
        _ => outlet_value::<Q, L>(k, src[fp.src as usize], m[0], [m[1], m[2], m[3]]),
    }
}

/// Half-way bounce-back from a moving face: `g_opp + 6 w_k rho c_k.u` (the face velocity `u`
/// times the solver's velocity scale and the face's profile at the node), with the node's own
/// `rho - 1`.
#[inline]
fn velocity_value<const Q: usize, L: Lattice3<Q>>(c: &Ctx, k: usize, g_opp: f32, drho: f32, u: &[f32; 3], profile: f32) -> f32 {
    let ck = L::C_REF[k];
    let rho = 1.0 + drho;
    let cu = ck[0] as f32 * u[0] + ck[1] as f32 * u[1] + ck[2] as f32 * u[2];
    g_opp + 6.0 * L::W_REF[k] * rho * cu * c.velocity_scale * profile
}

/// The node whose populations an outlet gives to `p` in direction `c_k`: across the face, clamped
/// into the box (`p` itself if that one is solid).
#[inline]
fn outlet_node(c: &Ctx, p: [usize; 3], ck: [i32; 3]) -> [usize; 3] {
    let b = [0, 1, 2].map(|a| {
        let s = p[a] as isize - ck[a] as isize;
        if c.periodic[a] {
            s.rem_euclid(c.n[a] as isize) as usize
        } else {
            s.clamp(0, c.n[a] as isize - 1) as usize
        }
    });
    if c.is_solid(b) {
        p
    } else {
        b
    }
}

/// Zero gradient across an outlet, shifted to `rho = 1`: `g_k - (rho - 1) w_k s_k(u)` of the
/// node across the face, with its moments `(rho - 1, j)` and `s_k` the equilibrium's shape
/// (`f^eq_k = rho w_k s_k(u)`).
#[inline]
fn outlet_value<const Q: usize, L: Lattice3<Q>>(k: usize, gk: f32, drho: f32, j: [f32; 3]) -> f32 {
    let ck = L::C_REF[k];
    let rho = 1.0 + drho;
    let u = j.map(|v| v / rho);
    let cu = 3.0 * (ck[0] as f32 * u[0] + ck[1] as f32 * u[1] + ck[2] as f32 * u[2]);
    let shape = 1.0 + cu + 0.5 * cu * cu - 1.5 * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    gk - drho * L::W_REF[k] * shape
}
