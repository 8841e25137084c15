//! Seeded Gaussian noise: xorshift64* uniform draws and the Box–Muller
//! transform. The same seed gives the same sequence on every platform.

/// A deterministic Gaussian generator.
#[derive(Clone, Debug)]
pub struct Gaussian {
    state: u64,
    spare: Option<f64>,
}

impl Gaussian {
    /// A generator for `seed`: every seed gives its own stream (the seed
    /// goes through splitmix64, whose output is never zero for xorshift's
    /// sake — a zero is replaced by a constant).
    pub fn new(seed: u64) -> Self {
        let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        Self {
            state: if z == 0 { 0x2545_F491_4F6C_DD1D } else { z },
            spare: None,
        }
    }

    /// One uniform draw in (0, 1] (the stream [`Gaussian::sample`] uses).
    pub fn uniform(&mut self) -> f64 {
        let mut x = self.state;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.state = x;
        // 53 random bits in (0, 1].
        ((x.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }

    /// One draw from N(0, sigma²).
    pub fn sample(&mut self, sigma: f64) -> f64 {
        let unit = match self.spare.take() {
            Some(z) => z,
            None => {
                let (u1, u2) = (self.uniform(), self.uniform());
                let r = libm::sqrt(-2.0 * libm::log(u1));
                let angle = 2.0 * core::f64::consts::PI * u2;
                self.spare = Some(r * libm::sin(angle));
                r * libm::cos(angle)
            }
        };
        sigma * unit
    }
}
