//! A seeded source of Gaussian noise for synthetic measurements.

/// Deterministic standard normal numbers for synthetic measurements (the tests, the
/// walk-through): splitmix64 uniforms (Steele, Lea & Flood 2014) through Box-Muller, so the
/// same seed gives the same noise on every machine.
pub struct GaussianNoise(u64);

impl GaussianNoise {
    /// A sequence starting from `seed`.
    pub fn new(seed: u64) -> Self {
        GaussianNoise(seed)
    }

    /// A uniform number in (0, 1] (53 random bits, so ln(u) is finite).
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }

    /// The next standard normal number (mean 0, standard deviation 1).
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}
