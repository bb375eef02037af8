//! STAGE 5: the cache index — a kd-tree (kiddo) over cache positions and the paper's selection of the
//! caches that serve a shading point (ALGORITHMS.md §5, Eq. 5): N nearest by distance → normals within
//! θ_max → the M smallest Dist = ‖p_c − p_s‖ + λ·sqrt(1 − n_c·n_s), with a fallback to all N when the
//! normal filter leaves none; inverse-Dist weights for interpolation.
//!
//! Depends on nothing but glam and kiddo; used by placement (DGS, AS) and by the render driver alike. It
//! must not depend on the record type of any application, on `scene` or on `render`.

use std::num::NonZeroUsize;

use glam::Vec3A;
use kiddo::{ImmutableKdTree, SquaredEuclidean};

/// Parameters of the §5 selection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LookupParams {
    /// N: nearest candidates by Euclidean distance.
    pub candidates: usize,
    /// θ_max in degrees: the normal filter.
    pub theta_max_deg: f32,
    /// M: caches kept.
    pub keep: usize,
}

impl Default for LookupParams {
    fn default() -> Self {
        LookupParams { candidates: 20, theta_max_deg: 30.0, keep: 6 }
    }
}

/// One cache chosen for a shading point: its id (index into the points given to [`CacheIndex::new`]) and
/// its Eq. 5 distance Dist = ‖p_c − p_s‖ + λ·sqrt(max(0, 1 − n_c·n_s)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbour {
    /// The cache id.
    pub id: u32,
    /// Eq. 5 distance to the shading point.
    pub dist: f32,
}

/// Relative size of the exact-hit radius: a shading point closer than `EXACT_HIT · L` (Eq. 5 distance) to a
/// cache takes that cache's value alone (ALGORITHMS.md §5 step 6).
pub const EXACT_HIT: f32 = 1e-7;

/// One candidate of a group: position, distance to the group centre, id.
#[derive(Clone, Copy, Debug)]
struct Cand {
    p: Vec3A,
    dc: f32,
    id: u32,
}

/// Reusable buffers of [`CacheIndex::select_group_in`]; keep one per thread across a run of neighbouring
/// groups. It changes how fast selections are found, never what is selected.
#[derive(Debug, Default)]
pub struct GroupScratch {
    /// Shared candidates, by (distance to the centre, id).
    cand: Vec<Cand>,
    /// Per query: the N nearest as packed keys.
    ranked: Vec<u64>,
    /// Packed (distance to the centre, id) keys while gathering.
    keys: Vec<u64>,
    /// The N-th nearest distance of the last group that queried the tree: a group several times wider is
    /// halved before querying (it would almost surely fail the width test after paying for the query).
    last_spacing: Option<f32>,
    /// The selection handed to the callback.
    out: Vec<Neighbour>,
}

/// Packs a non-negative distance (or squared distance) and an id into one key ordered by (distance, id):
/// the bits of a non-negative finite f32 order like the float.
#[inline]
fn key(d: f32, id: u32) -> u64 {
    ((d.max(0.0).to_bits() as u64) << 32) | id as u64
}

/// The (distance, id) of a key.
#[inline]
fn unkey(k: u64) -> (f32, u32) {
    (f32::from_bits((k >> 32) as u32), k as u32)
}

/// Keeps the `k` smallest keys (steps 2–5 do not depend on their order). Short lists are sorted: for a
/// few dozen keys that beats a selection.
fn top_k(keys: &mut Vec<u64>, k: usize) {
    if keys.len() > k {
        if keys.len() <= 64 {
            keys.sort_unstable();
        } else if k > 0 {
            keys.select_nth_unstable(k - 1);
        }
    }
    keys.truncate(k);
}

/// Largest shared candidate list of [`CacheIndex::select_group`]; longer ones split the group.
const GROUP_CAP: usize = 192;

/// How much wider than the last group's spacing a group may be before it is halved unqueried.
const PRESPLIT: f32 = 2.0;

/// A kd-tree over cache positions with the §5 selection and Eq. 5 weights.
///
/// Caches whose position or normal is not finite, or whose normal has zero length, are left out of the
/// tree (they can never be selected); [`CacheIndex::skipped`] counts them. Normals are normalised on entry.
/// Every query is deterministic: ties in distance are broken by cache id, never by tree layout or thread.
pub struct CacheIndex {
    /// None when no cache is usable (kiddo needs at least one point).
    tree: Option<ImmutableKdTree<f32, 3>>,
    /// Tree item → cache id.
    ids: Vec<u32>,
    /// Position and unit normal of every cache, by cache id (skipped ones too, unused).
    points: Vec<(Vec3A, Vec3A)>,
    lookup: LookupParams,
    lambda: f32,
    cos_max: f32,
    /// The exact-hit radius EXACT_HIT · L.
    exact_radius: f32,
    skipped: usize,
}

