//! STAGE 5 (application, importance caching): one cache's discrete distribution over the VPLs, stored in
//! about one byte per VPL so that 25K caches × 8192 VPLs × three stored distributions stay under 1 GB
//! (ALGORITHMS.md §6.3 plans 4 B per entry: 3.3 GB).
//!
//! Each weight is quantised to an 8-bit code standing for an integer weight on a logarithmic scale
//! (4 exponent bits, 4 mantissa bits: 16 values per octave, 3–6 % steps, a 1 : 61 440 range below the largest
//! weight; smaller weights become 0). Sampling and the pdf read the *integer* weights, so the pdf a draw is
//! weighted with is the probability it was drawn with (up to 2⁻⁶⁴ from the 64-bit random number and the
//! rounding of the pdf to f32):
//! quantisation changes which VPLs get drawn, never the estimator's expectation. The weights are summed
//! in blocks of 64 VPLs (a cumulative u64 per block): a draw is a binary search over the blocks and a scan
//! of at most 64 codes.
//!
//! Depends on nothing but std.

/// VPLs per block of the cumulative table.
const BLOCK: usize = 64;

/// The largest integer weight (code 255).
const MAX_WEIGHT: u32 = weight_of(255);

/// The integer weight of an 8-bit code: 0 for code 0; else (16 + m)·2^e with e = (c − 1) >> 4 and
/// m = (c − 1) & 15.
const fn weight_of(code: u8) -> u32 {
    if code == 0 {
        return 0;
    }
    let c = (code - 1) as u32;
    (16 + (c & 15)) << (c >> 4)
}

/// The weight of every code.
const WEIGHTS: [u32; 256] = {
    let mut w = [0u32; 256];
    let mut c = 0;
    while c < 256 {
        w[c] = weight_of(c as u8);
        c += 1;
    }
    w
};

/// The code whose weight is nearest to `x` (in ratio), for 0 ≤ x ≤ [`MAX_WEIGHT`]; 0 below half the
/// smallest weight. Computed from the bits of `x` with integer operations and selects only (this runs for
/// every VPL of every distribution, and the loop over them vectorises): for 16 ≤ x < 2²⁰ the octave is
/// e = x's binary exponent − 4 and x/2^e − 16 = M/2¹⁹ with M the 23 mantissa bits, so rounding it half away
/// from zero (as `f32::round` does) is (M + 2¹⁸) >> 19 ∈ 0..=16; m = 16 (just below the next octave) gives
/// that octave's first code, (e + 1)·16 + 1 = e·16 + m + 1. Below 16 the code is 1, from 2²⁰ up (and +∞) the
/// largest, 255; below 8, negative or NaN, 0.
#[inline(always)]
fn code_of(x: f32) -> u8 {
    let bits = x.to_bits();
    // Non-negative floats order as their bits: 8.0 ≤ x ≤ +∞ (negative numbers and NaN fall outside).
    let kept = (0x4100_0000..=0x7f80_0000).contains(&bits);
    let exp = bits >> 23;
    let m = (((bits & 0x7f_ffff) + (1 << 18)) >> 19).min(16);
    let c = match exp {
        ..131 => 1,
        131..=146 => ((exp - 131) << 4) + m + 1,
        _ => 255,
    };
    if kept { c.min(255) as u8 } else { 0 }
}

/// The integer weight of `code` as an f32 (exact: every weight is below 2²⁴), from the code's bits alone:
/// (16 + m)·2^e with 2^e built as a float's exponent, so that loops over codes vectorise (a table lookup
/// per code does not).
#[inline(always)]
fn weight_f32(code: u8) -> f32 {
    let c = (code as u32).wrapping_sub(1);
    let w = (16 + (c & 15)) as f32 * f32::from_bits((127 + ((c >> 4) & 15)) << 23);
    if code == 0 { 0.0 } else { w }
}

/// The largest finite value of `values`, and at least 0: eight running maxima (a select, not `f32::max`,
/// whose NaN rule keeps the compiler from vectorising), combined at the end.
pub fn finite_max(values: &[f32]) -> f32 {
    let mut lanes = [0.0f32; 8];
    for chunk in values.chunks(8) {
        for (l, &w) in lanes.iter_mut().zip(chunk) {
            let v = if w.is_finite() { w } else { 0.0 };
            *l = if v > *l { v } else { *l };
        }
    }
    lanes.iter().fold(0.0f32, |a, &b| if b > a { b } else { a })
}

