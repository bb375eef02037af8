//! STAGE 4 timing (tests only, `#[ignore]`): every strategy on a 1920×1080 synthetic room with 120K caches.
//! Run with `cargo test --release --lib placement::timing -- --ignored --nocapture`. No assertions on time.

use std::time::Instant;

use glam::Vec3A;

use super::test_scenes::{self as ts, MaskOracle, Prim};
use super::{AdaptivePlacement, AdaptiveSampling, Discontinuity, ImageUniform, InitialPlacement, PlacementParams};
use super::{SpatialDirectional, ViewGuided};
use crate::gbuffer::GBuffer;

/// A room (floor, ceiling, three walls) with spheres, a staircase of boxes and a row of pillars: planes and
/// curved surfaces, depths from about 1 m to 14 m.
pub fn room(w: usize, h: usize) -> GBuffer {
    let mut prims = vec![
        Prim::Plane(Vec3A::ZERO, Vec3A::Y),
        Prim::Plane(Vec3A::new(0.0, 4.0, 0.0), -Vec3A::Y),
        Prim::Plane(Vec3A::new(0.0, 0.0, -14.0), Vec3A::Z),
        Prim::Plane(Vec3A::new(-5.0, 0.0, 0.0), Vec3A::X),
        Prim::Plane(Vec3A::new(5.0, 0.0, 0.0), -Vec3A::X),
    ];
    for i in 0..7 {
        let z = -2.0 - 1.6 * i as f32;
        prims.push(Prim::Sphere(Vec3A::new(-2.5 + 0.3 * i as f32, 0.6, z), 0.6));
        prims.push(Prim::Cuboid(Vec3A::new(3.0, 0.0, z - 0.8), Vec3A::new(4.2, 0.35 * (i + 1) as f32, z)));
        prims.push(Prim::Sphere(Vec3A::new(0.5 * i as f32 - 1.0, 2.8, z - 0.5), 0.25));
    }
    ts::cast(w, h, Vec3A::new(0.0, 1.7, 1.0), Vec3A::new(0.0, 1.2, -8.0), &prims, 24.0)
}

/// CPU seconds (user + system) this process has used so far, from /proc/self/stat (0 where unavailable).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let after = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<f64> = after.split_whitespace().map(|x| x.parse().unwrap_or(0.0)).collect();
    // Fields 14 and 15 (utime, stime) are the 12th and 13th after the ")".
    (f.get(11).copied().unwrap_or(0.0) + f.get(12).copied().unwrap_or(0.0)) / 100.0
}

/// Runs `f`, printing wall time and CPU time (CPU time is steadier on a shared machine).
fn time<T>(label: &str, f: impl FnOnce() -> T) -> T {
    let (t, c) = (Instant::now(), cpu_seconds());
    let out = f();
    eprintln!("{label:<34} {:>7.3} s wall {:>7.2} s cpu", t.elapsed().as_secs_f64(), cpu_seconds() - c);
    out
}

#[test]
#[ignore = "timing; run explicitly in release"]
fn placement_timings_at_1080p_with_120k_caches() {
    let g = time("G-buffer (synthetic room)", || room(1920, 1080));
    let (lo, hi) = g.depth_range;
    eprintln!("{} valid pixels, depth {lo:.2}–{hi:.2} m, {} threads", g.valid_count, rayon::current_num_threads());
    let p = PlacementParams::default();
    let total = 120_000;
    let n1 = ((1.0 - p.ratio as f64) * total as f64).round() as usize;
    let im = time("IM 120K", || ImageUniform.place(&g, total, &p, 1).unwrap());
    assert_eq!(im.sites.len(), total);
    let sd = time("SD 120K (T search)", || SpatialDirectional.place(&g, total, &p, 1).unwrap());
    eprintln!(
        "  T = {:?}, {} iterations, {} clusters found",
        sd.info.sd_threshold, sd.info.search_iterations, sd.info.clusters_found
    );
    let vgc = time("VGC 120K (σ_s search)", || ViewGuided::default().place(&g, total, &p, 1).unwrap());
    eprintln!(
        "  σ_s = {:?}, σ_a = {:?}, {} iterations, {} clusters found",
        vgc.info.sigma_s, vgc.info.sigma_a_deg, vgc.info.search_iterations, vgc.info.clusters_found
    );
    let vgc1 = time("VGC 102K (two-stage share)", || ViewGuided { two_stage: true }.place(&g, n1, &p, 1).unwrap());
    let mut oracle = MaskOracle::new(&g, &vgc1.sites);
    let info = time("DGS 18K (map + draws, mock masks)", || {
        Discontinuity::default().place(&g, &vgc1, &mut oracle, total - n1, &p, 1).unwrap()
    });
    assert_eq!(info.added, total - n1);
    let mut oracle = MaskOracle::new(&g, &vgc1.sites);
    let info = time("AS 18K after VGC (mock masks)", || {
        AdaptiveSampling.place(&g, &vgc1, &mut oracle, total - n1, &p, 1).unwrap()
    });
    eprintln!("  {} rounds", info.rounds);
}

#[test]
#[ignore = "timing; run explicitly in release"]
fn selection_timings() {
    use crate::cache::{CacheIndex, LookupParams};
    let g = room(1920, 1080);
    let valid: Vec<(usize, Vec3A, Vec3A)> =
        g.points.iter().enumerate().filter_map(|(i, sp)| sp.map(|sp| (i, sp.p, sp.n))).collect();
    let caches: Vec<(Vec3A, Vec3A)> = valid.iter().step_by(17).map(|v| (v.1, v.2)).collect();
    let index = CacheIndex::new(&caches, LookupParams::default(), 0.5 / 24.0);
    eprintln!("{} caches", caches.len());
    let rows: usize = std::env::var("SEL_ROWS").ok().and_then(|v| v.parse().ok()).unwrap_or(200);
    let only: Option<usize> = std::env::var("SEL_TILE").ok().and_then(|v| v.parse().ok());
    let t = Instant::now();
    let mut out = Vec::new();
    let mut sum = 0usize;
    for y in 0..if only.is_some_and(|t| t != 1) { 0 } else { rows } {
        for x in 0..1920 {
            if let Some(sp) = g.points[y * 1920 + x] {
                index.select(sp.p, sp.n, &mut out);
                sum += out.len();
            }
        }
    }
    eprintln!("single: {:.3} µs/px ({sum})", t.elapsed().as_secs_f64() * 1e6 / (rows * 1920) as f64);
    for tile in [2usize, 4, 8, 16].into_iter().filter(|&t| only.is_none_or(|o| o == t)) {
        let t = Instant::now();
        let mut sum = 0usize;
        let mut q = Vec::new();
        for ty in (0..rows).step_by(tile) {
            for tx in (0..1920).step_by(tile) {
                q.clear();
                for y in ty..ty + tile {
                    for x in tx..tx + tile {
                        if let Some(sp) = g.points[y * 1920 + x] {
                            q.push((sp.p, sp.n));
                        }
                    }
                }
                index.select_group(&q, |_, o| sum += o.len());
            }
        }
        eprintln!("tile {tile}: {:.3} µs/px ({sum})", t.elapsed().as_secs_f64() * 1e6 / (rows * 1920) as f64);
    }
}
