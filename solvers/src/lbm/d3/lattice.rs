//! The D3Q19 and D3Q27 velocity sets (Qian, d'Humieres & Lallemand 1992).
//!
//! Directions: 0 rest; 1-6 the axes (+x, -x, +y, -y, +z, -z); then the twelve edge diagonals;
//! D3Q27 adds the eight corners. Weights: D3Q19 1/3, 1/18, 1/36; D3Q27 8/27, 2/27, 1/54, 1/216.
//! Both have `c_s^2 = 1/3` and are isotropic to the second-order Hermite terms the equilibrium
//! needs.

/// A 3D velocity set with `Q` directions, as types so that every loop over directions in the
/// kernel has its bounds and coefficients at compile time.
pub trait Lattice3<const Q: usize>: Copy + Send + Sync + 'static {
    /// Name as the CLI spells it (`d3q19`).
    const NAME: &'static str;
    /// Lattice velocities `c_i`.
    const C: [[i32; 3]; Q];
    /// Weights `w_i`.
    const W: [f32; Q];
    /// Opposite direction: `c_{OPP[i]} = -c_i`.
    const OPP: [usize; Q] = opposites(&Self::C);
    /// The same tables behind `'static` references: indexing an associated `const` array with a
    /// run-time index (in loops over directions that are not unrolled) copies the whole array
    /// each time; these index static memory.
    const C_REF: &'static [[i32; 3]; Q] = &Self::C;
    const W_REF: &'static [f32; Q] = &Self::W;
    const OPP_REF: &'static [usize; Q] = &Self::OPP;
    /// Compile-time check that direction 0 is the rest and directions `2p + 1` and `2p + 2` are
    /// opposites, the pairs the collision is written on (evaluated where the collision uses it).
    const PAIRED: () = assert!(paired(&Self::C), "directions 2p+1 and 2p+2 must be opposites");
    /// Bytes moved per cell update by the fused A-B kernel with FP32 storage: `Q` populations
    /// read and `Q` written (152 for D3Q19, 216 for D3Q27).
    const BYTES_PER_CELL_F32: usize = 2 * Q * 4;
}

/// Index of the opposite of every direction.
const fn opposites<const Q: usize>(c: &[[i32; 3]; Q]) -> [usize; Q] {
    let mut opp = [0usize; Q];
    let mut i = 0;
    while i < Q {
        let mut j = 0;
        while j < Q {
            if c[j][0] == -c[i][0] && c[j][1] == -c[i][1] && c[j][2] == -c[i][2] {
                opp[i] = j;
            }
            j += 1;
        }
        i += 1;
    }
    opp
}

/// Whether `c[0]` is the rest and `c[2p + 1] = -c[2p + 2]` for every pair.
const fn paired<const Q: usize>(c: &[[i32; 3]; Q]) -> bool {
    if Q.is_multiple_of(2) || c[0][0] != 0 || c[0][1] != 0 || c[0][2] != 0 {
        return false;
    }
    let mut p = 0;
    while 2 * p + 2 < Q {
        let (a, b) = (c[2 * p + 1], c[2 * p + 2]);
        if a[0] != -b[0] || a[1] != -b[1] || a[2] != -b[2] {
            return false;
        }
        p += 1;
    }
    true
}

/// The rest, axis and edge velocities shared by both sets.
const C19: [[i32; 3]; 19] = [
    [0, 0, 0],
    [1, 0, 0],
    [-1, 0, 0],
    [0, 1, 0],
    [0, -1, 0],
    [0, 0, 1],
    [0, 0, -1],
    [1, 1, 0],
    [-1, -1, 0],
    [1, -1, 0],
    [-1, 1, 0],
    [1, 0, 1],
    [-1, 0, -1],
    [1, 0, -1],
    [-1, 0, 1],
    [0, 1, 1],
    [0, -1, -1],
    [0, 1, -1],
    [0, -1, 1],
];

const fn extend_27() -> [[i32; 3]; 27] {
    let mut c = [[0i32; 3]; 27];
    let mut i = 0;
    while i < 19 {
        c[i] = C19[i];
        i += 1;
    }
    let corners = [
        [1, 1, 1],
        [-1, -1, -1],
        [1, 1, -1],
        [-1, -1, 1],
        [1, -1, 1],
        [-1, 1, -1],
        [-1, 1, 1],
        [1, -1, -1],
    ];
    let mut k = 0;
    while k < 8 {
        c[19 + k] = corners[k];
        k += 1;
    }
    c
}

const fn weights<const Q: usize>(c: &[[i32; 3]; Q], w: [f32; 4]) -> [f32; Q] {
    let mut out = [0.0f32; Q];
    let mut i = 0;
    while i < Q {
        let n = (c[i][0] * c[i][0] + c[i][1] * c[i][1] + c[i][2] * c[i][2]) as usize;
        out[i] = w[n];
        i += 1;
    }
    out
}

/// D3Q19.
#[derive(Clone, Copy, Debug)]
pub struct D3q19;

impl Lattice3<19> for D3q19 {
    const NAME: &'static str = "d3q19";
    const C: [[i32; 3]; 19] = C19;
    const W: [f32; 19] = weights(&C19, [1.0 / 3.0, 1.0 / 18.0, 1.0 / 36.0, 0.0]);
}

/// D3Q27.
#[derive(Clone, Copy, Debug)]
pub struct D3q27;

impl Lattice3<27> for D3q27 {
    const NAME: &'static str = "d3q27";
    const C: [[i32; 3]; 27] = extend_27();
    const W: [f32; 27] = weights(&extend_27(), [8.0 / 27.0, 2.0 / 27.0, 1.0 / 54.0, 1.0 / 216.0]);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `sum w = 1`, `sum w c_a c_b = c_s^2 delta_ab`, `sum w c_a c_b c_c c_d = c_s^4 (delta delta
    /// + 2 perms)`, odd moments zero, and the opposite table.
    fn isotropic<const Q: usize, L: Lattice3<Q>>() {
        let w = |i: usize| L::W[i] as f64;
        let c = |i: usize, a: usize| L::C[i][a] as f64;
        assert!(((0..Q).map(w).sum::<f64>() - 1.0).abs() < 1e-7);
        let d = |a: usize, b: usize| if a == b { 1.0 } else { 0.0 };
        for a in 0..3 {
            assert!((0..Q).map(|i| w(i) * c(i, a)).sum::<f64>().abs() < 1e-7);
            for b in 0..3 {
                let m2: f64 = (0..Q).map(|i| w(i) * c(i, a) * c(i, b)).sum();
                assert!((m2 - d(a, b) / 3.0).abs() < 1e-7, "{} second moment {a}{b}", L::NAME);
                for e in 0..3 {
                    for f in 0..3 {
                        let m4: f64 = (0..Q).map(|i| w(i) * c(i, a) * c(i, b) * c(i, e) * c(i, f)).sum();
                        let expect = (d(a, b) * d(e, f) + d(a, e) * d(b, f) + d(a, f) * d(b, e)) / 9.0;
                        assert!((m4 - expect).abs() < 1e-7, "{} fourth moment {a}{b}{e}{f}", L::NAME);
                    }
                }
            }
        }
        for i in 0..Q {
            for a in 0..3 {
                assert_eq!(L::C[L::OPP[i]][a], -L::C[i][a]);
            }
        }
    }

    #[test]
    fn both_sets_are_isotropic_to_fourth_order() {
        isotropic::<19, D3q19>();
        isotropic::<27, D3q27>();
        assert_eq!(D3q19::BYTES_PER_CELL_F32, 152);
        assert_eq!(D3q27::BYTES_PER_CELL_F32, 216);
    }
}
