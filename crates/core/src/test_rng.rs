//! A small deterministic generator (xorshift) for the unit tests, so that a failure
//! reproduces and the tests need no extra crate.

use glam::DVec3;

/// Xorshift64 state; seed it with any non-zero value.
pub struct Rng(pub u64);

impl Rng {
    /// The next raw value.
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    /// Uniform in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A point with coordinates uniform in `[lo, hi)`.
    pub fn point(&mut self, lo: f64, hi: f64) -> DVec3 {
        DVec3::new(
            self.uniform(lo, hi),
            self.uniform(lo, hi),
            self.uniform(lo, hi),
        )
    }

    /// A uniform index below `n`.
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    /// `x` moved by up to `ulps` units in the last place either way (through its bits).
    pub fn nudge(&mut self, x: f64, ulps: u64) -> f64 {
        let step = self.next() % (2 * ulps + 1);
        f64::from_bits((x.to_bits() + step).wrapping_sub(ulps))
    }

    /// One of `items`.
    pub fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        items[(self.next() % items.len() as u64) as usize]
    }
}
