//! STAGE 4, first stage **VGC**: view-guided clustering, the first stage of the paper's method
//! (paper §3.1, Eq. 1–2; ALGORITHMS.md §4.4). A spatial pass splits nodes whose longest world-space side
//! exceeds σ_s′, then an angular pass splits every spatial leaf whose normal spread exceeds σ_a′, both
//! thresholds grown with depth by Eq. 1 (corrected sign, ambiguity A1). σ_s is searched on a log scale so
//! that the cluster count hits the budget; each cluster's cache is the member nearest its jittered mean by
//! Eq. 2.
//!
//! Depends on `gbuffer`, the shared placement helpers and `sampling`; never on `render`, `scene` or `cache`.

use std::ops::Range;
use std::sync::atomic::{AtomicU32, Ordering};

use rayon::prelude::*;

use super::budget::{self, Prelude};
use super::cluster::{self, Representative};
use super::hierarchy::{Hierarchy, Node, NodeRule};
use super::points::{self, DepthScale, Pt};
use super::search::search_log;
use super::split::{Angular, cone_spread_bound, node_stats, split_spatial};
use super::{AngularMode, InitialPlacement, PlacementInfo, PlacementParams, SplitRule, Stage1};
use crate::error::{Error, Result};
use crate::gbuffer::GBuffer;

/// Stream tag of the representative jitter.
const STAGE_REP: u64 = 0x5647_0001;
/// Lower end of the σ_s search, relative to L (ALGORITHMS.md §4.4: [1e-5·L, L]).
const SIGMA_S_MIN: f32 = 1e-5;
/// Upper end of an automatically raised σ_a, degrees: a normal spread never exceeds it.
const MAX_SIGMA_A: f32 = 360.0;

/// VGC — view-guided clustering.
///
/// | option | type | default | meaning |
/// |---|---|---|---|
/// | `two_stage` | bool | false | the budget is stage 1's share of a two-stage total: σ_a is chosen for N1/(1 − R) caches |
/// | `PlacementParams::sigma_a_deg` | `Option<f32>` | 15° at 120K … 25° at 25K caches per 1920×1080 pixels | σ_a, the angular threshold |
/// | `PlacementParams::gamma` | f32 | 0.2 | Γ of Eq. 1, per metre |
/// | `PlacementParams::meters_per_unit` | f32 | 1 | scene units → metres for depths |
/// | `PlacementParams::angular` | AngularMode | Cone | how normal spread is measured and split (A4) |
/// | `PlacementParams::lambda` | `Option<f32>` | 0.5/L | λ of Eq. 2 |
/// | `PlacementParams::jitter` | f32 | 0.2 | jitter of the mean, fraction of the cluster extent (A6) |
///
/// σ_s is searched in [1e-5·L, L] until the count is within 0.2 % of the budget (or 40 steps); the final
/// count is then made exact (see `cluster::fit_to_budget`). If a σ_a the user set yields more clusters than
/// the budget on its own (even with σ_s = L), placement fails with an error naming σ_a and the budget; an
/// automatic σ_a is raised instead, with a note. Forms clusters with
/// [`SplitRule::ViewGuided`].
#[derive(Clone, Copy, Debug, Default)]
pub struct ViewGuided {
    /// The budget is the first-stage share of a two-stage total (VGC+DGS, VGC+AS).
    pub two_stage: bool,
}

/// The spatial pass's node rule: key = longest side / Eq. 1 factor of the node's mean depth, so the node
/// stops when longest side ≤ σ_s′ ⇔ key ≤ σ_s. The auxiliary value is a bound of the node's cone spread
/// divided by the same factor (cone mode; +∞ in the literal mode): when it is ≤ σ_a the node is one
/// angular cluster without looking at its points again.
struct SpatialRule {
    scale: DepthScale,
    cone: bool,
}

