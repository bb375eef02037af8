//! STAGE 4 (shared by SD and VGC): from clusters to cache sites — fitting the cluster count to the budget
//! exactly, choosing one representative per cluster (a random member for SD, Eq. 2 for VGC) and packing the
//! result into [`Clusters`].
//!
//! Depends on `points`, `split` and `sampling`; knows nothing of how the clusters were found.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::ops::Range;

use glam::{DVec3, Vec3A};
use rayon::prelude::*;

use super::points::Pt;
use super::split::split_with;
use super::{Clusters, SplitRule};
use crate::gbuffer::PixelId;
use crate::sampling::Rng;

/// How a cluster's cache is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Representative {
    /// A uniformly random member (SD [P §1; LS `group.seed`]).
    Random,
    /// The member closest to the jittered mean by Eq. 2 (VGC [P §3.1]).
    Eq2 {
        /// λ of Eq. 2.
        lambda: f32,
        /// Total jitter width as a fraction of the cluster's extent per axis (CHOICE A6: 0.2).
        jitter: f32,
    },
}

/// Picks the representative of one cluster (`pts` non-empty) with the cluster's own random stream.
pub(crate) fn representative(pts: &[Pt], how: Representative, rng: &mut Rng) -> PixelId {
    match how {
        Representative::Random => pts[rng.below(pts.len() as u32) as usize].id,
        Representative::Eq2 { lambda, jitter } => eq2_member(pts, lambda, jitter, rng),
    }
}

/// Eq. 2: p_avg = mean position + jitter (u − ½)·jitter·extent per axis, n_avg = normalised mean normal;
/// the member minimising ‖p_s − p_avg‖ + λ·sqrt(max(0, 1 − n_s·n_avg)), ties to the smaller pixel id.
pub(crate) fn eq2_member(pts: &[Pt], lambda: f32, jitter: f32, rng: &mut Rng) -> PixelId {
    let (mut sp, mut sn) = (DVec3::ZERO, DVec3::ZERO);
    let mut lo = Vec3A::splat(f32::INFINITY);
    let mut hi = Vec3A::splat(f32::NEG_INFINITY);
    for q in pts {
        sp += DVec3::from(q.p.map(f64::from));
        sn += DVec3::from(q.n.map(f64::from));
        lo = lo.min(q.pos());
        hi = hi.max(q.pos());
    }
    let extent = hi - lo;
    let u = Vec3A::new(rng.uniform(), rng.uniform(), rng.uniform());
    let jitter = if jitter.is_finite() { jitter.max(0.0) } else { 0.0 };
    let p_avg = Vec3A::from((sp / pts.len() as f64).as_vec3()) + (u - 0.5) * jitter * extent;
    let n_avg: Vec3A = sn.normalize_or_zero().as_vec3().into();
    let cost = |q: &Pt| (q.pos() - p_avg).length() + lambda * (1.0 - q.normal().dot(n_avg)).max(0.0).sqrt();
    let mut best = (f32::INFINITY, PixelId::MAX);
    for q in pts {
        let c = cost(q);
        if c < best.0 || (c == best.0 && q.id < best.1) || best.1 == PixelId::MAX {
            best = (c, q.id);
        }
    }
    best.1
}

/// Makes the cluster list exactly `budget` long (`budget ≤ pts.len()`, clusters partition `pts`).
///
/// CHOICE (beyond ALGORITHMS.md, which lets stage 2 absorb a miss): the first stage's count is exact.
/// Surplus clusters: the smallest are dropped (their points stay uncovered) — they matter least and VGC's
/// point is to avoid small clusters. Missing clusters: the largest cluster is split once more with the
/// strategy's own rule, repeatedly. Returns how many were dropped (negative) or added (positive).
pub(crate) fn fit_to_budget(pts: &mut [Pt], clusters: &mut Vec<Range<u32>>, budget: usize, rule: SplitRule) -> i64 {
    let c = clusters.len();
    if c > budget {
        let mut order: Vec<usize> = (0..c).collect();
        // Smallest first; among equals the later cluster goes first.
        order.sort_unstable_by_key(|&i| (clusters[i].len(), Reverse(i)));
        let mut drop = vec![false; c];
        order.iter().take(c - budget).for_each(|&i| drop[i] = true);
        let mut i = 0;
        clusters.retain(|_| {
            i += 1;
            !drop[i - 1]
        });
        return -((c - budget) as i64);
    }
    let mut heap: BinaryHeap<(usize, Reverse<usize>)> =
        clusters.iter().enumerate().map(|(i, r)| (r.len(), Reverse(i))).collect();
    while clusters.len() < budget {
        let Some((len, Reverse(i))) = heap.pop() else { break };
        if len < 2 {
            break;
        }
        let r = clusters[i].clone();
        let Some(m) = split_with(&mut pts[r.start as usize..r.end as usize], rule) else { continue };
        let mid = r.start + m as u32;
        clusters[i] = r.start..mid;
        clusters.push(mid..r.end);
        heap.push((m, Reverse(i)));
        heap.push((r.end as usize - mid as usize, Reverse(clusters.len() - 1)));
    }
    (clusters.len() - c) as i64
}