/// A quantised discrete distribution over n items.
#[derive(Clone, Debug, PartialEq)]
pub struct Quantised {
    codes: Box<[u8]>,
    /// cum[b] = Σ of the integer weights of blocks before b; the last entry is the total (> 0).
    cum: Box<[u64]>,
    /// Multiplies an integer weight back to the caller's units (for [`Quantised::value`]).
    scale: f32,
    /// 1 / total in f64: the pdf is a multiplication (it runs for every selected cache of every draw).
    inv_total: f64,
}

impl Quantised {
    /// The distribution proportional to `weights` (negative and non-finite values count as 0), quantised;
    /// `None` when every weight is 0.
    pub fn new(weights: &[f32]) -> Option<Self> {
        let max = finite_max(weights);
        if max <= 0.0 {
            return None;
        }
        let to_int = MAX_WEIGHT as f32 / max;
        // Non-finite weights count as 0 (a select, so the loop vectorises; `code_of` gives 0 to x ≤ 0).
        let mut codes = vec![0u8; weights.len()].into_boxed_slice();
        for (c, &w) in codes.iter_mut().zip(weights) {
            *c = code_of(if w.is_finite() { w * to_int } else { 0.0 });
        }
        let mut cum = Vec::with_capacity(codes.len().div_ceil(BLOCK) + 1);
        let mut total = 0u64;
        cum.push(0);
        for block in codes.chunks(BLOCK) {
            total += block_weight(block);
            cum.push(total);
        }
        Some(Quantised {
            codes,
            cum: cum.into_boxed_slice(),
            scale: max / MAX_WEIGHT as f32,
            inv_total: 1.0 / total as f64,
        })
    }

    /// The smallest weight that keeps a non-zero code in a distribution whose largest weight is `max`
    /// (smaller ones quantise to 0).
    pub fn smallest_kept(max: f32) -> f32 {
        max * (8.0 / MAX_WEIGHT as f32)
    }

    /// Number of items.
    pub fn len(&self) -> usize {
        self.codes.len()
    }

    /// Whether there are no items (never true for a built distribution).
    pub fn is_empty(&self) -> bool {
        self.codes.is_empty()
    }

    fn total(&self) -> u64 {
        self.cum[self.cum.len() - 1]
    }

    /// The probability of item `j`: the probability [`Quantised::sample`] draws it with (weight / total,
    /// computed in f64 and rounded to f32).
    #[inline]
    pub fn pdf(&self, j: usize) -> f32 {
        (WEIGHTS[self.codes[j] as usize] as f64 * self.inv_total) as f32
    }

    /// Σ_j |value_a(j) − value_b(j)| over the items of `self` and `other` (the same count), skipping
    /// blocks where both are zero, summed in eight running sums, item i into sum i mod 8 (vectorisable;
    /// a sequential f32 sum over thousands of items is bound by the addition's latency).
    pub fn abs_diff_sum(&self, other: &Quantised) -> f32 {
        let mut lanes = [0.0f32; 8];
        for b in 0..self.cum.len() - 1 {
            if self.cum[b + 1] == self.cum[b] && other.cum[b + 1] == other.cum[b] {
                continue;
            }
            let end = ((b + 1) * BLOCK).min(self.codes.len());
            let (sa, sb) = (self.scale, other.scale);
            lane_sums(&mut lanes, &self.codes[b * BLOCK..end], &other.codes[b * BLOCK..end], |x, y| {
                (weight_f32(x) * sa - weight_f32(y) * sb).abs()
            });
        }
        lanes.iter().sum()
    }

    /// Σ_j value(j), in the same order as [`Quantised::abs_diff_sum`] against an all-zero distribution.
    pub fn value_sum(&self) -> f32 {
        let mut lanes = [0.0f32; 8];
        for b in 0..self.cum.len() - 1 {
            if self.cum[b + 1] == self.cum[b] {
                continue;
            }
            let end = ((b + 1) * BLOCK).min(self.codes.len());
            let codes = &self.codes[b * BLOCK..end];
            lane_sums(&mut lanes, codes, codes, |x, _| weight_f32(x) * self.scale);
        }
        lanes.iter().sum()
    }

    /// The quantised weight of item `j` in the units of the weights it was built from.
    #[inline]
    pub fn value(&self, j: usize) -> f32 {
        WEIGHTS[self.codes[j] as usize] as f32 * self.scale
    }

