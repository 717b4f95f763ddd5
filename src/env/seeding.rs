//! Seed mixing shared by the environments.

/// splitmix64 (Steele, Lea & Flood 2014): a seed -> a well-mixed 64-bit value.
pub(crate) fn splitmix64(seed: u64) -> u64 {
    let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A standard normal number for interval `k` of a run seeded `seed` (Box-Muller on two
/// splitmix64 draws): stateless, so any interval's value is known without replaying the others.
pub(crate) fn gaussian(seed: u64, k: u64) -> f64 {
    let a = splitmix64(seed ^ splitmix64(k));
    let b = splitmix64(a);
    let u1 = ((a >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
    let u2 = (b >> 11) as f64 / (1u64 << 53) as f64;
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}
