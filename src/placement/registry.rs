//! STAGE 4: the one registry of placement strategies, by the names users type (DESIGN.md §2, STYLE habit
//! 10: one explicit table, no self-registration).
//!
//! Depends only on the strategy types of this module's parent.

use crate::error::{Error, Result};

use super::{
    AdaptivePlacement, AdaptiveSampling, DgsTerms, Discontinuity, ImageUniform, InitialPlacement, PlacementParams,
    Refine, SpatialDirectional, ViewGuided,
};

/// A placement strategy: a first stage and, for two-stage strategies, a second.
#[derive(Debug)]
pub struct Strategy {
    /// The name as typed (`"vgc+dgs"`).
    pub name: &'static str,
    /// First stage.
    pub initial: Box<dyn InitialPlacement>,
    /// Second stage, when there is one (its share of the budget is `PlacementParams::ratio`).
    pub adaptive: Option<Box<dyn AdaptivePlacement>>,
}

impl Strategy {
    /// The first stage's share of a total budget: all of it for one-stage strategies, `1 − ratio` for the
    /// paper's two-stage ones, `1 − refine_share` for `refine` (with a target error: 1/256 of it, at least 16);
    /// at least one cache.
    pub fn first_stage_budget(&self, total: usize, p: &PlacementParams) -> usize {
        let share = match (&self.adaptive, self.name) {
            (None, _) => return total,
            (Some(_), "refine") if p.target.is_some() => return (total / 256).max(TARGET_START).min(total),
            (Some(_), "refine") => p.refine_share,
            (Some(_), _) => p.ratio,
        };
        (((1.0 - share as f64) * total as f64).round() as usize).clamp(1, total.max(1))
    }
}

/// With a target error refine's first stage places 1/256 of the budget, at least this many caches: the
/// budget is a ceiling, and the rounds add what the estimate asks for (a larger start overshoots loose
/// targets: 450 caches already meet 20 % on the staircase at 160×90).
const TARGET_START: usize = 16;

/// Every strategy name, in the order reports list them. `none` (the per-sample reference) is handled by
/// the render driver, not here.
pub const NAMES: [&str; 9] =
    ["im", "sd", "sd+as", "vgc", "vgc+dgs", "refine", "vgc+as", "vgc+dgs:diff", "vgc+dgs:geom"];

/// Looks a strategy up by name; an unknown name is an error listing the valid ones.
///
/// | name | stage 1 | stage 2 |
/// |---|---|---|
/// | `im` | IM | — |
/// | `sd` | SD | — |
/// | `sd+as` | SD | AS |
/// | `vgc` | VGC | — |
/// | `vgc+dgs` | VGC | DGS with the terms of `PlacementParams::dgs` (Eq. 4: all three by default) |
/// | `vgc+as` | VGC | AS (Table 2 ablation) |
/// | `vgc+dgs:diff` | VGC | DGS with Diff_avg′ + Diff_max′ only (Table 2 "DGS (diff)") |
/// | `vgc+dgs:geom` | VGC | DGS with G′ only (Table 2 "DGS (geom)") |
/// | `refine` | IM with `1 − refine_share` of the budget | rounds of map-guided insertion (beyond the paper) |
///
/// For two-stage strategies VGC is told its budget is the first-stage share, so σ_a follows the total.
pub fn strategy(name: &str) -> Result<Strategy> {
    let dgs = |terms| -> Box<dyn AdaptivePlacement> { Box::new(Discontinuity { terms }) };
    let (initial, adaptive): (Box<dyn InitialPlacement>, Option<Box<dyn AdaptivePlacement>>) = match name {
        "im" => (Box::new(ImageUniform), None),
        "sd" => (Box::new(SpatialDirectional), None),
        "sd+as" => (Box::new(SpatialDirectional), Some(Box::new(AdaptiveSampling))),
        "vgc" => (Box::new(ViewGuided { two_stage: false }), None),
        "vgc+dgs" => (Box::new(ViewGuided { two_stage: true }), Some(dgs(None))),
        "refine" => (Box::new(ImageUniform), Some(Box::new(Refine))),
        "vgc+as" => (Box::new(ViewGuided { two_stage: true }), Some(Box::new(AdaptiveSampling))),
        "vgc+dgs:diff" => {
            (Box::new(ViewGuided { two_stage: true }), Some(dgs(Some(DgsTerms { diff: true, geometry: false }))))
        }
        "vgc+dgs:geom" => {
            (Box::new(ViewGuided { two_stage: true }), Some(dgs(Some(DgsTerms { diff: false, geometry: true }))))
        }
        _ => {
            return Err(Error::usage(format!(
                "unknown placement \"{name}\"; expected one of: none, {}",
                NAMES.join(", ")
            )));
        }
    };
    let name = NAMES.iter().copied().find(|&n| n == name).unwrap_or("?");
    Ok(Strategy { name, initial, adaptive })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::placement::PlacementParams;
    use crate::placement::test_scenes::{self as ts, MaskOracle};

    #[test]
    fn every_name_resolves_and_two_stage_ones_have_a_second_stage() {
        for name in NAMES {
            let s = strategy(name).unwrap();
            assert_eq!(s.name, name);
            assert_eq!(s.adaptive.is_some(), name.contains('+') || name == "refine", "{name}");
        }
        let e = strategy("vgc+foo").unwrap_err().to_string();
        assert!(e.contains("vgc+foo") && NAMES.iter().all(|n| e.contains(n)), "{e}");
    }

    #[test]
    fn every_strategy_spends_the_total_budget_exactly() {
        let g = ts::sphere_on_plane(128, 96);
        let p = PlacementParams::default();
        let total = 900usize;
        for name in NAMES {
            let s = strategy(name).unwrap();
            let n1 = s.first_stage_budget(total, &p);
            let s1 = s.initial.place(&g, n1, &p, 4).unwrap();
            assert_eq!(s1.sites.len(), n1, "{name}");
            let mut oracle = MaskOracle::new(&g, &s1.sites);
            if let Some(a) = &s.adaptive {
                let info = a.place(&g, &s1, &mut oracle, total - s1.sites.len(), &p, 4).unwrap();
                assert_eq!(info.added, total - n1, "{name}");
            }
            assert_eq!(oracle.sites.len(), total, "{name}");
            ts::check_sites(&g, &oracle.sites);
        }
    }
}
