//! STAGE 4 (shared by SD and VGC): the budget search — bisection of a threshold on a log scale so that a
//! non-increasing cluster count lands on the budget (ALGORITHMS.md §4.2 "Budget", §4.4 "binary search for
//! σ_s", ambiguity A23).
//!
//! Depends on nothing; the count is a closure.

/// Iteration cap of the bisection (ALGORITHMS.md: ≈ 40).
pub(crate) const MAX_ITERATIONS: u32 = 40;
/// Relative tolerance on the count: stop when |count − target| ≤ 0.2 % of the target.
pub(crate) const TOLERANCE: f64 = 0.002;

/// The outcome of a search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Found {
    /// The threshold with the best count.
    pub t: f32,
    /// Its count.
    pub count: usize,
    /// Counts evaluated.
    pub iterations: u32,
}

/// Searches t in [lo, hi] for `count(t)` (non-increasing in t) closest to `target`; ties go to a count
/// ≤ target, then to the larger t. `count_hi = count(hi)` is passed in (callers check it first; at or above
/// the target it is the answer). Stops at
/// the tolerance, after [`MAX_ITERATIONS`] evaluations, or when the bracket cannot shrink.
pub(crate) fn search_log(
    lo: f32,
    hi: f32,
    count_hi: usize,
    target: usize,
    mut count: impl FnMut(f32) -> usize,
) -> Found {
    let tol = (TOLERANCE * target as f64).floor() as usize;
    let mut best = Found { t: hi, count: count_hi, iterations: 1 };
    let better = |c: usize, b: &Found| {
        let (dc, db) = (c.abs_diff(target), b.count.abs_diff(target));
        dc < db || (dc == db && c <= target && b.count > target)
    };
    if count_hi >= target || !(lo > 0.0 && lo < hi) {
        return best;
    }
    let c_lo = count(lo);
    let mut iterations = 2;
    if better(c_lo, &best) {
        best = Found { t: lo, count: c_lo, iterations };
    }
    let (mut lo, mut hi) = (lo as f64, hi as f64);
    if c_lo <= target {
        // Even the smallest threshold gives too few clusters: saturated.
        best.iterations = iterations;
        return best;
    }
    while iterations < MAX_ITERATIONS && best.count.abs_diff(target) > tol {
        let mid = (lo * hi).sqrt();
        let mid32 = mid as f32;
        if !(mid32 > lo as f32 && mid32 < hi as f32) {
            break;
        }
        let c = count(mid32);
        iterations += 1;
        if better(c, &best) {
            best = Found { t: mid32, count: c, iterations };
        }
        if c > target { lo = mid } else { hi = mid }
    }
    best.iterations = iterations;
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_a_smooth_target_within_tolerance() {
        // count = 1e6 / t², a smooth stand-in for a cluster count.
        let f = |t: f32| (1e6 / (t as f64 * t as f64)).round() as usize;
        let found = search_log(1e-3, 1e3, f(1e3), 120_000, f);
        assert!(found.count.abs_diff(120_000) <= 240, "{found:?}");
        assert_eq!(f(found.t), found.count);
    }

    #[test]
    fn saturation_and_a_step_function() {
        let found = search_log(1.0, 10.0, 5, 100, |_| 50);
        assert_eq!(found.count, 50);
        // A step function jumping over the target: the closer side wins, ties to ≤ target.
        let step = |t: f32| if t < 3.0 { 110 } else { 90 };
        let found = search_log(1.0, 10.0, 90, 100, step);
        assert_eq!(found.count, 90);
        let step = |t: f32| if t < 3.0 { 101 } else { 90 };
        assert_eq!(search_log(1.0, 10.0, 90, 100, step).count, 101);
    }
}