impl std::fmt::Debug for CacheIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CacheIndex")
            .field("caches", &self.ids.len())
            .field("skipped", &self.skipped)
            .field("lookup", &self.lookup)
            .field("lambda", &self.lambda)
            .field("exact_radius", &self.exact_radius)
            .finish()
    }
}

/// Whether a cache or query point can take part in a lookup.
fn usable(p: Vec3A, n: Vec3A) -> bool {
    p.is_finite() && n.is_finite() && n.length_squared() > 0.0
}

impl CacheIndex {
    /// Builds the index over `points` (position, normal) — cache `i` is `points[i]` — with the selection
    /// `lookup` and the Eq. 5 weight `lambda` (0.5/L in the paper).
    ///
    /// The exact-hit radius is `EXACT_HIT` times the diagonal of the caches' bounding box; the driver can set
    /// it from the scene's length scale L with [`CacheIndex::with_scale`].
    pub fn new(points: &[(Vec3A, Vec3A)], lookup: LookupParams, lambda: f32) -> Self {
        let mut ids = Vec::with_capacity(points.len());
        let mut coords = Vec::with_capacity(points.len());
        let mut stored = Vec::with_capacity(points.len());
        let (mut lo, mut hi) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
        for (i, &(p, n)) in points.iter().enumerate() {
            if usable(p, n) && i <= u32::MAX as usize {
                ids.push(i as u32);
                coords.push(p.to_array());
                lo = lo.min(p);
                hi = hi.max(p);
                stored.push((p, n.normalize()));
            } else {
                stored.push((p, n));
            }
        }
        let skipped = points.len() - ids.len();
        // kiddo's immutable tree has soft buckets (VecOfArenas), so any number of coincident positions is
        // accepted; construction can only fail on item-index overflow, which `ids` rules out.
        let tree = if coords.is_empty() { None } else { ImmutableKdTree::<f32, 3>::new_from_slice(&coords).ok() };
        let diagonal = if ids.is_empty() { 0.0 } else { (hi - lo).length() };
        let lambda = if lambda.is_finite() { lambda.max(0.0) } else { 0.0 };
        let theta = lookup.theta_max_deg.to_radians();
        let cos_max = if theta.is_finite() { theta.cos() } else { 1.0 };
        CacheIndex { tree, ids, points: stored, lookup, lambda, cos_max, exact_radius: EXACT_HIT * diagonal, skipped }
    }

    /// Sets the exact-hit radius from the scene's length scale L (`EXACT_HIT · L`, ALGORITHMS.md §5 step 6).
    pub fn with_scale(mut self, l: f32) -> Self {
        if l.is_finite() && l > 0.0 {
            self.exact_radius = EXACT_HIT * l;
        }
        self
    }

    /// Number of caches in the tree (usable ones).
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// Whether no cache can be selected.
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// How many of the given caches were left out for a non-finite position or normal.
    pub fn skipped(&self) -> usize {
        self.skipped
    }

    /// The selection parameters.
    pub fn lookup(&self) -> &LookupParams {
        &self.lookup
    }

    /// The λ of Eq. 5.
    pub fn lambda(&self) -> f32 {
        self.lambda
    }

    /// Position and (normalised) normal of cache `id`, if it exists.
    pub fn point(&self, id: u32) -> Option<(Vec3A, Vec3A)> {
        self.points.get(id as usize).copied()
    }

    /// Distance from cache `id` to its `k`-th nearest other cache in the tree: the radius of the region it
    /// serves when shading points blend `k` caches. Infinite when the tree has fewer than `k` other caches or
    /// `id` is not in it.
    pub fn region_radius(&self, id: u32, k: usize) -> f32 {
        let (Some(tree), Some(&(p, _))) = (&self.tree, self.points.get(id as usize)) else { return f32::INFINITY };
        let Some(k1) = NonZeroUsize::new(k + 1).filter(|k1| k1.get() <= self.ids.len()) else {
            return f32::INFINITY;
        };
        if !p.is_finite() {
            return f32::INFINITY;
        }
        let found = tree.query(&p.to_array()).nearest_n::<SquaredEuclidean<f32>>(k1).execute();
        // The cache itself is among the k + 1 nearest (at distance 0, or tied with a coincident one).
        found.iter().map(|r| r.distance).fold(0.0f32, f32::max).sqrt()
    }

