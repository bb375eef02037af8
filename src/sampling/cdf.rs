//! A discrete distribution drawn by inverting its cumulative sum, in expected O(1) per draw: a guide table
//! (Chen and Asau's "indexed search") says where the answer for each of `n` equal slices of [0, total) starts,
//! and a short walk from there finds it. The index drawn is exactly the one a binary search of the
//! cumulative sums gives (`partition_point`), so a renderer that switches to it draws the same samples; the
//! walk fixes any slice boundary that floating-point rounding put one entry off.
//!
//! Depends on nothing else in the crate.

/// Cumulative weights (f64, summed in order) with a guide table for drawing.
#[derive(Clone, Debug, Default)]
pub struct Cdf {
    /// Σ weights[..=j].
    cum: Vec<f64>,
    /// Per slice k of [0, total): the first j with cum\[j\] > k·total/n (empty when the sums are not
    /// non-decreasing and finite: draws then binary-search).
    guide: Vec<u32>,
}

impl Cdf {
    /// The distribution of `weights` (each summed as f64, in order).
    pub fn new(weights: impl IntoIterator<Item = f32>) -> Self {
        let mut acc = 0.0f64;
        let cum: Vec<f64> = weights
            .into_iter()
            .map(|w| {
                acc += w as f64;
                acc
            })
            .collect();
        let ordered =
            cum.iter().all(|c| c.is_finite()) && cum.windows(2).all(|w| w[0] <= w[1]) && cum.first() >= Some(&0.0);
        let mut guide = Vec::new();
        if let (true, Some(&total)) = (ordered && cum.len() < u32::MAX as usize, cum.last()) {
            let n = cum.len();
            guide.reserve(n);
            let mut j = 0;
            for k in 0..n {
                let threshold = (k as f64 / n as f64) * total;
                while j < n && cum[j] <= threshold {
                    j += 1;
                }
                guide.push(j as u32);
            }
        }
        Cdf { cum, guide }
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.cum.len()
    }

    /// Whether there is no entry.
    pub fn is_empty(&self) -> bool {
        self.cum.is_empty()
    }

    /// The sum of the weights (`None` when empty).
    pub fn total(&self) -> Option<f64> {
        self.cum.last().copied()
    }

    /// Draws with `unit` in [0, 1): the index j with Σ w[..j] ≤ unit·total < Σ w[..=j] (the last index when
    /// rounding puts unit·total at the total) and its probability w_j / total; `None` when the total is not
    /// positive or the drawn weight is 0.
    pub fn sample(&self, unit: f64) -> Option<(usize, f64)> {
        let total = *self.cum.last()?;
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let target = unit * total;
        let n = self.cum.len();
        let j = if self.guide.len() == n {
            let k = ((unit * n as f64) as usize).min(n - 1);
            let mut j = self.guide[k] as usize;
            while j > 0 && self.cum[j - 1] > target {
                j -= 1;
            }
            while j < n && self.cum[j] <= target {
                j += 1;
            }
            j
        } else {
            self.cum.partition_point(|&c| c <= target)
        }
        .min(n - 1);
        let p = (self.cum[j] - if j == 0 { 0.0 } else { self.cum[j - 1] }) / total;
        (p > 0.0).then_some((j, p))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Rng, unit_f64};

    /// The binary search the guide table replaces.
    fn searched(weights: &[f32], unit: f64) -> Option<(usize, f64)> {
        let mut acc = 0.0f64;
        let cum: Vec<f64> = weights
            .iter()
            .map(|&w| {
                acc += w as f64;
                acc
            })
            .collect();
        let total = *cum.last()?;
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let target = unit * total;
        let j = cum.partition_point(|&c| c <= target).min(cum.len() - 1);
        let p = (cum[j] - if j == 0 { 0.0 } else { cum[j - 1] }) / total;
        (p > 0.0).then_some((j, p))
    }

    #[test]
    fn every_draw_is_the_binary_searchs() {
        let mut rng = Rng::new(0x6364_6621);
        for case in 0..40 {
            let n = 1 + (rng.next_u64() % 3000) as usize;
            // Skewed weights (a few huge, many tiny), runs of zeros, equal weights.
            let weights: Vec<f32> = (0..n)
                .map(|i| match case % 4 {
                    0 => unit_f64(rng.next_u64()) as f32,
                    1 => (unit_f64(rng.next_u64()) as f32).powi(12) * 1e6,
                    2 if i % 7 < 3 => 0.0,
                    2 => 1.0 + i as f32,
                    _ => 0.25,
                })
                .collect();
            let cdf = Cdf::new(weights.iter().copied());
            assert_eq!(cdf.len(), n);
            let edges = [0.0, 1.0 - f64::EPSILON / 2.0, 0.5];
            for d in 0..4000 {
                let unit = if d < edges.len() { edges[d] } else { unit_f64(rng.next_u64()) };
                assert_eq!(cdf.sample(unit), searched(&weights, unit), "case {case}, n {n}, unit {unit}");
            }
            // Every slice boundary, where rounding is closest.
            for k in 0..n {
                let unit = k as f64 / n as f64;
                assert_eq!(cdf.sample(unit), searched(&weights, unit), "case {case}, slice {k}");
            }
        }
    }

    #[test]
    fn degenerate_weights_draw_nothing_or_fall_back() {
        assert_eq!(Cdf::new([]).sample(0.5), None);
        assert_eq!(Cdf::new([0.0, 0.0]).sample(0.5), None);
        assert_eq!(Cdf::new([f32::NAN, 1.0]).sample(0.5), None);
        // A negative weight: no guide, the binary search's answer.
        let w = [1.0, -0.5, 2.0];
        assert_eq!(Cdf::new(w).sample(0.3), searched(&w, 0.3));
        assert_eq!(Cdf::new([3.0]).sample(0.9), Some((0, 1.0)));
    }
}
