//! STAGE 4, second stage **AS**: adaptive sampling after a clustering first stage, our reconstruction of
//! Yoshida et al. 2015 as the paper summarises it (paper §3.2 last paragraph; ALGORITHMS.md §4.3, ambiguity
//! A20). Each cache's error is the summed difference to the caches the §5 lookup would blend at it; the
//! caches with the largest error get one more cache each, by splitting their cluster once with the first
//! stage's rule. New caches are evaluated and the process repeats until the budget is spent.
//!
//! Depends on `gbuffer`, `cache` (the §5 selection), the shared placement helpers and `sampling`; sees cache
//! records only through [`CacheOracle`]. Never depends on `render`, `scene` or an application.

use std::collections::{BinaryHeap, HashMap};
use std::ops::Range;

use glam::Vec3A;
use rayon::prelude::*;

use super::budget::{free_usable, pick_uniform};
use super::points::{Pt, usable_normal};
use super::split::split_with;
use super::{AdaptiveInfo, AdaptivePlacement, CacheId, CacheOracle, PlacementParams, SplitRule, Stage1};
use crate::cache::{CacheIndex, LookupParams, Neighbour};
use crate::error::{Error, Result};
use crate::gbuffer::{GBuffer, PixelId};
use crate::sampling::Rng;

/// Stream tags of AS's random decisions.
const STAGE_NEW: u64 = 0x4153_0001;
const STAGE_FILL: u64 = 0x4153_0002;
/// Rounds of error-driven insertion before the rest is placed by splitting the largest clusters.
const MAX_ROUNDS: u32 = 64;

/// AS — adaptive sampling by neighbour error (reconstruction).
///
/// | step | what |
/// |---|---|
/// | error | E(c) = Σ Diff(c, c′) over Nb(c), the M caches the §5 lookup selects at c's own position and normal, c itself excluded |
/// | insert | caches by E descending (E > 0, ties by id): split c's cluster once with the first stage's rule; the child without c gets a random member as a new cache (one-pixel clusters are skipped) |
/// | rounds | evaluate the new caches through the oracle and repeat with them as candidates; if a round inserts nothing, all caches are candidates once more; if still nothing (or after 64 rounds), split the largest clusters, then uniform |
///
/// Needs the clusters of the first stage (SD or VGC); a first stage without clusters is an error. Options:
/// `PlacementParams::lookup` (the §5 selection).
#[derive(Clone, Copy, Debug, Default)]
pub struct AdaptiveSampling;

/// The clusters as AS grows them: points of all clusters (partitioned in place by splits), the range of
/// each cluster, the cluster of each cache and which pixels are caches.
struct State<'g> {
    g: &'g GBuffer,
    pts: Vec<Pt>,
    leaves: Vec<Range<u32>>,
    leaf_of: Vec<Option<usize>>,
    is_cache: Vec<bool>,
    rule: SplitRule,
}

impl<'g> State<'g> {
    fn new(g: &'g GBuffer, stage1: &Stage1, oracle: &dyn CacheOracle) -> Result<Self> {
        let Some(c) = &stage1.clusters else {
            return Err(Error::usage("adaptive sampling (AS) needs the clusters of an SD or VGC first stage"));
        };
        let rule = c.rule.unwrap_or(SplitRule::ViewGuided);
        let mut pts = Vec::with_capacity(c.members.len());
        let mut leaves = Vec::with_capacity(c.ranges.len());
        for r in &c.ranges {
            let start = pts.len() as u32;
            for &id in c.members.get(r.start as usize..r.end as usize).unwrap_or(&[]) {
                if let Some((sp, n)) = g.get(id).and_then(|sp| usable_normal(sp).map(|n| (sp, n))) {
                    pts.push(Pt { p: sp.p.to_array(), n: n.to_array(), depth: sp.depth, id });
                }
            }
            leaves.push(start..pts.len() as u32);
        }
        let leaf_of_site: HashMap<PixelId, usize> = stage1.sites.iter().enumerate().map(|(i, &s)| (s, i)).collect();
        let mut is_cache = vec![false; g.points.len()];
        let leaf_of = (0..oracle.len() as CacheId)
            .map(|c| {
                let s = oracle.site(c);
                if let Some(t) = is_cache.get_mut(s as usize) {
                    *t = true;
                }
                leaf_of_site.get(&s).copied().filter(|&l| l < leaves.len())
            })
            .collect();
        Ok(State { g, pts, leaves, leaf_of, is_cache, rule })
    }