    /// Squared distance from cache `id` to `p` — the one distance every candidate ranking uses.
    #[inline]
    fn d2(&self, id: u32, p: Vec3A) -> f32 {
        (self.points[id as usize].0 - p).length_squared()
    }

    /// Selects the caches for shading point (p, n) into `out` (cleared first), sorted by Dist, then id —
    /// ALGORITHMS.md §5 steps 1–5:
    /// 1. the N nearest caches by Euclidean distance (ties at the N-th distance broken by id);
    /// 2. keep those with n_c·n_s ≥ cos θ_max;
    /// 3. Dist = ‖p_c − p_s‖ + λ·sqrt(max(0, 1 − n_c·n_s)) (Eq. 5);
    /// 4. keep the M smallest;
    /// 5. if step 2 kept none, use all N candidates in steps 3–4.
    ///
    /// A query with a non-finite position or normal selects nothing. `n` should be unit length. For many
    /// nearby queries (a tile, the samples of a pixel) [`CacheIndex::select_group`] gives the same answers
    /// several times faster.
    pub fn select(&self, p: Vec3A, n: Vec3A, out: &mut Vec<Neighbour>) {
        out.clear();
        let Some(tree) = &self.tree else { return };
        if !p.is_finite() || !n.is_finite() || self.lookup.keep == 0 || self.lookup.candidates == 0 {
            return;
        }
        let ranked = self.nearest(tree, p);
        self.finish(&ranked, n, &mut Vec::with_capacity(ranked.len()), out);
    }

    /// Selects for a group of shading points at once, calling `f(i, selection)` for each query in order;
    /// every selection equals what [`CacheIndex::select`] returns for that query. Meant for nearby points
    /// (a pixel tile, the sub-pixel samples of a pixel): the group shares two tree queries — the N nearest
    /// to its centre c (farthest at distance r) and then every cache within r + 2ρ of c, ρ the group's radius,
    /// which holds each member's N nearest by the triangle inequality — and ranks that list per query.
    /// Groups wider than r (depth edges) or with long lists are halved, down to single queries.
    pub fn select_group(&self, queries: &[(Vec3A, Vec3A)], f: impl FnMut(usize, &[Neighbour])) {
        self.select_group_in(queries, &mut GroupScratch::default(), f);
    }

    /// [`CacheIndex::select_group`] with buffers the caller keeps across a run of neighbouring groups (a
    /// row of tiles), which also lets each group skip tree queries that the last one shows are futile.
    pub fn select_group_in(
        &self,
        queries: &[(Vec3A, Vec3A)],
        scratch: &mut GroupScratch,
        mut f: impl FnMut(usize, &[Neighbour]),
    ) {
        let mut out = std::mem::take(&mut scratch.out);
        self.group(queries, 0, &mut out, scratch, &mut f);
        scratch.out = out;
    }

    fn group(
        &self,
        queries: &[(Vec3A, Vec3A)],
        base: usize,
        out: &mut Vec<Neighbour>,
        scratch: &mut GroupScratch,
        f: &mut impl FnMut(usize, &[Neighbour]),
    ) {
        let ok = |&(p, n): &(Vec3A, Vec3A)| p.is_finite() && n.is_finite();
        let centre = match &self.tree {
            Some(tree) if queries.len() > 1 && self.lookup.keep > 0 && self.lookup.candidates > 0 => {
                self.group_candidates(tree, queries.iter().filter(|q| ok(q)).map(|q| q.0), scratch)
            }
            _ => None,
        };
        if centre.is_none() && queries.len() > 1 {
            let (a, b) = queries.split_at(queries.len() / 2);
            self.group(a, base, out, scratch, f);
            self.group(b, base + a.len(), out, scratch, f);
            return;
        }
        let mut prev = None;
        for (i, &(p, n)) in queries.iter().enumerate() {
            match centre {
                Some(c) if ok(&(p, n)) => {
                    self.nearest_among(&scratch.cand, c, p, prev, &mut scratch.ranked);
                    prev = scratch.ranked.iter().max().map(|&k| (p, unkey(k).0.sqrt()));
                    self.finish(&scratch.ranked, n, &mut scratch.keys, out);
                }
                _ => self.select(p, n, out),
            }
            f(base + i, out);
        }
    }

