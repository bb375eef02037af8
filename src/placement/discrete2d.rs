//! STAGE 4 (DGS): a piecewise-constant 2-D discrete distribution over pixels, sampled by a marginal row and
//! then a conditional column [P §3.2], with removal of a drawn pixel in O(W + H) so that draws are without
//! replacement (ALGORITHMS.md §4.5.5, ambiguity A12).
//!
//! Depends on nothing; cumulative sums are in f64 and rebuilt from the weights, so removals do not drift.

/// A W × H table of non-negative weights with per-row and marginal cumulative sums.
#[derive(Clone, Debug)]
pub(crate) struct Discrete2D {
    w: usize,
    h: usize,
    weights: Vec<f32>,
    /// Inclusive prefix sums within each row (row-major).
    row_cdf: Vec<f64>,
    /// Inclusive prefix sums of the row totals.
    marginal: Vec<f64>,
}

impl Discrete2D {
    /// A table over `weights` (row-major, `w·h` long); negative or non-finite weights count as 0.
    pub fn new(w: usize, h: usize, weights: &[f32]) -> Self {
        let weights: Vec<f32> =
            (0..w * h).map(|i| weights.get(i).copied().filter(|v| v.is_finite() && *v > 0.0).unwrap_or(0.0)).collect();
        let mut t = Discrete2D { w, h, weights, row_cdf: vec![0.0; w * h], marginal: vec![0.0; h] };
        for y in 0..h {
            t.rebuild_row(y);
        }
        t.rebuild_marginal(0);
        t
    }

    fn rebuild_row(&mut self, y: usize) {
        let mut acc = 0f64;
        for x in 0..self.w {
            acc += self.weights[y * self.w + x] as f64;
            self.row_cdf[y * self.w + x] = acc;
        }
    }

    fn row_total(&self, y: usize) -> f64 {
        if self.w == 0 { 0.0 } else { self.row_cdf[y * self.w + self.w - 1] }
    }

    fn rebuild_marginal(&mut self, from: usize) {
        let mut acc = if from == 0 { 0.0 } else { self.marginal[from - 1] };
        for y in from..self.h {
            acc += self.row_total(y);
            self.marginal[y] = acc;
        }
    }

    /// Σ of all weights.
    pub fn total(&self) -> f64 {
        self.marginal.last().copied().unwrap_or(0.0)
    }

    /// Draws a pixel (x, y) with probability weight / total from (u0, u1) ∈ [0, 1)²: a row by the
    /// marginal, then a column by the row's conditional. `None` when the total is 0.
    pub fn sample(&self, u0: f32, u1: f32) -> Option<(usize, usize)> {
        let total = self.total();
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let y = pick(&self.marginal, u0 as f64 * total)?;
        let row = &self.row_cdf[y * self.w..(y + 1) * self.w];
        let x = pick(row, u1 as f64 * self.row_total(y))?;
        Some((x, y))
    }

    /// Sets the weight of (x, y) to 0 and updates that row's sums and the marginal: O(W + H).
    pub fn remove(&mut self, x: usize, y: usize) {
        if x < self.w && y < self.h && self.weights[y * self.w + x] != 0.0 {
            self.weights[y * self.w + x] = 0.0;
            self.rebuild_row(y);
            self.rebuild_marginal(y);
        }
    }
}

/// The first index whose inclusive prefix sum exceeds `target` (so it has positive mass); when rounding puts
/// `target` at or past the end, the last index with positive mass.
fn pick(cdf: &[f64], target: f64) -> Option<usize> {
    let i = cdf.partition_point(|&c| c <= target);
    if i < cdf.len() {
        return Some(i);
    }
    let last = *cdf.last()?;
    // Last entry with positive mass: the first index reaching the final sum.
    let j = cdf.partition_point(|&c| c < last);
    (last > 0.0).then_some(j)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// A tiny map with zeros, small and large weights.
    const MAP: [f32; 12] = [0.0, 1.0, 2.0, 0.0, 0.5, 0.0, 3.0, 1.5, 0.0, 0.25, 0.0, 4.0];

    #[test]
    fn frequencies_follow_the_weights_with_replacement() {
        let t = Discrete2D::new(4, 3, &MAP);
        let total: f64 = MAP.iter().map(|&v| v as f64).sum();
        assert!((t.total() - total).abs() < 1e-9);
        let n = 400_000u32;
        let mut counts = [0u32; 12];
        let mut rng = Rng::keyed(0xd15c, 0, 0);
        for _ in 0..n {
            let (x, y) = t.sample(rng.uniform(), rng.uniform()).unwrap();
            counts[y * 4 + x] += 1;
        }
        // Each count is Binomial(n, p): |f − p| ≤ 5·sqrt(p(1 − p)/n) fails with probability < 6e-7 per cell
        // (normal approximation), so < 1e-5 for all 12 cells together; zero-weight cells must never appear.
        for (i, &c) in counts.iter().enumerate() {
            let p = MAP[i] as f64 / total;
            let f = c as f64 / n as f64;
            let tol = 5.0 * (p * (1.0 - p) / n as f64).sqrt();
            assert!((f - p).abs() <= tol, "cell {i}: {f} vs {p} ± {tol}");
            if p == 0.0 {
                assert_eq!(c, 0);
            }
        }
    }

    #[test]
    fn removal_draws_every_positive_pixel_once() {
        let mut t = Discrete2D::new(4, 3, &MAP);
        let mut rng = Rng::keyed(0xd15c, 1, 0);
        let mut seen = Vec::new();
        while let Some((x, y)) = t.sample(rng.uniform(), rng.uniform()) {
            assert!(!seen.contains(&(x, y)));
            seen.push((x, y));
            t.remove(x, y);
        }
        assert_eq!(seen.len(), MAP.iter().filter(|&&v| v > 0.0).count());
        assert_eq!(t.total(), 0.0);
        // Extreme draws stay on positive cells.
        let t = Discrete2D::new(4, 3, &MAP);
        assert_eq!(t.sample(0.0, 0.0), Some((1, 0)));
        assert_eq!(t.sample(0.999_999_9, 0.999_999_9), Some((3, 2)));
    }

    #[test]
    fn empty_and_degenerate_tables() {
        assert_eq!(Discrete2D::new(0, 0, &[]).sample(0.5, 0.5), None);
        assert_eq!(Discrete2D::new(2, 2, &[0.0, f32::NAN, -1.0, f32::INFINITY]).sample(0.5, 0.5), None);
    }
}