    /// Splits the cluster of cache `c` once; the child without c's site gets a new cache (a random free
    /// member, stream (seed, new, `n`)). Returns the new cache's pixel.
    fn split_leaf(&mut self, c: CacheId, site: PixelId, seed: u64, n: u64) -> Option<PixelId> {
        let leaf = self.leaf_of.get(c as usize).copied().flatten()?;
        let r = self.leaves[leaf].clone();
        self.split_range(leaf, r, Some(site), seed, STAGE_NEW, n)
    }

    fn split_range(
        &mut self,
        leaf: usize,
        r: Range<u32>,
        keep: Option<PixelId>,
        seed: u64,
        tag: u64,
        n: u64,
    ) -> Option<PixelId> {
        if r.len() < 2 {
            return None;
        }
        let slice = &mut self.pts[r.start as usize..r.end as usize];
        let m = split_with(slice, self.rule)? as u32;
        let (a, b) = (r.start..r.start + m, r.start + m..r.end);
        let in_a = keep.is_some_and(|s| self.pts[a.start as usize..a.end as usize].iter().any(|q| q.id == s));
        let (mine, other) = if in_a || keep.is_none() { (a, b) } else { (b, a) };
        let free: Vec<PixelId> = self.pts[other.start as usize..other.end as usize]
            .iter()
            .map(|q| q.id)
            .filter(|&id| !self.is_cache[id as usize])
            .collect();
        if free.is_empty() {
            return None;
        }
        let pick = free[Rng::keyed(seed, tag, n).below(free.len() as u32) as usize];
        self.is_cache[pick as usize] = true;
        self.leaves[leaf] = mine;
        self.leaves.push(other);
        self.leaf_of.push(Some(self.leaves.len() - 1));
        Some(pick)
    }
}

/// E(c) for each candidate (ALGORITHMS.md §4.3 step 2), all differences in one `diff_many` call.
fn errors(g: &GBuffer, oracle: &dyn CacheOracle, cands: &[CacheId], lookup: LookupParams, lambda: f32) -> Vec<f32> {
    let caches: Vec<(Vec3A, Vec3A)> = (0..oracle.len() as CacheId)
        .map(|c| {
            g.get(oracle.site(c))
                .and_then(|sp| usable_normal(sp).map(|n| (sp.p, n)))
                .unwrap_or((Vec3A::NAN, Vec3A::NAN))
        })
        .collect();
    // CHOICE: select M + 1 and drop c itself, so Nb(c) has M caches other than c.
    let lp = LookupParams { keep: lookup.keep + 1, ..lookup };
    let index = CacheIndex::new(&caches, lp, lambda).with_scale(g.scale);
    let nbs: Vec<Vec<CacheId>> = cands
        .par_iter()
        .map_init(Vec::<Neighbour>::new, |near, &c| {
            let (p, n) = caches[c as usize];
            index.select(p, n, near);
            near.iter().map(|nb| nb.id).filter(|&id| id != c).take(lookup.keep).collect()
        })
        .collect();
    let pairs: Vec<(CacheId, CacheId)> =
        cands.iter().zip(&nbs).flat_map(|(&c, nb)| nb.iter().map(move |&o| (c, o))).collect();
    let diffs = oracle.diff_many(&pairs);
    let mut e = Vec::with_capacity(cands.len());
    let mut k = 0;
    for nb in &nbs {
        let sum: f64 =
            diffs.get(k..k + nb.len()).unwrap_or(&[]).iter().filter(|d| d.is_finite()).map(|&d| d as f64).sum();
        e.push(sum as f32);
        k += nb.len();
    }
    e
}