/// One representative per cluster (in parallel, cluster `i` with stream (seed, `stage`, i)), and the
/// clusters packed with their members in cluster order.
pub(crate) fn assemble(
    pts: &[Pt],
    clusters: &[Range<u32>],
    how: Representative,
    rule: SplitRule,
    seed: u64,
    stage: u64,
) -> (Vec<PixelId>, Clusters) {
    let sites: Vec<PixelId> = clusters
        .par_iter()
        .enumerate()
        .map(|(i, r)| {
            let mut rng = Rng::keyed(seed, stage, i as u64);
            representative(&pts[r.start as usize..r.end as usize], how, &mut rng)
        })
        .collect();
    let mut members = Vec::with_capacity(clusters.iter().map(|r| r.len()).sum());
    let mut ranges = Vec::with_capacity(clusters.len());
    for r in clusters {
        let start = members.len() as u32;
        members.extend(pts[r.start as usize..r.end as usize].iter().map(|q| q.id));
        ranges.push(start..members.len() as u32);
    }
    (sites, Clusters { members, ranges, rule: Some(rule) })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane(n: u32) -> Vec<Pt> {
        (0..n)
            .map(|i| Pt { p: [(i % 10) as f32, (i / 10) as f32, 0.0], n: [0.0, 0.0, 1.0], depth: 1.0, id: i })
            .collect()
    }

    #[test]
    fn eq2_without_jitter_picks_the_member_nearest_the_centroid() {
        let pts = plane(100);
        let mut rng = Rng::keyed(1, 2, 3);
        // Centroid (4.5, 4.5): four members tie at equal distance; the smallest id wins.
        assert_eq!(eq2_member(&pts, 0.5, 0.0, &mut rng), 44);
        let shifted: Vec<Pt> = pts.iter().filter(|q| q.p[0] < 9.0).copied().collect();
        // Centroid (4, 4.5): members (4,4) = 44 and (4,5) = 54 tie.
        assert_eq!(eq2_member(&shifted, 0.5, 0.0, &mut rng), 44);
    }

    #[test]
    fn representatives_are_members() {
        let pts = plane(100);
        for seed in 0..50 {
            let mut rng = Rng::keyed(seed, 0, 0);
            let id = representative(&pts[10..30], Representative::Eq2 { lambda: 0.5, jitter: 0.2 }, &mut rng);
            assert!((10..30).contains(&id));
            let id = representative(&pts[10..30], Representative::Random, &mut rng);
            assert!((10..30).contains(&id));
        }
    }

    #[test]
    fn budget_fit_drops_the_smallest_and_splits_the_largest() {
        let mut pts = plane(100);
        let mut clusters = vec![0..50, 50..52, 52..53, 53..100];
        assert_eq!(fit_to_budget(&mut pts, &mut clusters, 3, SplitRule::ViewGuided), -1);
        assert_eq!(clusters, vec![0..50, 50..52, 53..100]);
        assert_eq!(fit_to_budget(&mut pts, &mut clusters, 6, SplitRule::ViewGuided), 3);
        assert_eq!(clusters.len(), 6);
        assert!(clusters.iter().all(|r| !r.is_empty()));
        assert_eq!(clusters.iter().map(|r| r.len()).sum::<usize>(), 99);
    }
}