impl NodeRule for SpatialRule {
    fn process(&self, pts: &mut [Pt]) -> (f32, f32, Option<usize>) {
        let st = node_stats(pts);
        let longest = (st.hi - st.lo).max_element();
        let f = self.scale.factor(st.depth_sum / pts.len() as f32);
        let flat = if self.cone { cone_spread_bound(st.n_lo, st.n_hi) / f } else { f32::INFINITY };
        let split = if pts.len() > 1 && longest > 0.0 { split_spatial(pts, st.lo, st.hi) } else { None };
        (longest / f, flat, split)
    }
}

/// Splits a spatial leaf (at `base` in the whole array) into angular clusters, left to right, calling
/// `emit` with each cluster's absolute range. Explicit stack: no recursion depth limit.
fn angular_pass(pts: &mut [Pt], base: u32, angular: &Angular, mut emit: impl FnMut(Range<u32>)) {
    let mut stack = vec![(0usize, pts.len())];
    while let Some((a, b)) = stack.pop() {
        let node = &mut pts[a..b];
        match angular.needs_split(node).then(|| angular.split(node)).flatten() {
            Some(m) => {
                stack.push((a + m, b));
                stack.push((a, a + m));
            }
            None => emit(base + a as u32..base + b as u32),
        }
    }
}

/// Number of angular clusters of a spatial leaf, without changing `pts` (a copy is split when needed).
fn angular_count(pts: &[Pt], angular: &Angular) -> usize {
    if !angular.needs_split(pts) {
        return 1;
    }
    let mut copy = pts.to_vec();
    let mut n = 0;
    angular_pass(&mut copy, 0, angular, |_| n += 1);
    n
}

impl ViewGuided {
    /// σ_a for this budget over `pixels` pixels: the paper's rule applies to the total cache count.
    fn sigma_a(&self, budget: usize, params: &PlacementParams, pixels: usize) -> f32 {
        let r = params.ratio;
        let total = if self.two_stage && r.is_finite() && (0.0..1.0).contains(&r) {
            (budget as f64 / (1.0 - r as f64)).round() as usize
        } else {
            budget
        };
        params.sigma_a_for(total, pixels)
    }
}

impl InitialPlacement for ViewGuided {
    fn place(&self, g: &GBuffer, budget: usize, params: &PlacementParams, seed: u64) -> Result<Stage1> {
        budget::check_gbuffer(g)?;
        let rule = SplitRule::ViewGuided;
        let (mut pts, mut notes) = match budget::prelude(g, budget, params.meters_per_unit, Some(&|_: &[Pt]| rule)) {
            Prelude::Done(s) => return Ok(s),
            Prelude::Go(pts, notes) => (pts, notes),
        };
        let mut sigma_a = self.sigma_a(budget, params, g.width * g.height);
        if !(sigma_a.is_finite() && sigma_a >= 0.0) {
            return Err(Error::usage(format!("VGC: σ_a must be a non-negative angle in degrees, got {sigma_a}")));
        }
        let scale = DepthScale::of(&pts, params.gamma);
        let spherical = params.angular == AngularMode::SphericalAngles;
        let h = Hierarchy::build(&mut pts, &SpatialRule { scale, cone: !spherical });
        let l = points::length_scale(g, &pts);
        let auto = params.sigma_a_deg.is_none();
        // The spatial hierarchy does not depend on σ_a; only the angular counts are redone when an
        // automatic σ_a has to be raised.
        let found = loop {
            let angular = Angular { spherical, sigma_a, scale };
            // Angular cluster count per spatial node, computed at most once (0 = not yet known).
            let memo: Vec<AtomicU32> = (0..h.nodes.len()).map(|_| AtomicU32::new(0)).collect();
            let weight = |i: usize| {
                if h.nodes[i].aux <= sigma_a {
                    return 1;
                }
                let known = memo[i].load(Ordering::Relaxed);
                if known > 0 {
                    return known as usize;
                }
                let nd = h.nodes[i];
                let c = angular_count(&pts[nd.start as usize..(nd.start + nd.len) as usize], &angular);
                memo[i].store(c.min(u32::MAX as usize) as u32, Ordering::Relaxed);
                c
            };
            let count = |sigma_s: f32| h.cut_count(sigma_s, &weight);
            let count_hi = count(l);
            if count_hi > budget {
                // CHOICE (ALGORITHMS.md §4.4 only covers a σ_a the user chose): the paper's rule of thumb
                // is for budgets of 25K–120K; for far smaller budgets the automatic σ_a is raised (×1.5,
                // up to 360°, where no node is split by angle) with a note, instead of failing on a value
                // the user never gave. A σ_a the user set is kept, and too small a one is an error.
                if auto && sigma_a < MAX_SIGMA_A {
                    sigma_a = (sigma_a * 1.5).clamp(1.0, MAX_SIGMA_A);
                    continue;
                }
                if !auto {
                    return Err(Error::usage(format!(
                        "VGC: σ_a = {sigma_a}° alone gives {count_hi} clusters (with σ_s = L = {l}), more than the \
                         budget of {budget} caches; raise σ_a or the budget"
                    )));
                }
            }
            break search_log(SIGMA_S_MIN * l, l, count_hi, budget, count);
        };
        let chosen = self.sigma_a(budget, params, g.width * g.height);
        if sigma_a != chosen {
            notes.push(format!(
                "VGC: the automatic σ_a = {chosen}° gives more clusters than the budget of {budget} on its own; \
                 raised to {sigma_a}°"
            ));
        }
        let angular = Angular { spherical, sigma_a, scale };
        let mut clusters = final_clusters(&mut pts, &h, found.t, &angular);
        cluster::fit_to_budget(&mut pts, &mut clusters, budget, rule);
        let how = Representative::Eq2 { lambda: params.lambda_for(l), jitter: params.jitter };
        let (sites, clusters) = cluster::assemble(&pts, &clusters, how, rule, seed, STAGE_REP);
        let info = PlacementInfo {
            sigma_s: Some(found.t),
            sigma_a_deg: Some(sigma_a),
            search_iterations: found.iterations,
            clusters_found: found.count,
            notes,
            ..Default::default()
        };
        Ok(Stage1 { sites, clusters: Some(clusters), info })
    }
}