impl AdaptivePlacement for AdaptiveSampling {
    fn place(
        &self,
        g: &GBuffer,
        stage1: &Stage1,
        oracle: &mut dyn CacheOracle,
        budget: usize,
        params: &PlacementParams,
        seed: u64,
    ) -> Result<AdaptiveInfo> {
        super::budget::check_gbuffer(g)?;
        if budget == 0 {
            return Ok(AdaptiveInfo::default());
        }
        let mut st = State::new(g, stage1, oracle)?;
        let l = g.scale;
        let lambda = params.lambda_for(if l.is_finite() && l > 0.0 { l } else { 1.0 });
        let mut info = AdaptiveInfo::default();
        let mut cands: Vec<CacheId> = (0..oracle.len() as CacheId).collect();
        let mut widened = true; // the first round already looks at every cache
        while info.added < budget && info.rounds < MAX_ROUNDS {
            let e = errors(g, oracle, &cands, params.lookup, lambda);
            let mut order: Vec<usize> = (0..cands.len()).filter(|&i| e[i] > 0.0).collect();
            order.sort_by(|&a, &b| e[b].total_cmp(&e[a]).then(cands[a].cmp(&cands[b])));
            let mut new_sites = Vec::new();
            for i in order {
                if info.added + new_sites.len() == budget {
                    break;
                }
                let c = cands[i];
                let n = (info.added + new_sites.len()) as u64;
                if let Some(s) = st.split_leaf(c, oracle.site(c), seed, n) {
                    new_sites.push(s);
                }
            }
            if new_sites.is_empty() {
                if widened {
                    break;
                }
                widened = true;
                cands = (0..oracle.len() as CacheId).collect();
                continue;
            }
            let first_new = oracle.len() as CacheId;
            oracle.evaluate(&new_sites);
            info.rounds += 1;
            info.added += new_sites.len();
            cands = (first_new..oracle.len() as CacheId).collect();
            widened = false;
        }
        if info.added < budget {
            let filled = fill(&mut st, budget - info.added, seed);
            info.notes.push(format!(
                "the neighbour error placed {} of {budget} caches; the other {} split the largest clusters or are uniform",
                info.added,
                filled.len()
            ));
            if info.added + filled.len() < budget {
                info.notes.push(format!("only {} free usable pixels remain", info.added + filled.len()));
            }
            if !filled.is_empty() {
                oracle.evaluate(&filled);
                info.rounds += 1;
                info.added += filled.len();
            }
        }
        Ok(info)
    }
}

/// Places `k` caches without an error signal: split the largest clusters (ties by index), then uniformly
/// random free usable pixels.
fn fill(st: &mut State<'_>, k: usize, seed: u64) -> Vec<PixelId> {
    let mut out = Vec::new();
    let mut heap: BinaryHeap<(usize, std::cmp::Reverse<usize>)> =
        st.leaves.iter().enumerate().map(|(i, r)| (r.len(), std::cmp::Reverse(i))).collect();
    while out.len() < k {
        let Some((len, std::cmp::Reverse(leaf))) = heap.pop() else { break };
        if len < 2 {
            break;
        }
        let r = st.leaves[leaf].clone();
        let keep = st.pts[r.start as usize..r.end as usize].iter().map(|q| q.id).find(|&id| st.is_cache[id as usize]);
        if let Some(s) = st.split_range(leaf, r, keep, seed, STAGE_FILL, out.len() as u64) {
            out.push(s);
            heap.push((st.leaves[leaf].len(), std::cmp::Reverse(leaf)));
            heap.push((st.leaves[st.leaves.len() - 1].len(), std::cmp::Reverse(st.leaves.len() - 1)));
        }
    }
    if out.len() < k {
        let mut free = free_usable(st.g, &st.is_cache);
        let rest = pick_uniform(&mut free, k - out.len(), seed, STAGE_FILL + 1);
        rest.iter().for_each(|&id| st.is_cache[id as usize] = true);
        out.extend(rest);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::placement::test_scenes::{self as ts, MaskOracle};
    use crate::placement::{ImageUniform, InitialPlacement, SpatialDirectional, ViewGuided};

    #[test]
    fn as_meets_the_contract_after_sd_and_vgc() {
        ts::check_adaptive(&AdaptiveSampling, &SpatialDirectional, true);
        ts::check_adaptive(&AdaptiveSampling, &ViewGuided { two_stage: true }, true);
    }

    #[test]
    fn as_adds_exactly_the_budget_over_several_rounds() {
        // Few caches with an error: the first round cannot spend a large budget, later rounds must.
        let g = ts::flat(96, 64);
        let p = PlacementParams::default();
        let s1 = ViewGuided::default().place(&g, 60, &p, 1).unwrap();
        let mut oracle = MaskOracle::new(&g, &s1.sites);
        let info = AdaptiveSampling.place(&g, &s1, &mut oracle, 400, &p, 1).unwrap();
        assert_eq!(info.added, 400);
        assert_eq!(oracle.sites.len(), 460);
        assert!(info.rounds >= 2, "{info:?}");
        ts::check_sites(&g, &oracle.sites);
    }

    #[test]
    fn a_first_stage_without_clusters_is_an_error() {
        let g = ts::flat(32, 32);
        let s1 = ImageUniform.place(&g, 20, &PlacementParams::default(), 1).unwrap();
        let mut oracle = MaskOracle::new(&g, &s1.sites);
        let e = AdaptiveSampling.place(&g, &s1, &mut oracle, 5, &PlacementParams::default(), 1).unwrap_err();
        assert!(e.to_string().contains("clusters"));
    }
}