    /// Draws an item with 64 uniformly random bits `r`.
    #[inline]
    pub fn sample(&self, r: u64) -> usize {
        // The target integer in [0, total): the high word of r·total.
        let target = ((r as u128 * self.total() as u128) >> 64) as u64;
        // The last block whose start is ≤ target (blocks with zero weight are skipped past by the search:
        // their start equals the next block's).
        let b = self.cum.partition_point(|&c| c <= target) - 1;
        let mut acc = self.cum[b];
        let start = b * BLOCK;
        let end = (start + BLOCK).min(self.codes.len());
        for j in start..end {
            acc += WEIGHTS[self.codes[j] as usize] as u64;
            if target < acc {
                return j;
            }
        }
        // Unreachable for target < total; the block's last non-zero item is the safe answer.
        (start..end).rev().find(|&j| self.codes[j] != 0).unwrap_or(start)
    }

    /// Bytes this distribution occupies, heap included.
    pub fn bytes(&self) -> usize {
        std::mem::size_of::<Self>() + self.codes.len() + self.cum.len() * 8
    }

    /// The most bytes a distribution over `n` items occupies.
    pub fn bytes_for(n: usize) -> usize {
        std::mem::size_of::<Self>() + n + (n.div_ceil(BLOCK) + 1) * 8
    }
}

/// Σ of the integer weights of `codes`, exactly: f64 sums of integers below 2⁵³ do not round, so the
/// eight running sums (vectorisable, unlike a table lookup per code) give the integer sum in any order.
#[inline(always)]
fn block_weight(codes: &[u8]) -> u64 {
    let mut lanes = [0.0f64; 8];
    let chunks = codes.chunks_exact(8);
    let rest = chunks.remainder();
    for x in chunks {
        for k in 0..8 {
            lanes[k] += weight_f32(x[k]) as f64;
        }
    }
    for (k, &x) in rest.iter().enumerate() {
        lanes[k] += weight_f32(x) as f64;
    }
    lanes.iter().sum::<f64>() as u64
}

