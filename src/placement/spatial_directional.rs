//! STAGE 4, first stage **SD**: the spatial-directional 6-D BVH of LightSlice as the paper uses it
//! (ALGORITHMS.md §4.2, ambiguity A19): shading points become q = (p, s·n), a node splits at the centre of
//! its longest 6-D axis, and stops when its largest 6-D extent ≤ T or it holds fewer than S_min points. T is
//! found by a log-scale search so that the leaf count is closest to the budget; each leaf's cache is a
//! uniformly random member.
//!
//! Depends on `gbuffer`, the shared placement helpers and `sampling`; never on `render`, `scene` or `cache`.

use super::budget::{self, Prelude};
use super::cluster::{self, Representative};
use super::hierarchy::{Hierarchy, NodeRule};
use super::points::{self, Pt};
use super::search::search_log;
use super::split::{sd_bounds, sd_extent, split_sd};
use super::{InitialPlacement, PlacementInfo, PlacementParams, SplitRule, Stage1};
use crate::error::Result;
use crate::gbuffer::GBuffer;

/// Stream tag of the representatives.
const STAGE_REP: u64 = 0x5344_0001;

/// SD — spatial-directional clustering (LightSlice's 6-D BVH with a threshold and a minimum size).
///
/// | option | type | default | meaning |
/// |---|---|---|---|
/// | `PlacementParams::sd_min_size` | usize | 10 | S_min: a node with fewer points is a leaf (Fig. 1 shows 10 and 50) |
///
/// The normal scale s is the mean of the three extents of the shading points' box / 8 (\[LS\]); the threshold T
/// is searched in [1e-6·L, 4·L] on a log scale (reported in `PlacementInfo::sd_threshold`). When S_min makes
/// the count saturate below the budget, the largest leaves are split further to meet it (with a note).
/// Forms clusters with [`SplitRule::SpatialDirectional`].
#[derive(Clone, Copy, Debug, Default)]
pub struct SpatialDirectional;

/// SD's node rule: key = largest 6-D extent; children unless fewer than S_min (or 2) points or all equal.
struct SdRule {
    s: f32,
    min_size: usize,
}

impl NodeRule for SdRule {
    fn process(&self, pts: &mut [Pt]) -> (f32, f32, Option<usize>) {
        let (lo, hi) = sd_bounds(pts, self.s);
        let (extent, _) = sd_extent(&lo, &hi);
        let split = if pts.len() >= self.min_size && extent > 0.0 { split_sd(pts, self.s, &lo, &hi) } else { None };
        (extent, 0.0, split)
    }
}

/// The normal scale s of [LS] `_GroupGatherPoints`: mean extent of the points' box / 8.
fn normal_scale(pts: &[Pt]) -> f32 {
    let (lo, hi, _) = super::split::spatial_stats(pts);
    let s = (hi - lo).element_sum() / 3.0 / 8.0;
    if s.is_finite() { s } else { 0.0 }
}

impl InitialPlacement for SpatialDirectional {
    fn place(&self, g: &GBuffer, budget: usize, params: &PlacementParams, seed: u64) -> Result<Stage1> {
        budget::check_gbuffer(g)?;
        let rule_of = |pts: &[Pt]| SplitRule::SpatialDirectional { normal_scale: normal_scale(pts) };
        let (mut pts, mut notes) = match budget::prelude(g, budget, params.meters_per_unit, Some(&rule_of)) {
            Prelude::Done(s) => return Ok(s),
            Prelude::Go(pts, notes) => (pts, notes),
        };
        let s = normal_scale(&pts);
        let rule = SplitRule::SpatialDirectional { normal_scale: s };
        let min_size = params.sd_min_size.max(2);
        let h = Hierarchy::build(&mut pts, &SdRule { s, min_size });
        let l = points::length_scale(g, &pts);
        let count = |t: f32| h.cut_count(t, &|_| 1);
        let (lo, hi) = (1e-6 * l, 4.0 * l);
        let found = search_log(lo, hi, count(hi), budget, count);
        let mut clusters: Vec<_> =
            h.cut(found.t).into_iter().map(|i| h.nodes[i]).map(|n| n.start..n.start + n.len).collect();
        let adjusted = cluster::fit_to_budget(&mut pts, &mut clusters, budget, rule);
        if adjusted > 0 && found.t <= lo {
            notes.push(format!(
                "SD saturates at {} clusters with S_min = {}: {adjusted} more caches come from splitting the largest clusters",
                found.count, params.sd_min_size
            ));
        }
        let (sites, clusters) = cluster::assemble(&pts, &clusters, Representative::Random, rule, seed, STAGE_REP);
        let info = PlacementInfo {
            sd_threshold: Some(found.t),
            search_iterations: found.iterations,
            clusters_found: found.count,
            notes,
            ..Default::default()
        };
        Ok(Stage1 { sites, clusters: Some(clusters), info })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::placement::test_scenes as ts;

    #[test]
    fn sd_meets_the_contract() {
        ts::check_initial(&SpatialDirectional, true);
    }

    #[test]
    fn sd_search_lands_near_the_budget_and_reports_t() {
        let g = ts::sphere_on_plane(160, 120);
        let p = PlacementParams { sd_min_size: 2, ..Default::default() };
        let s = SpatialDirectional.place(&g, 800, &p, 1).unwrap();
        assert_eq!(s.sites.len(), 800);
        assert!(s.info.sd_threshold.is_some_and(|t| t > 0.0));
        assert!(s.info.clusters_found.abs_diff(800) <= 80, "{:?}", s.info);
        ts::check_clusters(&g, &s);
    }

    #[test]
    fn a_large_minimum_size_saturates_and_is_topped_up() {
        let g = ts::sphere_on_plane(64, 48);
        let p = PlacementParams { sd_min_size: 200, ..Default::default() };
        let s = SpatialDirectional.place(&g, 500, &p, 1).unwrap();
        assert_eq!(s.sites.len(), 500);
        assert!(s.info.clusters_found < 500);
        assert!(s.info.notes.iter().any(|n| n.contains("saturates")), "{:?}", s.info.notes);
    }
}
