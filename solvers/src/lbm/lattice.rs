//! The D2Q9 velocity set (Qian, d'Humieres & Lallemand 1992).
//!
//! Directions: 0 rest; 1 E, 2 N, 3 W, 4 S; 5 NE, 6 NW, 7 SW, 8 SE.
//! Weights: 4/9 (rest), 1/9 (axis), 1/36 (diagonal); `c_s^2 = 1/3`.

/// Number of discrete velocities.
pub const Q: usize = 9;

/// x components of the lattice velocities `c_i`.
pub const CX: [i32; Q] = [0, 1, 0, -1, 0, 1, -1, -1, 1];
/// y components of the lattice velocities `c_i`.
pub const CY: [i32; Q] = [0, 0, 1, 0, -1, 1, 1, -1, -1];
/// Lattice weights `w_i`.
pub const W: [f32; Q] = [
    4.0 / 9.0,
    1.0 / 9.0,
    1.0 / 9.0,
    1.0 / 9.0,
    1.0 / 9.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
];
/// Index of the opposite direction: `c_{OPP[i]} = -c_i`.
pub const OPP: [usize; Q] = [0, 3, 4, 1, 2, 7, 8, 5, 6];

/// Squared speed of sound.
pub const CS2: f32 = 1.0 / 3.0;

/// Bytes moved per cell update by the fused A-B kernel with FP32 storage: nine populations read
/// and nine written, 4 bytes each. No flag field is read in the bulk loop (boundary cells are a
/// separate list), so this is the whole traffic.
pub const BYTES_PER_CELL_F32: usize = 2 * Q * 4;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn velocity_set_is_isotropic_to_second_order() {
        let sum_w: f32 = W.iter().sum();
        assert!((sum_w - 1.0).abs() < 1e-7);
        for a in 0..2 {
            for b in 0..2 {
                let mut m = 0.0f64;
                for i in 0..Q {
                    let c = [CX[i] as f64, CY[i] as f64];
                    m += W[i] as f64 * c[a] * c[b];
                }
                let expect = if a == b { 1.0 / 3.0 } else { 0.0 };
                assert!((m - expect).abs() < 1e-7, "second moment {a}{b} = {m}");
            }
        }
        for i in 0..Q {
            assert_eq!(CX[OPP[i]], -CX[i]);
            assert_eq!(CY[OPP[i]], -CY[i]);
        }
    }
}