/// Adds `term(a[i], b[i])` to `lanes[i % 8]` for every i (`a` and `b` of one length, starting at a multiple
/// of 8 of the distribution): eight at a time, so the loop vectorises, in the order a one-at-a-time loop
/// would add them.
#[inline(always)]
fn lane_sums(lanes: &mut [f32; 8], a: &[u8], b: &[u8], term: impl Fn(u8, u8) -> f32) {
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..8 {
            lanes[k] += term(x[k], y[k]);
        }
    }
    for (k, (&x, &y)) in ra.iter().zip(rb).enumerate() {
        lanes[k] += term(x, y);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    #[test]
    fn codes_are_monotone_and_round_to_the_nearest_step() {
        for c in 1..255u8 {
            assert!(WEIGHTS[c as usize] < WEIGHTS[c as usize + 1], "{c}");
        }
        assert_eq!(MAX_WEIGHT, 30 << 15);
        for c in 1..=255u8 {
            assert_eq!(code_of(WEIGHTS[c as usize] as f32), c, "exact weights keep their code");
        }
        for c in 0..=255u8 {
            assert_eq!(weight_f32(c), WEIGHTS[c as usize] as f32, "{c}");
        }
        let codes: Vec<u8> = (0..203u32).map(|i| (i * 97 % 256) as u8).collect();
        assert_eq!(block_weight(&codes), codes.iter().map(|&c| WEIGHTS[c as usize] as u64).sum::<u64>());
        // Every weight from 16 up is within 3.2 % of its code's weight.
        let mut x = 16.0f32;
        while x <= MAX_WEIGHT as f32 {
            let q = WEIGHTS[code_of(x) as usize] as f32;
            assert!((q / x - 1.0).abs() <= 1.0 / 31.0 + 1e-6, "{x} -> {q}");
            x *= 1.013;
        }
        assert_eq!(code_of(7.9), 0);
        let max = 3.5f32;
        let kept = Quantised::new(&[max, Quantised::smallest_kept(max), Quantised::smallest_kept(max) * 0.99]).unwrap();
        assert!(kept.pdf(1) > 0.0 && kept.pdf(2) == 0.0);
        assert_eq!(code_of(f32::NAN), 0);
    }

    /// The library-call formula `code_of` replaces.
    fn code_by_log2(x: f32) -> u8 {
        if x.is_nan() || x < 8.0 {
            return 0;
        }
        if x <= 16.0 {
            return 1;
        }
        let e = ((x / 16.0).log2().floor() as i32).clamp(0, 15) as u32;
        let m = (x / (1u32 << e) as f32 - 16.0).round().clamp(0.0, 16.0) as u32;
        let c = if m == 16 { ((e + 1) << 4) + 1 } else { (e << 4) + m + 1 };
        c.min(255) as u8
    }

    #[test]
    fn codes_from_bits_equal_the_logarithm_formula_for_every_float_in_range() {
        // Every f32 from 7 to 2^21 (past MAX_WEIGHT), plus the extremes.
        let (lo, hi) = (7.0f32.to_bits(), ((1u32 << 21) as f32).to_bits());
        for b in lo..=hi {
            let x = f32::from_bits(b);
            assert_eq!(code_of(x), code_by_log2(x), "{x:e}");
        }
        for x in [0.0, -1.0, f32::INFINITY, f32::MAX, 1e30, f32::NAN] {
            assert_eq!(code_of(x), code_by_log2(x), "{x:e}");
        }
    }

    #[test]
    fn the_pdf_is_the_probability_of_being_drawn() {
        // Enumerate the draw over evenly spaced 64-bit numbers: each item's share of them is its pdf.
        let w: Vec<f32> = (0..200).map(|j| if j % 7 == 3 { 0.0 } else { ((j * 37 % 101) as f32).powi(2) }).collect();
        let d = Quantised::new(&w).unwrap();
        let n = 1u64 << 20;
        let mut hits = vec![0u64; w.len()];
        for i in 0..n {
            hits[d.sample(i.wrapping_mul(u64::MAX / n))] += 1;
        }
        let mut sum = 0.0f64;
        for (j, &h) in hits.iter().enumerate() {
            let p = d.pdf(j) as f64;
            sum += p;
            assert!((h as f64 / n as f64 - p).abs() <= 2.0 / n as f64 + 1e-7 * p, "{j}: {h} vs {p}");
            if w[j] == 0.0 {
                assert_eq!(h, 0);
            }
        }
        assert!((sum - 1.0).abs() < 1e-5);
    }

    #[test]
    fn random_draws_follow_the_pdf_and_values_track_the_weights() {
        let w: Vec<f32> = (0..1000).map(|j| 1.0 + (j as f32 * 0.37).sin().abs() * 1e3).collect();
        let d = Quantised::new(&w).unwrap();
        let mut rng = Rng::new(4);
        let mut hits = vec![0u32; w.len()];
        let n = 2_000_000;
        for _ in 0..n {
            hits[d.sample(rng.next_u64())] += 1;
        }
        let chi2: f64 = hits
            .iter()
            .enumerate()
            .map(|(j, &h)| {
                let e = d.pdf(j) as f64 * n as f64;
                (h as f64 - e).powi(2) / e
            })
            .sum();
        // 999 degrees of freedom: mean 999, sd 45.
        assert!(chi2 < 999.0 + 5.0 * 45.0, "chi2 {chi2}");
        for (j, &x) in w.iter().enumerate() {
            assert!((d.value(j) / x - 1.0).abs() < 0.033, "{j}");
        }
        assert!(d.bytes() <= Quantised::bytes_for(1000));
    }

    #[test]
    fn the_blockwise_difference_sum_matches_the_plain_sum() {
        let mut rng = Rng::new(8);
        // Runs of zeros as sorted VPLs give (whole blocks and partial ones), and a partial last block.
        let w = |rng: &mut Rng| -> Vec<f32> {
            (0..1000).map(|j| if (j / 150) % 2 == 0 { 0.0 } else { rng.uniform() * 10.0 }).collect()
        };
        let (a, b) = (Quantised::new(&w(&mut rng)).unwrap(), Quantised::new(&w(&mut rng)).unwrap());
        let plain: f64 = (0..a.len()).map(|j| (a.value(j) as f64 - b.value(j) as f64).abs()).sum();
        assert!((a.abs_diff_sum(&b) as f64 / plain - 1.0).abs() < 1e-5, "{} vs {plain}", a.abs_diff_sum(&b));
        let total: f64 = (0..a.len()).map(|j| a.value(j) as f64).sum();
        assert!((a.value_sum() as f64 / total - 1.0).abs() < 1e-5);
        assert_eq!(a.abs_diff_sum(&a), 0.0);
    }

    #[test]
    fn all_zero_has_no_distribution_and_a_single_item_always_wins() {
        assert!(Quantised::new(&[0.0, -1.0, f32::NAN]).is_none());
        let d = Quantised::new(&[0.0, 0.0, 5.0, 0.0]).unwrap();
        for r in [0, 1, u64::MAX / 2, u64::MAX] {
            assert_eq!(d.sample(r), 2);
        }
        assert_eq!(d.pdf(2), 1.0);
    }
}
