//! Counter-based random streams. A stream is identified by a key — typically (seed, stage tag, index) —
//! so the numbers a pixel, sample or cache sees never depend on which thread runs it or in what order.

/// Mixes 64 bits (the SplitMix64 finaliser): every input bit affects every output bit.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Hashes three words into one (seed, stage, index → stream key).
#[inline]
pub fn hash3(a: u64, b: u64, c: u64) -> u64 {
    mix64(mix64(mix64(a ^ 0x9e37_79b9_7f4a_7c15).wrapping_add(b)).wrapping_add(c))
}

/// A PCG32 generator (O'Neill 2014, the XSH-RR variant pbrt uses), started from a hashed key.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

const PCG_MULT: u64 = 0x5851_f42d_4c95_7f2d;

/// The largest f32 below 1; uniform floats are clamped to it so they stay in [0, 1).
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// 64 uniform bits as a number in [0, 1): their top 53 bits over 2⁵³ (every f64 of that grid exactly).
#[inline]
pub fn unit_f64(u: u64) -> f64 {
    (u >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

impl Rng {
    /// A stream for `key` (use [`hash3`] to build keys); `key` selects both start state and sequence.
    pub fn new(key: u64) -> Self {
        let inc = (mix64(key ^ 0xda3e_39cb_94b9_5bdb) << 1) | 1;
        let mut r = Rng { state: 0, inc };
        r.next_u32();
        r.state = r.state.wrapping_add(mix64(key));
        r.next_u32();
        r
    }

    /// The stream for (seed, stage, index).
    pub fn keyed(seed: u64, stage: u64, index: u64) -> Self {
        Rng::new(hash3(seed, stage, index))
    }

    /// The next 32 uniformly distributed bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(PCG_MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// The next 64 uniformly distributed bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        ((self.next_u32() as u64) << 32) | self.next_u32() as u64
    }

    /// A uniform float in [0, 1).
    #[inline]
    pub fn uniform(&mut self) -> f32 {
        ((self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)).min(ONE_MINUS_EPSILON)
    }

    /// A uniform point in [0, 1)².
    #[inline]
    pub fn uniform2(&mut self) -> [f32; 2] {
        [self.uniform(), self.uniform()]
    }

    /// A uniform integer in [0, n) without modulo bias; `n` must be > 0.
    pub fn below(&mut self, n: u32) -> u32 {
        debug_assert!(n > 0);
        let threshold = n.wrapping_neg() % n;
        loop {
            let r = self.next_u32();
            if r >= threshold {
                return r % n;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_key_same_numbers_different_key_different_numbers() {
        let a: Vec<u32> = (0..8)
            .map({
                let mut r = Rng::keyed(1, 2, 3);
                move |_| r.next_u32()
            })
            .collect();
        let b: Vec<u32> = (0..8)
            .map({
                let mut r = Rng::keyed(1, 2, 3);
                move |_| r.next_u32()
            })
            .collect();
        let c: Vec<u32> = (0..8)
            .map({
                let mut r = Rng::keyed(1, 2, 4);
                move |_| r.next_u32()
            })
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn uniform_floats_are_in_range_with_the_right_mean() {
        let mut r = Rng::new(42);
        let n = 100_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let u = r.uniform();
            assert!((0.0..1.0).contains(&u));
            sum += u as f64;
        }
        assert!((sum / n as f64 - 0.5).abs() < 0.005);
    }

    #[test]
    fn below_covers_its_range_evenly() {
        let mut r = Rng::new(7);
        let mut counts = [0u32; 5];
        for _ in 0..50_000 {
            counts[r.below(5) as usize] += 1;
        }
        for c in counts {
            assert!((9_500..10_500).contains(&c), "{counts:?}");
        }
    }
}