/// The clusters for σ_s: the spatial cut, then the angular pass inside every spatial leaf (in parallel over
/// leaves, results in leaf order).
fn final_clusters(pts: &mut [Pt], h: &Hierarchy, sigma_s: f32, angular: &Angular) -> Vec<Range<u32>> {
    let leaves = h.cut(sigma_s);
    let mut chunks: Vec<(&Node, &mut [Pt])> = Vec::with_capacity(leaves.len());
    let mut rest = pts;
    for &i in &leaves {
        let (a, b) = rest.split_at_mut(h.nodes[i].len as usize);
        chunks.push((&h.nodes[i], a));
        rest = b;
    }
    let per_leaf: Vec<Vec<Range<u32>>> = chunks
        .into_par_iter()
        .map(|(node, chunk)| {
            let mut out = Vec::new();
            if node.aux <= angular.sigma_a {
                out.push(node.start..node.start + node.len);
            } else {
                angular_pass(chunk, node.start, angular, |r| out.push(r));
            }
            out
        })
        .collect();
    per_leaf.into_iter().flatten().collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::placement::test_scenes as ts;

    #[test]
    fn vgc_meets_the_contract() {
        ts::check_initial(&ViewGuided::default(), true);
        ts::check_initial(&ViewGuided { two_stage: true }, true);
    }

    #[test]
    fn the_search_lands_within_0_2_percent_on_a_smooth_scene() {
        let g = ts::sphere_on_plane(320, 240);
        for budget in [500, 2000, 6000] {
            let s = ViewGuided::default().place(&g, budget, &PlacementParams::default(), 5).unwrap();
            assert_eq!(s.sites.len(), budget);
            let tol = (0.002 * budget as f64).ceil() as usize;
            assert!(s.info.clusters_found.abs_diff(budget) <= tol, "budget {budget}: {:?}", s.info);
            assert!(s.info.sigma_s.is_some_and(|x| x > 0.0));
            ts::check_clusters(&g, &s);
        }
    }

    #[test]
    fn cluster_count_does_not_grow_with_sigma_s() {
        let mut pts = points::collect(&ts::staircase(96, 64), 1.0);
        let scale = DepthScale::of(&pts, 0.2);
        let angular = Angular { spherical: false, sigma_a: 20.0, scale };
        let h = Hierarchy::build(&mut pts, &SpatialRule { scale, cone: true });
        let counts: Vec<usize> = (0..30)
            .map(|i| 20.0 * 0.7f32.powi(i))
            .map(|s| {
                h.cut_count(s, &|n: usize| {
                    let nd = h.nodes[n];
                    angular_count(&pts[nd.start as usize..(nd.start + nd.len) as usize], &angular)
                })
            })
            .collect();
        assert!(counts.windows(2).all(|w| w[0] <= w[1]), "{counts:?}");
    }

    #[test]
    fn both_angular_modes_work() {
        let g = ts::sphere_on_plane(96, 64);
        for angular in [AngularMode::Cone, AngularMode::SphericalAngles] {
            let p = PlacementParams { angular, ..Default::default() };
            let s = ViewGuided::default().place(&g, 300, &p, 1).unwrap();
            assert_eq!(s.sites.len(), 300);
            ts::check_clusters(&g, &s);
        }
    }

    #[test]
    fn too_small_an_angular_threshold_is_an_error_naming_it_and_the_budget() {
        let g = ts::sphere_on_plane(96, 64);
        let p = PlacementParams { sigma_a_deg: Some(1.0), ..Default::default() };
        let e = ViewGuided::default().place(&g, 50, &p, 1).unwrap_err().to_string();
        assert!(e.contains("σ_a = 1°") && e.contains("budget of 50"), "{e}");
        // A plane needs no angular split: one cache is fine.
        let one = ViewGuided::default().place(&ts::flat(96, 64), 1, &PlacementParams::default(), 1).unwrap();
        assert_eq!(one.sites.len(), 1);
    }

    #[test]
    fn an_automatic_sigma_a_is_raised_for_a_tiny_budget_with_a_note() {
        let g = ts::sphere_on_plane(96, 64);
        for budget in [1, 2, 5] {
            let s = ViewGuided::default().place(&g, budget, &PlacementParams::default(), 1).unwrap();
            assert_eq!(s.sites.len(), budget);
            assert!(s.info.sigma_a_deg.is_some_and(|a| a > 25.0), "{:?}", s.info);
            assert!(s.info.notes.iter().any(|n| n.contains("raised to")), "{:?}", s.info.notes);
        }
    }

    #[test]
    fn two_stage_sigma_a_uses_the_total_budget() {
        let p = PlacementParams::default();
        let n1 = (0.85f64 * 120_000.0).round() as usize;
        let px = (1920 * 1080) as usize;
        assert_eq!(ViewGuided { two_stage: true }.sigma_a(n1, &p, px), 15.0);
        assert!(ViewGuided { two_stage: false }.sigma_a(n1, &p, px) > 15.0);
        // The rule follows density: a ninth of the pixels at a ninth of the budget is the same σ_a.
        assert!((ViewGuided { two_stage: true }.sigma_a(n1 / 9, &p, 640 * 360) - 15.0).abs() < 1e-3);
        assert_eq!(p.sigma_a_for(40_000 / 9, 640 * 360), 25.0);
    }

    #[test]
    fn far_clusters_are_larger_than_near_ones() {
        // Eq. 1 grows the thresholds with depth: with a 10 m depth range (α = 3) distant clusters hold more
        // pixels than near ones would if the thresholds were flat.
        let g = ts::plane(160, 120);
        let with = ViewGuided::default().place(&g, 400, &PlacementParams::default(), 2).unwrap();
        let flat =
            ViewGuided::default().place(&g, 400, &PlacementParams { gamma: 0.0, ..Default::default() }, 2).unwrap();
        let far_share = |s: &Stage1| {
            let far = s.sites.iter().filter(|&&id| g.get(id).is_some_and(|sp| sp.depth > 6.0)).count();
            far as f64 / s.sites.len() as f64
        };
        assert!(far_share(&with) < far_share(&flat), "{} vs {}", far_share(&with), far_share(&flat));
    }
}
