//! STAGE 4, first stage **IM**: image-space uniform sampling (ALGORITHMS.md §4.1; the paper's baseline,
//! after Georgiev et al.'s random image-space records). Jittered-stratified: one random usable pixel per cell
//! of a grid sized for the budget, then an exact trim or fill.
//!
//! Depends on `gbuffer`, the shared placement helpers and `sampling`; never on `render`, `scene` or `cache`.

use rayon::prelude::*;

use super::budget::{self, Prelude};
use super::{InitialPlacement, PlacementInfo, PlacementParams, Stage1};
use crate::error::Result;
use crate::gbuffer::{GBuffer, PixelId};
use crate::sampling::Rng;

/// Stream tags of IM's random decisions.
const STAGE_CELL: u64 = 0x494d_0001;
const STAGE_TRIM: u64 = 0x494d_0002;
const STAGE_FILL: u64 = 0x494d_0003;

/// IM — image-space uniform sampling.
///
/// | step | what |
/// |---|---|
/// | grid | G = ceil(N1·W·H / P) cells of aspect ≈ 1 (P = usable pixels), so cells that see only background are compensated |
/// | cell | one uniformly random usable pixel per cell (cells without one are skipped) |
/// | trim / fill | drop random picks above N1; add uniformly random unused usable pixels below N1 |
///
/// No options. Forms no clusters.
#[derive(Clone, Copy, Debug, Default)]
pub struct ImageUniform;

/// Cell counts (nx, ny) for about `g_cells` square-ish cells on a w × h image.
fn grid(w: usize, h: usize, g_cells: usize) -> (usize, usize) {
    let side = ((w * h) as f64 / g_cells.max(1) as f64).sqrt();
    let nx = ((w as f64 / side).round() as usize).clamp(1, w);
    let ny = ((h as f64 / side).round() as usize).clamp(1, h);
    (nx, ny)
}

impl InitialPlacement for ImageUniform {
    fn place(&self, g: &GBuffer, budget: usize, params: &PlacementParams, seed: u64) -> Result<Stage1> {
        budget::check_gbuffer(g)?;
        let (usable_count, notes) = match budget::prelude(g, budget, params.meters_per_unit, None) {
            Prelude::Done(s) => return Ok(s),
            Prelude::Go(pts, notes) => (pts.len(), notes),
        };
        let (w, h) = (g.width, g.height);
        let usable: Vec<bool> = (0..w * h).into_par_iter().map(|i| super::points::is_usable(g, i as PixelId)).collect();
        let g_cells = (budget as f64 * (w * h) as f64 / usable_count as f64).ceil() as usize;
        let (nx, ny) = grid(w, h, g_cells);
        let picks: Vec<PixelId> = (0..nx * ny)
            .into_par_iter()
            .filter_map(|c| {
                let (cx, cy) = (c % nx, c / nx);
                let (x0, x1) = (cx * w / nx, (cx + 1) * w / nx);
                let (y0, y1) = (cy * h / ny, (cy + 1) * h / ny);
                let mut rng = Rng::keyed(seed, STAGE_CELL, c as u64);
                // Reservoir sampling of one usable pixel in the cell.
                let mut chosen = None;
                let mut seen = 0u32;
                for y in y0..y1 {
                    for x in x0..x1 {
                        if usable[y * w + x] {
                            seen += 1;
                            if rng.below(seen) == 0 {
                                chosen = Some(g.id(x, y));
                            }
                        }
                    }
                }
                chosen
            })
            .collect();
        let found = picks.len();
        let sites = fit(picks, budget, &usable, seed);
        let info = PlacementInfo { clusters_found: found, notes, ..Default::default() };
        Ok(Stage1 { sites, clusters: None, info })
    }
}

/// Trims random picks or fills with random unused usable pixels to exactly `budget` (≤ usable count).
fn fit(mut picks: Vec<PixelId>, budget: usize, usable: &[bool], seed: u64) -> Vec<PixelId> {
    if picks.len() > budget {
        let mut idx: Vec<PixelId> = (0..picks.len() as PixelId).collect();
        let mut keep = budget::pick_uniform(&mut idx, budget, seed, STAGE_TRIM);
        keep.sort_unstable();
        return keep.into_iter().map(|i| picks[i as usize]).collect();
    }
    if picks.len() < budget {
        let mut taken = vec![false; usable.len()];
        picks.iter().for_each(|&id| taken[id as usize] = true);
        let mut free: Vec<PixelId> =
            (0..usable.len()).filter(|&i| usable[i] && !taken[i]).map(|i| i as PixelId).collect();
        let extra = budget::pick_uniform(&mut free, budget - picks.len(), seed, STAGE_FILL);
        picks.extend(extra);
    }
    picks
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::placement::test_scenes as ts;

    #[test]
    fn grid_has_about_the_requested_cells() {
        let (nx, ny) = grid(1920, 1080, 120_000);
        assert!((nx * ny).abs_diff(120_000) < 1_500, "{nx}×{ny}");
        assert_eq!(grid(3, 1, 100), (3, 1));
    }

    #[test]
    fn im_meets_the_contract() {
        ts::check_initial(&ImageUniform, true);
    }

    #[test]
    fn im_spreads_over_the_image() {
        let g = ts::flat(64, 48);
        let s = ImageUniform.place(&g, 48, &PlacementParams::default(), 3).unwrap();
        // Jittered strata: 48 sites on a fully valid 64×48 image put exactly one site in every 8×8 block.
        let mut per_block = [0u32; 48];
        for &id in &s.sites {
            let (x, y) = g.xy(id);
            per_block[(y / 8) * 8 + x / 8] += 1;
        }
        assert!(per_block.iter().all(|&c| c == 1), "{per_block:?}");
    }
}