    /// The canonical N nearest to `p` among a group's candidates (sorted by distance to `c`) into `ranked`
    /// as packed (d², id) keys. With e = ‖p − c‖ and r = the N-th smallest distance to `c`, the N nearest
    /// to `p` lie within r + e of `p`, and any such cache within r + 2e of `c`: only that prefix of the list
    /// is scanned and only caches within r + e are ranked (margins for rounding).
    fn nearest_among(&self, cand: &[Cand], c: Vec3A, p: Vec3A, prev: Option<(Vec3A, f32)>, ranked: &mut Vec<u64>) {
        ranked.clear();
        let k = self.lookup.candidates.min(cand.len());
        if k == 0 {
            return;
        }
        let e = (p - c).length();
        // Upper bounds of the N-th distance from p: via the centre, and via the previous query.
        let mut r = cand[k - 1].dc + e;
        if let Some((q, rq)) = prev {
            r = r.min(rq + (p - q).length());
        }
        let keep = r * (1.0 + 1e-5) + f32::MIN_POSITIVE;
        let (keep2, scan) = (keep * keep, (r + e) * (1.0 + 1e-5) + f32::MIN_POSITIVE);
        for cd in cand {
            if cd.dc > scan {
                break;
            }
            let d2 = (cd.p - p).length_squared();
            if d2 <= keep2 {
                ranked.push(key(d2, cd.id));
            }
        }
        top_k(ranked, k);
    }

