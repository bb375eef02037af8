//! STAGE 4 (shared by every strategy): the budget cases every first stage handles the same way — budget 0,
//! no usable pixel, a budget at or above the usable pixel count — and seeded uniform picks without
//! replacement (fills and fallbacks).
//!
//! Depends on `points`, `gbuffer` and `sampling`; knows nothing of any particular strategy.

use super::points::{self, Pt};
use super::{Clusters, PlacementInfo, SplitRule, Stage1};
use crate::error::{Error, Result};
use crate::gbuffer::{GBuffer, PixelId};
use crate::sampling::Rng;

/// What a first stage does after the common checks.
#[derive(Debug)]
pub(crate) enum Prelude {
    /// The answer is already known (budget 0, nothing usable, or every usable pixel is a site).
    Done(Stage1),
    /// Proceed with these usable points (more than `budget` of them) and the notes gathered so far.
    Go(Vec<Pt>, Vec<String>),
}

/// Refuses a G-buffer whose point count does not match its size (placement indexes pixels by (x, y)).
pub(crate) fn check_gbuffer(g: &GBuffer) -> Result<()> {
    match g.width.checked_mul(g.height) {
        Some(n) if n == g.points.len() && n <= PixelId::MAX as usize => Ok(()),
        _ => Err(Error::usage(format!(
            "placement: the G-buffer holds {} shading points for {}×{} pixels",
            g.points.len(),
            g.width,
            g.height
        ))),
    }
}

/// A strategy's split rule for a set of points.
pub(crate) type RuleOf<'a> = &'a dyn Fn(&[Pt]) -> SplitRule;

/// The checks every first stage starts with. `rule` gives the strategy's split rule for its points
/// (singleton clusters are reported with it when every pixel becomes a site).
pub(crate) fn prelude(g: &GBuffer, budget: usize, meters_per_unit: f32, rule: Option<RuleOf<'_>>) -> Prelude {
    let pts = points::collect(g, meters_per_unit);
    let mut notes = Vec::new();
    if pts.len() < g.valid_count {
        notes.push(format!(
            "{} valid pixel(s) have a non-finite position, normal or depth and cannot host a cache",
            g.valid_count - pts.len()
        ));
    }
    if pts.is_empty() {
        notes.push("no usable shading point (the view sees only background): no caches placed".to_string());
        return Prelude::Done(Stage1 { info: PlacementInfo { notes, ..Default::default() }, ..Default::default() });
    }
    if budget == 0 {
        return Prelude::Done(Stage1 { info: PlacementInfo { notes, ..Default::default() }, ..Default::default() });
    }
    if budget >= pts.len() {
        if budget > pts.len() {
            notes.push(format!(
                "budget {budget} exceeds the {} usable pixels: every usable pixel becomes a cache",
                pts.len()
            ));
        }
        let sites: Vec<PixelId> = pts.iter().map(|q| q.id).collect();
        let clusters = rule.map(|rule| Clusters {
            members: sites.clone(),
            ranges: (0..sites.len() as u32).map(|i| i..i + 1).collect(),
            rule: Some(rule(&pts)),
        });
        let info = PlacementInfo { clusters_found: sites.len(), notes, ..Default::default() };
        return Prelude::Done(Stage1 { sites, clusters, info });
    }
    Prelude::Go(pts, notes)
}

/// Picks `k` of `candidates` uniformly without replacement (partial Fisher–Yates with the stream
/// (seed, `stage`, 0)); returns them in draw order. `candidates` is reordered.
pub(crate) fn pick_uniform(candidates: &mut [PixelId], k: usize, seed: u64, stage: u64) -> Vec<PixelId> {
    let k = k.min(candidates.len());
    let mut rng = Rng::keyed(seed, stage, 0);
    for i in 0..k {
        let j = i + rng.below((candidates.len() - i) as u32) as usize;
        candidates.swap(i, j);
    }
    candidates[..k].to_vec()
}

/// The usable pixels of `g` not marked in `taken` (indexed by pixel id), in pixel order.
pub(crate) fn free_usable(g: &GBuffer, taken: &[bool]) -> Vec<PixelId> {
    (0..g.points.len() as PixelId)
        .filter(|&id| !taken.get(id as usize).copied().unwrap_or(false) && points::is_usable(g, id))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_g_buffer_of_the_wrong_size_is_refused_by_every_strategy() {
        let mut g = crate::placement::test_scenes::flat(8, 8);
        g.points.pop();
        assert!(check_gbuffer(&g).is_err());
        for name in crate::placement::registry::NAMES {
            let s = crate::placement::registry::strategy(name).unwrap();
            let e = s.initial.place(&g, 5, &Default::default(), 1).unwrap_err();
            assert!(e.to_string().contains("8×8"), "{name}: {e}");
            if let Some(a) = &s.adaptive {
                let mut o = crate::placement::test_scenes::MaskOracle::new(&g, &[]);
                assert!(a.place(&g, &Default::default(), &mut o, 5, &Default::default(), 1).is_err(), "{name}");
            }
        }
    }

    #[test]
    fn uniform_picks_are_distinct_and_seeded() {
        let mut a: Vec<PixelId> = (0..1000).collect();
        let mut b = a.clone();
        let mut c = a.clone();
        let pa = pick_uniform(&mut a, 100, 7, 1);
        assert_eq!(pa, pick_uniform(&mut b, 100, 7, 1));
        assert_ne!(pa, pick_uniform(&mut c, 100, 8, 1));
        let mut sorted = pa.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), 100);
        assert_eq!(pick_uniform(&mut a, 5000, 7, 1).len(), 1000);
    }
}
