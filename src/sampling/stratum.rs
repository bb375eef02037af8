//! Draws stratified across the sub-pixel samples of a pixel.
//!
//! A pixel's n sub-pixel samples each make m draws of a stream (say, "the position in technique F's
//! distribution"). Drawn independently, the n·m numbers clump and leave gaps; here they are the n·m points
//! of a lattice with spacing 2⁶⁴/(n·m), shifted by one random offset per pixel and stream: one number falls
//! in each stratum. Sample i's draw d takes point d·n + i, so a sample's own m draws are spread m-fold too.
//! Each number alone is uniform on [0, 2⁶⁴) whatever its point (the shift is), so an estimator that is
//! unbiased with independent uniform numbers stays unbiased; only the covariance between the pixel's
//! samples changes, and it is negative where their integrands are alike (the pixel mean's variance falls).
//!
//! Depends only on [`super::rng`]'s hashing.

use super::rng::{hash3, mix64};

/// Stream tag of the lattice offsets.
const STAGE_STRATUM: u64 = 0x7374_7261_7475_6d00;

/// Where a sample sits among its pixel's sub-pixel samples: what its stratified draws are keyed by.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stratum {
    key: u64,
    index: u32,
    count: u32,
}

impl Stratum {
    /// Sample `index` of `count` (≥ 1) in the pixel identified by `pixel`, at render seed `seed`.
    pub fn new(seed: u64, pixel: u64, index: u32, count: u32) -> Self {
        let count = count.max(1);
        Stratum { key: hash3(seed, STAGE_STRATUM, pixel), index: index.min(count - 1), count }
    }

    /// A sample alone in its pixel (its draws are only spread over its own draws of a stream).
    pub fn alone(seed: u64, pixel: u64) -> Self {
        Stratum::new(seed, pixel, 0, 1)
    }

    /// Draw `d` of the `m` (≥ 1) this sample makes of stream `stream`: 64 uniformly distributed bits. Over
    /// the pixel's samples, the count·m draws of a stream fall one in each of count·m equal strata.
    #[inline]
    pub fn draw(&self, stream: u64, d: u32, m: u32) -> u64 {
        let m = m.max(1);
        let points = self.count as u128 * m as u128;
        let point = d.min(m - 1) as u128 * self.count as u128 + self.index as u128;
        let offset = mix64(self.key ^ mix64(stream.wrapping_add(0x9e37_79b9_7f4a_7c15)));
        offset.wrapping_add(((point << 64) / points) as u64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strata(seed: u64, pixel: u64, stream: u64, n: u32, m: u32) -> Vec<u64> {
        let mut s: Vec<u64> = (0..n)
            .flat_map(|i| {
                let st = Stratum::new(seed, pixel, i, n);
                (0..m).map(move |d| st.draw(stream, d, m))
            })
            .collect();
        s.sort_unstable();
        s
    }

    #[test]
    fn a_pixels_draws_of_a_stream_fall_one_per_stratum() {
        for (n, m) in [(1, 1), (4, 1), (4, 4), (16, 3), (1, 7)] {
            for pixel in 0..50 {
                let s = strata(3, pixel, 11, n, m);
                let width = (1u128 << 64) / (n * m) as u128;
                // Sorted, consecutive draws are one stratum apart (the lattice, shifted and wrapped).
                let gaps: Vec<u128> = s.windows(2).map(|w| (w[1] - w[0]) as u128).collect();
                for g in gaps {
                    assert!(g.abs_diff(width) <= 1, "{n}×{m} pixel {pixel}: gap {g} vs {width}");
                }
            }
        }
    }

    #[test]
    fn each_draw_alone_is_uniform() {
        // Over many pixels, each (sample, draw) position's numbers fill 8 equal bins evenly (χ² with 7 degrees
        // of freedom; 40 is far beyond its 99.999th percentile).
        let (n, m, pixels) = (4u32, 2u32, 8000u64);
        for i in 0..n {
            for d in 0..m {
                let mut bins = [0f64; 8];
                for pixel in 0..pixels {
                    bins[(Stratum::new(9, pixel, i, n).draw(5, d, m) >> 61) as usize] += 1.0;
                }
                let e = pixels as f64 / 8.0;
                let chi2: f64 = bins.iter().map(|b| (b - e) * (b - e) / e).sum();
                assert!(chi2 < 40.0, "sample {i} draw {d}: χ² {chi2} over {bins:?}");
            }
        }
    }

    #[test]
    fn streams_pixels_and_seeds_have_their_own_offsets() {
        let a = Stratum::new(1, 7, 0, 4);
        assert_ne!(a.draw(1, 0, 1), a.draw(2, 0, 1));
        assert_ne!(a.draw(1, 0, 1), Stratum::new(1, 8, 0, 4).draw(1, 0, 1));
        assert_ne!(a.draw(1, 0, 1), Stratum::new(2, 7, 0, 4).draw(1, 0, 1));
        assert_eq!(a.draw(1, 0, 1), Stratum::new(1, 7, 0, 4).draw(1, 0, 1));
    }

    #[test]
    fn out_of_range_arguments_are_clamped_not_panicking() {
        // No sample count is a sample alone; an index past the count is the last sample.
        assert_eq!(Stratum::new(0, 0, 9, 0), Stratum::alone(0, 0));
        assert_eq!(Stratum::new(0, 0, 9, 4), Stratum::new(0, 0, 3, 4));
        // No draw count is one draw; a draw past the count is the last draw.
        let s = Stratum::new(2, 5, 1, 4);
        assert_eq!(s.draw(7, 5, 0), s.draw(7, 0, 1));
        assert_eq!(s.draw(7, 9, 3), s.draw(7, 2, 3));
        let _ = Stratum::alone(0, 0).draw(u64::MAX, u32::MAX, u32::MAX);
    }
}