    /// Candidate superset for a group of positions, sorted by (distance to the group centre, id), and that
    /// centre; `None` when the group is wider than its caches' spacing or the list would exceed [`GROUP_CAP`].
    fn group_candidates(
        &self,
        tree: &ImmutableKdTree<f32, 3>,
        ps: impl Iterator<Item = Vec3A> + Clone,
        scratch: &mut GroupScratch,
    ) -> Option<Vec3A> {
        let (keys, out) = (&mut scratch.keys, &mut scratch.cand);
        keys.clear();
        out.clear();
        let (lo, hi) = ps
            .clone()
            .fold((Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)), |(lo, hi), p| (lo.min(p), hi.max(p)));
        if !(lo.is_finite() && hi.is_finite()) {
            return None;
        }
        let c = 0.5 * (lo + hi);
        let k = self.lookup.candidates.min(self.ids.len());
        let by_centre = |id: u32| key(self.d2(id, c).sqrt(), id);
        if self.ids.len() <= GROUP_CAP.max(k) {
            keys.extend(self.ids.iter().map(|&id| by_centre(id)));
        } else {
            let rad = ps.map(|p| (p - c).length()).fold(0.0f32, f32::max);
            if scratch.last_spacing.is_some_and(|d| rad > PRESPLIT * d) {
                return None;
            }
            let near = tree.query(&c.to_array()).nearest_n::<SquaredEuclidean<f32>>(NonZeroUsize::new(k)?).execute();
            let d = near.iter().map(|r| self.d2(self.ids[r.item as usize], c).sqrt()).fold(0.0f32, f32::max);
            scratch.last_spacing = Some(d);
            // A group wider than its caches' spacing (a depth edge) would gather too many: split it.
            if rad > d {
                return None;
            }
            // Every member's N nearest lie within d + 2·rad of c (triangle inequality); margin for rounding.
            let r = (d + 2.0 * rad) * (1.0 + 1e-5) + f32::MIN_POSITIVE;
            let within = tree.query(&c.to_array()).within::<SquaredEuclidean<f32>>(r * r).unsorted().execute();
            if within.len() > GROUP_CAP {
                return None;
            }
            keys.extend(within.iter().map(|r| by_centre(self.ids[r.item as usize])));
        }
        keys.sort_unstable();
        out.extend(keys.iter().map(|&k| {
            let (dc, id) = unkey(k);
            Cand { p: self.points[id as usize].0, dc, id }
        }));
        Some(c)
    }

    /// Steps 2–5 on the N nearest (`ranked`: packed (d², id), any order), ordering through packed
    /// (Dist, id) keys in `keys` (scratch).
    fn finish(&self, ranked: &[u64], n: Vec3A, keys: &mut Vec<u64>, out: &mut Vec<Neighbour>) {
        out.clear();
        keys.clear();
        let dist = |d2: f32, dot: f32| d2.sqrt() + self.lambda * (1.0 - dot).max(0.0).sqrt();
        // Step 2 (normal filter); step 5 falls back to all N candidates when it keeps none.
        for &k in ranked {
            let (d2, id) = unkey(k);
            let dot = self.points[id as usize].1.dot(n);
            if dot >= self.cos_max {
                keys.push(key(dist(d2, dot), id));
            }
        }
        if keys.is_empty() {
            keys.extend(ranked.iter().map(|&k| {
                let (d2, id) = unkey(k);
                key(dist(d2, self.points[id as usize].1.dot(n)), id)
            }));
        }
        // Dist ≥ 0, so (Dist, id) packs into an ordered key; N is small, a plain sort beats a selection.
        keys.sort_unstable();
        out.extend(keys.iter().take(self.lookup.keep).map(|&k| {
            let (dist, id) = unkey(k);
            Neighbour { id, dist }
        }));
    }

    /// The N nearest caches to `p` as packed (d², id) keys, ranked. One tree query of N + 1; only when the
    /// N-th and (N+1)-th distances are within rounding of each other (coincident or symmetric caches) a
    /// radius query gathers every cache at that distance, so the set never depends on the tree layout.
    fn nearest(&self, tree: &ImmutableKdTree<f32, 3>, p: Vec3A) -> Vec<u64> {
        let q = p.to_array();
        let k = self.lookup.candidates.min(self.ids.len());
        let Some(k1) = NonZeroUsize::new((k + 1).min(self.ids.len())) else { return Vec::new() };
        let keyed = |r: &kiddo::QueryResultItem<(), u32, f32>| {
            let id = self.ids[r.item as usize];
            key(self.d2(id, p), id)
        };
        let mut ranked: Vec<u64> =
            tree.query(&q).nearest_n::<SquaredEuclidean<f32>>(k1).execute().iter().map(keyed).collect();
        ranked.sort_unstable();
        let gap = ranked.len() <= k || unkey(ranked[k]).0 > unkey(ranked[k - 1]).0 * (1.0 + 1e-5) + f32::MIN_POSITIVE;
        if !gap {
            let radius = unkey(ranked[k - 1]).0 * (1.0 + 2e-5) + f32::MIN_POSITIVE;
            ranked = tree.query(&q).within::<SquaredEuclidean<f32>>(radius).execute().iter().map(keyed).collect();
        }
        top_k(&mut ranked, k);
        ranked
    }

    /// Normalised interpolation weights for a selection (ALGORITHMS.md §5 step 6): w_i = 1/Dist_i divided by
    /// Σ w, as (cache id, weight) pairs in `out` (cleared first). If a cache is closer than the exact-hit
    /// radius (Dist ≤ EXACT_HIT · L), `out` holds that cache alone with weight 1. Entries with a non-finite
    /// Dist are ignored; an empty selection gives an empty `out`.
    pub fn interpolate_weights(&self, near: &[Neighbour], out: &mut Vec<(u32, f32)>) {
        out.clear();
        let finite = near.iter().filter(|nb| nb.dist.is_finite() && nb.dist >= 0.0);
        if let Some(hit) = finite
            .clone()
            .filter(|nb| nb.dist <= self.exact_radius)
            .min_by(|a, b| a.dist.total_cmp(&b.dist).then(a.id.cmp(&b.id)))
        {
            out.push((hit.id, 1.0));
            return;
        }
        out.extend(finite.map(|nb| (nb.id, 1.0 / nb.dist)));
        let sum: f32 = out.iter().map(|&(_, w)| w).sum();
        if sum > 0.0 && sum.is_finite() {
            for (_, w) in out.iter_mut() {
                *w /= sum;
            }
        } else if !out.is_empty() {
            // Every distance below f32 precision of 1/Dist: fall back to equal weights.
            let w = 1.0 / out.len() as f32;
            out.iter_mut().for_each(|e| e.1 = w);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// Seed of every random input in these tests.
    const SEED: u64 = 0x5eed_cace;

    #[test]
    fn the_region_radius_is_the_distance_to_the_kth_other_cache() {
        let points: Vec<(Vec3A, Vec3A)> =
            [0.0, 1.0, 3.0, 6.0].iter().map(|&x| (Vec3A::new(x, 0.0, 0.0), Vec3A::Z)).collect();
        let index = CacheIndex::new(&points, LookupParams::default(), 0.0);
        assert_eq!(index.region_radius(0, 1), 1.0);
        assert_eq!(index.region_radius(0, 2), 3.0);
        assert_eq!(index.region_radius(2, 2), 3.0);
        assert_eq!(index.region_radius(3, 3), 6.0);
        // Fewer than k other caches, or no such cache: unbounded.
        assert_eq!(index.region_radius(0, 4), f32::INFINITY);
        assert_eq!(index.region_radius(9, 1), f32::INFINITY);
    }

    fn random_unit(r: &mut Rng) -> Vec3A {
        loop {
            let v = Vec3A::new(r.uniform() * 2.0 - 1.0, r.uniform() * 2.0 - 1.0, r.uniform() * 2.0 - 1.0);
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }

    /// Random caches: positions in a unit cube, normals in a cone around +z so the filter matters.
    fn random_caches(r: &mut Rng, n: usize) -> Vec<(Vec3A, Vec3A)> {
        (0..n)
            .map(|_| {
                let p = Vec3A::new(r.uniform(), r.uniform(), r.uniform());
                let n = (Vec3A::Z + 0.8 * random_unit(r)).normalize();
                (p, n)
            })
            .collect()
    }

    /// §5 steps 1–5 by brute force.
    fn brute(points: &[(Vec3A, Vec3A)], lp: LookupParams, lambda: f32, p: Vec3A, n: Vec3A) -> Vec<Neighbour> {
        let mut by_dist: Vec<(f32, u32)> =
            points.iter().enumerate().map(|(i, &(pc, _))| ((pc - p).length_squared(), i as u32)).collect();
        by_dist.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        by_dist.truncate(lp.candidates);
        let cos = lp.theta_max_deg.to_radians().cos();
        let mut c: Vec<u32> =
            by_dist.iter().map(|e| e.1).filter(|&i| points[i as usize].1.normalize().dot(n) >= cos).collect();
        if c.is_empty() {
            c = by_dist.iter().map(|e| e.1).collect();
        }
        let mut out: Vec<Neighbour> = c
            .into_iter()
            .map(|id| {
                let (pc, nc) = points[id as usize];
                Neighbour { id, dist: (pc - p).length() + lambda * (1.0 - nc.normalize().dot(n)).max(0.0).sqrt() }
            })
            .collect();
        out.sort_by(|a, b| a.dist.total_cmp(&b.dist).then(a.id.cmp(&b.id)));
        out.truncate(lp.keep);
        out
    }

    #[test]
    fn selection_matches_brute_force_on_random_caches() {
        let mut r = Rng::keyed(SEED, 1, 0);
        for &count in &[1usize, 5, 19, 20, 21, 300, 2000] {
            let caches = random_caches(&mut r, count);
            let lp = LookupParams::default();
            let lambda = 0.5 / 3f32.sqrt();
            let index = CacheIndex::new(&caches, lp, lambda);
            assert_eq!(index.len(), count);
            let mut got = Vec::new();
            for _ in 0..300 {
                let p = Vec3A::new(r.uniform() * 1.2 - 0.1, r.uniform() * 1.2 - 0.1, r.uniform() * 1.2 - 0.1);
                let n = (Vec3A::Z + 1.2 * random_unit(&mut r)).normalize();
                index.select(p, n, &mut got);
                let want = brute(&caches, lp, lambda, p, n);
                assert_eq!(got.len(), want.len(), "{count} caches");
                for (g, w) in got.iter().zip(&want) {
                    assert_eq!(g.id, w.id, "{count} caches at {p}");
                    assert!((g.dist - w.dist).abs() <= 1e-5, "{} vs {}", g.dist, w.dist);
                }
                assert!(got.windows(2).all(|w| w[0].dist <= w[1].dist));
            }
        }
    }

    #[test]
    fn filter_keeps_only_similar_normals_unless_it_falls_back() {
        let mut r = Rng::keyed(SEED, 2, 0);
        let caches = random_caches(&mut r, 500);
        let lp = LookupParams::default();
        let index = CacheIndex::new(&caches, lp, 0.3);
        let mut got = Vec::new();
        let cos = lp.theta_max_deg.to_radians().cos();
        index.select(Vec3A::splat(0.5), Vec3A::Z, &mut got);
        assert_eq!(got.len(), lp.keep);
        assert!(got.iter().all(|nb| index.point(nb.id).is_some_and(|(_, n)| n.dot(Vec3A::Z) >= cos - 1e-6)));
        // Facing away from every cache: the filter leaves none, so the fallback uses all N candidates.
        index.select(Vec3A::splat(0.5), -Vec3A::Z, &mut got);
        assert_eq!(got.len(), lp.keep);
    }

    #[test]
    fn many_coincident_caches_are_accepted_and_ties_break_by_id() {
        // Far more identical positions than kiddo's bucket size (32): a hard-bucket tree would refuse them.
        let mut caches = vec![(Vec3A::new(1.0, 2.0, 3.0), Vec3A::Y); 5000];
        caches.push((Vec3A::new(1.5, 2.0, 3.0), Vec3A::Y));
        caches.extend(std::iter::repeat_n((Vec3A::new(-1.0, 0.0, 0.0), Vec3A::Y), 100));
        let index = CacheIndex::new(&caches, LookupParams::default(), 0.1);
        assert_eq!(index.len(), caches.len());
        let mut got = Vec::new();
        index.select(Vec3A::new(1.0, 2.0, 3.0), Vec3A::Y, &mut got);
        let ids: Vec<u32> = got.iter().map(|nb| nb.id).collect();
        assert_eq!(ids, vec![0, 1, 2, 3, 4, 5]);
        let brute_ids: Vec<u32> = brute(&caches, LookupParams::default(), 0.1, Vec3A::new(1.0, 2.0, 3.0), Vec3A::Y)
            .iter()
            .map(|nb| nb.id)
            .collect();
        assert_eq!(ids, brute_ids);
        index.select(Vec3A::new(-1.0, 0.1, 0.0), Vec3A::Y, &mut got);
        assert_eq!(got.iter().map(|nb| nb.id).collect::<Vec<_>>(), vec![5001, 5002, 5003, 5004, 5005, 5006]);
    }

    #[test]
    fn fewer_caches_than_candidates_and_empty_index() {
        let caches = vec![(Vec3A::ZERO, Vec3A::Z), (Vec3A::X, Vec3A::Z), (Vec3A::Y, Vec3A::X)];
        let index = CacheIndex::new(&caches, LookupParams::default(), 0.5);
        let mut got = Vec::new();
        index.select(Vec3A::new(0.1, 0.0, 0.0), Vec3A::Z, &mut got);
        assert_eq!(got.iter().map(|nb| nb.id).collect::<Vec<_>>(), vec![0, 1]);
        let empty = CacheIndex::new(&[], LookupParams::default(), 0.5);
        assert!(empty.is_empty());
        empty.select(Vec3A::ZERO, Vec3A::Z, &mut got);
        assert!(got.is_empty());
    }

    #[test]
    fn nan_caches_are_skipped_and_nan_queries_select_nothing() {
        let caches = vec![
            (Vec3A::new(f32::NAN, 0.0, 0.0), Vec3A::Z),
            (Vec3A::ZERO, Vec3A::new(f32::NAN, 0.0, 1.0)),
            (Vec3A::ZERO, Vec3A::ZERO),
            (Vec3A::X, Vec3A::Z),
            (Vec3A::new(f32::INFINITY, 0.0, 0.0), Vec3A::Z),
        ];
        let index = CacheIndex::new(&caches, LookupParams::default(), 0.5);
        assert_eq!((index.len(), index.skipped()), (1, 4));
        let mut got = Vec::new();
        index.select(Vec3A::ZERO, Vec3A::Z, &mut got);
        assert_eq!(got.iter().map(|nb| nb.id).collect::<Vec<_>>(), vec![3]);
        index.select(Vec3A::new(f32::NAN, 0.0, 0.0), Vec3A::Z, &mut got);
        assert!(got.is_empty());
        index.select(Vec3A::ZERO, Vec3A::new(0.0, f32::NAN, 1.0), &mut got);
        assert!(got.is_empty());
    }

    #[test]
    fn weights_are_inverse_distances_and_an_exact_hit_stands_alone() {
        let caches = vec![(Vec3A::ZERO, Vec3A::Z), (Vec3A::X, Vec3A::Z), (Vec3A::new(3.0, 0.0, 0.0), Vec3A::Z)];
        let index = CacheIndex::new(&caches, LookupParams::default(), 0.5).with_scale(10.0);
        let mut near = Vec::new();
        let mut w = Vec::new();
        index.select(Vec3A::new(0.5, 0.0, 0.0), Vec3A::Z, &mut near);
        index.interpolate_weights(&near, &mut w);
        assert_eq!(w.len(), 3);
        let sum: f32 = w.iter().map(|e| e.1).sum();
        assert!((sum - 1.0).abs() < 1e-6);
        // Dist 0.5, 0.5, 2.5 ⇒ weights 2, 2, 0.4 normalised.
        assert!((w[0].1 - 2.0 / 4.4).abs() < 1e-6 && (w[2].1 - 0.4 / 4.4).abs() < 1e-6, "{w:?}");
        index.select(Vec3A::X, Vec3A::Z, &mut near);
        index.interpolate_weights(&near, &mut w);
        assert_eq!(w, vec![(1, 1.0)]);
        index.select(Vec3A::new(1.0 + 5e-7, 0.0, 0.0), Vec3A::Z, &mut near);
        index.interpolate_weights(&near, &mut w);
        assert_eq!(w, vec![(1, 1.0)], "within 1e-7·L of cache 1");
        index.interpolate_weights(&[], &mut w);
        assert!(w.is_empty());
    }

    /// Checks `select_group_in` (buffers kept across calls, as the render and DGS keep them) against
    /// `select` query by query.
    fn group_matches_single(index: &CacheIndex, queries: &[(Vec3A, Vec3A)], scratch: &mut GroupScratch) {
        let mut single = Vec::new();
        let mut calls = 0;
        index.select_group_in(queries, scratch, |i, got| {
            assert_eq!(i, calls, "queries answered out of order");
            calls += 1;
            index.select(queries[i].0, queries[i].1, &mut single);
            assert_eq!(got, &single[..], "query {i} at {}", queries[i].0);
        });
        assert_eq!(calls, queries.len());
    }

    #[test]
    fn group_selection_equals_single_selection() {
        let mut r = Rng::keyed(SEED, 4, 0);
        for &count in &[3usize, 150, 5000, 40_000] {
            let caches = random_caches(&mut r, count);
            let index = CacheIndex::new(&caches, LookupParams::default(), 0.3);
            // One scratch for every group of this index: tight groups first, then wider ones that the
            // remembered spacing may split before querying.
            let mut scratch = GroupScratch::default();
            for spread in [0.0, 0.002, 0.02, 0.3] {
                let c = Vec3A::new(r.uniform(), r.uniform(), r.uniform());
                let queries: Vec<(Vec3A, Vec3A)> = (0..16)
                    .map(|_| {
                        let p = c + spread * Vec3A::new(r.uniform() - 0.5, r.uniform() - 0.5, r.uniform() - 0.5);
                        (p, (Vec3A::Z + random_unit(&mut r)).normalize())
                    })
                    .collect();
                group_matches_single(&index, &queries, &mut scratch);
            }
        }
    }

    #[test]
    fn group_selection_handles_ties_and_bad_queries() {
        let mut caches = vec![(Vec3A::new(0.5, 0.5, 0.5), Vec3A::Z); 1000];
        let mut r = Rng::keyed(SEED, 5, 0);
        caches.extend(random_caches(&mut r, 2000));
        let index = CacheIndex::new(&caches, LookupParams::default(), 0.3);
        let mut queries: Vec<(Vec3A, Vec3A)> =
            (0..12).map(|i| (Vec3A::new(0.5 + 0.001 * i as f32, 0.5, 0.5), Vec3A::Z)).collect();
        queries.push((Vec3A::NAN, Vec3A::Z));
        queries.push((Vec3A::new(0.5, 0.5, 0.5), Vec3A::new(f32::NAN, 0.0, 0.0)));
        let mut scratch = GroupScratch::default();
        group_matches_single(&index, &queries, &mut scratch);
        // A group straddling distant points (a depth edge) is split, still matching.
        let far: Vec<(Vec3A, Vec3A)> =
            (0..8).map(|i| (Vec3A::splat(if i % 2 == 0 { 0.05 } else { 0.95 }), Vec3A::Z)).collect();
        group_matches_single(&index, &far, &mut scratch);
    }

    #[test]
    fn lookups_do_not_depend_on_the_thread_count() {
        let mut r = Rng::keyed(SEED, 3, 0);
        let caches = random_caches(&mut r, 20_000);
        let queries: Vec<Vec3A> = (0..2000).map(|_| Vec3A::new(r.uniform(), r.uniform(), r.uniform())).collect();
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let index = CacheIndex::new(&caches, LookupParams::default(), 0.3);
                let mut out = Vec::new();
                let mut all = Vec::new();
                for &q in &queries {
                    index.select(q, Vec3A::Z, &mut out);
                    all.extend(out.iter().map(|nb| nb.id));
                }
                all
            })
        };
        assert_eq!(run(1), run(2));
    }
}
