//! Behaviour of the `importancecache` integrator (issue 12): unbiased against its own exact many-light
//! reference (per image region, over 64 seeds, for the combined techniques, each technique alone where
//! its support covers the light, α-max, and the baselines), the conservative technique keeping occluded
//! VPLs reachable (and the test able to see the bias without it), the VPL solution against pbrt-v3's own
//! path tracer, deterministic VPLs, the memory bound, bad input, and finite images where methods fail.
//!
//! Why the unbiasedness test is exact: with the VPL set fixed (`vplseed`), the reference (`placement none`)
//! is the exact sum Σ_j I_j at every sub-pixel sample, and the cached estimator draws one VPL per technique
//! and weights it by MIS over the densities it was drawn with, so its expectation over the shading
//! randomness equals that sum whatever the caches hold, as long as some technique can draw every VPL that
//! contributes. Different seeds also move the caches, which changes nothing in expectation.

mod common;

use std::path::{Path, PathBuf};

use cachert::Warnings;
use cachert::image::Image;
use cachert::integrator::{RenderOutput, RenderSettings, render};
use cachert::scene::{LoadOptions, LoadedScene, load, load_str};

/// Seeds per unbiasedness check.
const SEEDS: u64 = 64;

fn loaded_text(text: &str) -> LoadedScene {
    load_str(text, Path::new("inline.pbrt"), LoadOptions::default()).unwrap_or_else(|e| panic!("load: {e}"))
}

fn render_with(
    loaded: &LoadedScene,
    set: &[(&str, &str)],
    seed: u64,
    threads: Option<usize>,
) -> cachert::Result<RenderOutput> {
    // The clamp's compensation is off unless a test sets it: a second, stochastic term in the reference
    // (`placement none`) would make it inexact, and these tests are about how the VPL sum is estimated
    // (the compensation has its own test, `the_light_the_clamp_removes_is_put_back`).
    let off = [("compensate", "0")];
    let settings = RenderSettings {
        integrator: Some("importancecache".into()),
        set: off.iter().chain(set).map(|(k, v)| (k.to_string(), v.to_string())).collect(),
        seed,
        threads,
        ..Default::default()
    };
    render(&loaded.scene, loaded.integrator.as_ref(), &settings, &mut Warnings::default())
}

fn image(loaded: &LoadedScene, set: &[(&str, &str)], seed: u64) -> Image {
    render_with(loaded, set, seed, None).unwrap_or_else(|e| panic!("{set:?}: {e}")).image
}

/// The end of the test scenes lit from above: a 1×1 downward-facing area lamp at height 2.8, then `WorldEnd`.
const LAMP: &str = "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [6 6 6]\n\
     Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-0.5 2.8 -0.5  0.5 2.8 -0.5  0.5 2.8 0.5  -0.5 2.8 0.5]\n\
     AttributeEnd\nWorldEnd\n";

/// A floor and a back wall under a downward-facing square lamp, nothing between them: every VPL that
/// can light a point of the floor can light every point of the floor (and the same for the wall), so each
/// technique alone covers the light it must estimate.
fn open_corner(res: u32) -> String {
    format!(
        "LookAt 0 2.5 -4  0 0.8 0.5  0 1 0\nCamera \"perspective\" \"float fov\" 55\n\
         Film \"image\" \"integer xresolution\" {res} \"integer yresolution\" {res}\n\
         WorldBegin\nMaterial \"matte\" \"rgb Kd\" [0.6 0.5 0.4]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-2 0 -2  2 0 -2  2 0 2  -2 0 2]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-2 0 2  2 0 2  2 3 2  -2 3 2]\n\
         {LAMP}"
    )
}

/// A floor under a point light with a floating square occluder: part of the floor is in shadow, so a cache
/// there has zero F density for the light's emission VPLs (all at the light) that light points just
/// outside the shadow.
fn shadowed_floor(res: u32) -> String {
    format!(
        "LookAt 0 4 -3  0 0 0.3  0 1 0\nCamera \"perspective\" \"float fov\" 60\n\
         Film \"image\" \"integer xresolution\" {res} \"integer yresolution\" {res}\n\
         WorldBegin\nLightSource \"point\" \"point from\" [0 3 0] \"rgb I\" [10 10 10]\n\
         Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-3 0 -3  3 0 -3  3 0 3  -3 0 3]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 2 1 0 3 2] \"point P\" [-0.7 1.5 -0.7  0.7 1.5 -0.7  0.7 1.5 0.7  -0.7 1.5 0.7]\n\
         WorldEnd\n"
    )
}

/// A mirror ahead of the camera that shows a matte wall behind it: the camera sees the wall only in the
/// mirror, so no cache (caches sit where the camera looks first) serves it, and importance caching shades it
/// by power sampling with `fallbackdraws` draws. The floor the camera sees directly is shaded from caches.
fn mirror_and_a_wall_behind(res: u32) -> String {
    format!(
        "LookAt 0 1.2 -1  0 0.9 2  0 1 0\nCamera \"perspective\" \"float fov\" 60\n\
         Film \"image\" \"integer xresolution\" {res} \"integer yresolution\" {res}\n\
         WorldBegin\nMaterial \"matte\" \"rgb Kd\" [0.6 0.5 0.4]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-4 0 -4  4 0 -4  4 0 2  -4 0 2]\n\
         Material \"matte\" \"rgb Kd\" [0.2 0.5 0.7]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 2 1 0 3 2] \"point P\" [-4 0 -3  4 0 -3  4 3 -3  -4 3 -3]\n\
         Material \"mirror\"\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-4 0.5 2  4 0.5 2  4 3 2  -4 3 2]\n\
         {LAMP}"
    )
}

/// Per-quadrant means of `im` (channels averaged).
fn quadrants(im: &Image) -> [f64; 4] {
    let (w, h) = (im.width, im.height);
    let mut sum = [0.0f64; 4];
    let mut n = [0usize; 4];
    for y in 0..h {
        for x in 0..w {
            let q = (x * 2 / w) + 2 * (y * 2 / h);
            let c = im.get(x, y);
            sum[q] += (c[0] + c[1] + c[2]) as f64 / 3.0;
            n[q] += 1;
        }
    }
    [0, 1, 2, 3].map(|q| sum[q] / n[q] as f64)
}

/// The largest |mean − reference| / standard error over the quadrants, for `SEEDS` renders with `set`
/// (over `RETEST` more when that is beyond 3).
fn worst_z(loaded: &LoadedScene, set: &[(&str, &str)], reference: &[f64; 4]) -> f64 {
    let z = z_over(loaded, set, reference, 100, SEEDS);
    if z <= 3.0 {
        return z;
    }
    // This file checks 31 settings of 4 quadrants each: unbiased estimators land beyond 3 standard errors
    // in one of them with a probability of about 1 − 0.9973^124 ≈ 29 % (it happened once: `u` alone on the
    // open corner, 3.27 with seeds 100–163, 1.25 at most over 1024 seeds). A setting with a quadrant beyond
    // 3 is checked again over RETEST fresh seeds, where a real bias shows twice as many standard errors and
    // a chance excursion does not come back; the bar, 3 standard errors, stays.
    eprintln!("  {set:?}: {z:.2} standard errors over {SEEDS} seeds; checked again over {RETEST} more");
    z_over(loaded, set, reference, 10_000, RETEST)
}

/// Seeds of [`worst_z`]'s second look.
const RETEST: u64 = 256;

/// The largest |mean − reference| / standard error over the four quadrants, over `n` seeds from `first`.
fn z_over(loaded: &LoadedScene, set: &[(&str, &str)], reference: &[f64; 4], first: u64, n: u64) -> f64 {
    let per_seed: Vec<[f64; 4]> = (0..n).map(|s| quadrants(&image(loaded, set, first + s))).collect();
    let mut worst = 0.0f64;
    for q in 0..4 {
        let xs: Vec<f64> = per_seed.iter().map(|r| r[q]).collect();
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (xs.len() - 1) as f64;
        let se = (var / xs.len() as f64).sqrt();
        // A quadrant the estimator gets exactly (no light) has se = 0 and must match to rounding.
        let z = if se > 0.0 {
            (mean - reference[q]).abs() / se
        } else if (mean - reference[q]).abs() <= 1e-6 * reference[q].abs().max(1e-6) {
            0.0
        } else {
            f64::INFINITY
        };
        eprintln!("  {set:?} quadrant {q}: mean {mean:.6} ref {:.6} se {se:.2e} z {z:.2}", reference[q]);
        worst = worst.max(z);
    }
    worst
}

fn reference(loaded: &LoadedScene, base: &[(&str, &str)]) -> [f64; 4] {
    let mut set = base.to_vec();
    set.push(("placement", "none"));
    quadrants(&image(loaded, &set, 1))
}

/// A metal floor of `roughness` and a matte back wall under a lamp. Near a mirror (0.003) the floor's lobe turns
/// the lamp's and the wall's VPLs into spikes, and the VPLs on the floor send narrow beams onto the wall —
/// both halves of the near-specular split.
fn metal_floor(res: u32, roughness: f32) -> String {
    format!(
        "LookAt 0 1.5 -4  0 0.8 0.5  0 1 0\nCamera \"perspective\" \"float fov\" 55\n\
         Film \"image\" \"integer xresolution\" {res} \"integer yresolution\" {res}\n\
         WorldBegin\nMaterial \"matte\" \"rgb Kd\" [0.6 0.5 0.4]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-2 0 2  2 0 2  2 3 2  -2 3 2]\n\
         AttributeBegin\nMaterial \"metal\" \"float roughness\" {roughness} \"bool remaproughness\" \"false\"\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-2 0 -2  2 0 -2  2 0 2  -2 0 2]\n\
         AttributeEnd\n\
         {LAMP}"
    )
}

/// The shipped room at 24×18: occluders and an area light, small enough for 64 seeds.
fn small_room() -> LoadedScene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/room.pbrt");
    load(&path, LoadOptions { resolution: Some([24, 18]), ..Default::default() }).unwrap()
}

/// The settings the room's tests share.
const ROOM_BASE: [(&str, &str); 3] = [("vpls", "256"), ("caches", "16"), ("subpixels", "4")];

/// Per-quadrant standard deviation of `n` renders with `set` (seeds 500, 501, …).
fn quadrant_sd(loaded: &LoadedScene, set: &[(&str, &str)], n: u64) -> [f64; 4] {
    let per_seed: Vec<[f64; 4]> = (0..n).map(|s| quadrants(&image(loaded, set, 500 + s))).collect();
    [0, 1, 2, 3].map(|q| {
        let mean = per_seed.iter().map(|r| r[q]).sum::<f64>() / n as f64;
        (per_seed.iter().map(|r| (r[q] - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
    })
}

/// Every `extra` setting added to `base` is within 3 standard errors of reference `r` in each quadrant.
fn assert_each_unbiased(loaded: &LoadedScene, base: &[(&str, &str)], extras: &[[(&str, &str); 2]], r: &[f64; 4]) {
    for extra in extras {
        let mut set = base.to_vec();
        set.extend(extra.iter().copied());
        let z = worst_z(loaded, &set, r);
        assert!(z <= 3.0, "{extra:?}: a quadrant is {z:.2} standard errors from the reference");
    }
}

/// Summed quadrant spread over 16 seeds of `base` + `extra` with the split setting `on`, divided by the same
/// with `off`.
fn spread_ratio(
    loaded: &LoadedScene,
    base: &[(&str, &str)],
    extra: (&str, &str),
    on: (&str, &str),
    off: (&str, &str),
) -> f64 {
    let with = |split| {
        let mut set = base.to_vec();
        set.extend([extra, split]);
        quadrant_sd(loaded, &set, 16)
    };
    let (a, b) = (with(on), with(off));
    eprintln!("  {extra:?}: sd with {on:?} {a:?}, with {off:?} {b:?}");
    a.iter().sum::<f64>() / b.iter().sum::<f64>()
}

/// The metal floor of `roughness` at 24×24 and the small settings its tests share, once every `extras`
/// setting has been checked unbiased there.
fn unbiased_on_a_metal_floor(
    roughness: f32,
    extras: &[[(&str, &str); 2]],
) -> (LoadedScene, [(&'static str, &'static str); 3]) {
    let loaded = loaded_text(&metal_floor(24, roughness));
    let base = [("vpls", "256"), ("caches", "12"), ("subpixels", "4")];
    let r = reference(&loaded, &base);
    assert_each_unbiased(&loaded, &base, extras, &r);
    (loaded, base)
}

#[test]
fn the_near_specular_split_is_unbiased_and_takes_out_the_spikes() {
    let (loaded, base) = unbiased_on_a_metal_floor(
        0.003,
        &[
            [("placement", "vgc+dgs"), ("mis", "balance")],
            [("placement", "im"), ("mis", "alphamax")],
            [("sampling", "power"), ("draws", "4")],
            [("sampling", "uniform"), ("draws", "4")],
        ],
    );
    // The split is what takes the spikes out: without it (splitcone 0) the same estimators spread wider.
    for extra in [("placement", "vgc+dgs"), ("sampling", "power")] {
        let ratio = spread_ratio(&loaded, &base, extra, ("splitcone", "10"), ("splitcone", "0"));
        assert!(ratio < 0.5, "{extra:?}: the split should at least halve the spread (ratio {ratio:.3})");
    }
}

#[test]
fn the_near_split_is_unbiased_and_takes_out_the_near_vpls_spikes() {
    // Floor meets wall: VPLs on either side of the corner lie within a few d_c of receivers on the other.
    // Balls of 8 d_c hold enough of the light for a wrong split to show: with the ball's members not
    // excluded from the other draws (counted twice) the worst quadrant is 7.7–8.7 standard errors off;
    // at 3 d_c it was only 2.9, so a smaller ball could not catch that. The default (1) is run too.
    let loaded = loaded_text(&open_corner(24));
    let base = [("vpls", "256"), ("caches", "12"), ("subpixels", "4"), ("splitcone", "0")];
    let r = reference(&loaded, &base);
    assert_each_unbiased(
        &loaded,
        &base,
        &[
            [("placement", "vgc+dgs"), ("splitnear", "8")],
            [("placement", "im"), ("splitnear", "8")],
            [("sampling", "power"), ("splitnear", "8")],
            [("sampling", "uniform"), ("splitnear", "8")],
            [("placement", "vgc+dgs"), ("splitnear", "1")],
        ],
        &r,
    );
    // Power sampling's weight is Σflux·f/d²: the near VPLs are its spikes, and the ball takes them out
    // (measured: the summed quadrant spread falls to 0.75 of its value without). The cached estimator's
    // spread here hardly moves (0.94): its caches, on the same two planes, already give those VPLs density;
    // the bathroom's bevels, where they do not, are in experiments/notes/importance.md. Measured with
    // independent draws: stratified ones already spread power sampling's draws of a pixel over those VPLs,
    // and the split's share of the narrowing falls (0.88).
    let mut independent = base.to_vec();
    independent.push(("stratify", "false"));
    let ratio = spread_ratio(&loaded, &independent, ("sampling", "power"), ("splitnear", "3"), ("splitnear", "0"));
    assert!(ratio < 0.85, "power: the near split should narrow the spread (ratio {ratio:.3})");
}

#[test]
fn cached_estimates_are_unbiased_for_every_technique_alone_and_combined_where_each_covers_the_light() {
    let loaded = loaded_text(&open_corner(24));
    let base = [("vpls", "256"), ("caches", "12"), ("subpixels", "4")];
    let r = reference(&loaded, &base);
    assert!(r.iter().all(|&v| v > 0.0), "{r:?}");
    for (dist, mis) in [
        ("f", "balance"),
        ("u", "balance"),
        ("b", "balance"),
        ("c", "balance"),
        ("fubc", "balance"),
        ("fubc", "alphamax"),
        ("ffubcc", "balance"),
        ("ffubcc", "alphamax"),
    ] {
        let mut set = base.to_vec();
        set.extend([("distributions", dist), ("mis", mis), ("placement", "vgc+dgs")]);
        let z = worst_z(&loaded, &set, &r);
        assert!(z <= 3.0, "{dist} {mis}: a quadrant is {z:.2} standard errors from the reference");
    }
}

#[test]
fn every_placement_and_both_heuristics_are_unbiased_with_occlusion_on_the_shipped_room() {
    let (loaded, base) = (small_room(), ROOM_BASE);
    let r = reference(&loaded, &base);
    for (placement, mis) in [("vgc+dgs", "balance"), ("vgc+dgs", "alphamax"), ("im", "balance"), ("sd+as", "balance")] {
        let mut set = base.to_vec();
        set.extend([("placement", placement), ("mis", mis)]);
        let z = worst_z(&loaded, &set, &r);
        assert!(z <= 3.0, "{placement} {mis}: a quadrant is {z:.2} standard errors from the reference");
    }
    for sampling in ["uniform", "power"] {
        let mut set = base.to_vec();
        set.push(("sampling", sampling));
        let z = worst_z(&loaded, &set, &r);
        assert!(z <= 3.0, "sampling {sampling}: a quadrant is {z:.2} standard errors from the reference");
    }
}

#[test]
fn draws_stratified_across_a_pixels_samples_stay_unbiased_and_narrow_the_spread() {
    // `stratify` (on by default, so the tests above check it) spreads the draws of a pixel's four sub-pixel
    // samples over the distributions; each draw alone is as before, so off is unbiased too, and on narrows
    // the spread of the image over seeds — on the open corner, whose caches all see the same light; on the
    // room at 96×72 the cached estimate's spread did not move (its 16 caches differ too much for the
    // positions in their distributions to mean the same VPLs), which the 640×360 scenes of
    // experiments/notes/importance.md do not share.
    let (loaded, base) = (small_room(), ROOM_BASE);
    let r = reference(&loaded, &base);
    assert_each_unbiased(
        &loaded,
        &base,
        &[[("placement", "vgc+dgs"), ("stratify", "false")], [("sampling", "power"), ("stratify", "false")]],
        &r,
    );
    let loaded = loaded_text(&open_corner(48));
    // The pixels' own spread (root mean per-pixel variance over 16 seeds): the quadrants' would mix in
    // the spread of where the caches go, which stratified draws do not touch.
    let pixel_spread = |extra: (&str, &str), stratify: &str| {
        let mut set = base.to_vec();
        set.extend([extra, ("stratify", stratify)]);
        let images: Vec<Image> = (0..16).map(|s| image(&loaded, &set, 500 + s)).collect();
        let n = images.len() as f64;
        let mut sum = 0.0;
        for p in 0..images[0].pixels.len() {
            for c in 0..3 {
                let xs = images.iter().map(|im| im.pixels[p][c] as f64);
                let mean = xs.clone().sum::<f64>() / n;
                sum += xs.map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
            }
        }
        (sum / (3 * images[0].pixels.len()) as f64).sqrt()
    };
    for extra in [("placement", "vgc+dgs"), ("sampling", "uniform"), ("sampling", "power")] {
        let (on, off) = (pixel_spread(extra, "true"), pixel_spread(extra, "false"));
        eprintln!("  {extra:?}: pixel spread stratified {on:.3e}, independent {off:.3e}");
        // Measured: 0.92 of the independent spread for importance caching, 0.98 for power sampling (whose
        // draws concentrate on the lamp's few strong VPLs), 0.61 for uniform sampling.
        let bound = if extra.1 == "uniform" { 0.8 } else { 1.0 };
        assert!(on < bound * off, "{extra:?}: stratified draws should narrow the spread ({on:.3e} vs {off:.3e})");
    }
}

#[test]
fn the_lobe_technique_is_unbiased_and_narrows_a_glossy_floors_spread() {
    // A metal floor of roughness 0.1: its lobe (about 24° wide) is wider than the split's 10° cones, so the
    // lobe technique G draws there, in proportion to flux among the VPL clusters the lobe's cone meets.
    let (loaded, base) = unbiased_on_a_metal_floor(
        0.1,
        &[
            [("placement", "vgc+dgs"), ("mis", "balance")],
            [("placement", "im"), ("mis", "alphamax")],
            [("placement", "sd+as"), ("distributions", "fcg")],
        ],
    );
    let ratio =
        spread_ratio(&loaded, &base, ("placement", "vgc+dgs"), ("distributions", "fubcg"), ("distributions", "fubc"));
    // Measured: 0.85 (the floor's quadrants 0.78 and 0.92; the wall's, where G never draws, unchanged).
    assert!(ratio < 0.95, "the lobe technique should narrow the spread (ratio {ratio:.3})");
}

#[test]
fn shadow_rays_shared_in_runs_keep_the_estimate_unbiased_and_trace_fewer_rays() {
    // A cache traces only the ends of a run of VPLs close together as it sees them (`visangle`); at 45° the
    // runs are long and straddle the room's occluders, so some VPLs are taken as visible where they are
    // not. F is then a different density, but the one sampled: the estimate stays unbiased.
    let loaded = small_room();
    let base = [ROOM_BASE[0], ROOM_BASE[1], ROOM_BASE[2], ("placement", "vgc+dgs")];
    let r = reference(&loaded, &base);
    let rays = |angle: &str| {
        let mut set = base.to_vec();
        set.push(("visangle", angle));
        let out = render_with(&loaded, &set, 1, None).unwrap();
        let c = out.cache.unwrap();
        assert_eq!(c.settings["visangle"], angle.parse::<f64>().unwrap());
        (c.stats.cache_rays.shadow, out.image.pixels)
    };
    let (exact, exact_image) = rays("0");
    let (default, _) = rays("10");
    let (wide, wide_image) = rays("45");
    eprintln!("shadow rays: 45° {wide}, 10° {default}, 0° {exact}");
    assert!(wide < default && default < exact, "shadow rays: 45° {wide}, 10° {default}, 0° {exact}");
    assert_ne!(wide_image, exact_image, "the shared rays should change F, and so the draws");
    let mut set = base.to_vec();
    set.push(("visangle", "45"));
    let z = worst_z(&loaded, &set, &r);
    assert!(z <= 3.0, "visangle 45: a quadrant is {z:.2} standard errors from the reference");
}

#[test]
fn the_conservative_technique_keeps_vpls_occluded_at_the_caches_reachable() {
    // Few caches over a floor partly in shadow, each sample served by its nearest cache alone (M = 1): a
    // shadowed cache gives the light's VPLs zero F density, yet it serves lit points at the shadow's edge.
    // F with C is unbiased; F alone loses their light, and the test must see it.
    let loaded = loaded_text(&shadowed_floor(24));
    let base =
        [("vpls", "64"), ("vpldepth", "1"), ("caches", "12"), ("M", "1"), ("subpixels", "4"), ("placement", "im")];
    let r = reference(&loaded, &base);
    let mut with_c = base.to_vec();
    with_c.push(("distributions", "fc"));
    let z = worst_z(&loaded, &with_c, &r);
    assert!(z <= 3.0, "F+C: a quadrant is {z:.2} standard errors from the reference");
    let mut alone = base.to_vec();
    alone.push(("distributions", "f"));
    let z = worst_z(&loaded, &alone, &r);
    // Measured: the quadrants 11–19 % low, 4.4–6.4 standard errors.
    assert!(z > 4.0, "F alone should lose the light of VPLs occluded at its caches (worst z {z:.2})");
}

/// The shared scenes must be here: fails, with the reason, where they are absent (outside CI the tests that
/// need them print a `skipped` line and pass; under CI they fail too).
#[test]
fn shared_scenes_present() {
    common::assert_shared_scenes_present();
}

#[test]
fn the_vpl_solution_matches_pbrt_v3_path_on_the_cornell_box() {
    // pbrt-v3 `path` maxdepth 5 = a camera vertex plus light paths of up to 4 surface vertices. Without the
    // distance clamp the VPL solution is unbiased for it, but heavy-tailed (1/d² between VPLs and receivers
    // near the box's corners), so small VPL sets land low more often than high. Compared off the light
    // (pixels whose 3×3 neighbourhood in the 8×-downsampled reference is below 1) at 32², one sub-pixel
    // sample: over the whole image the emitter's edge pixels would dominate the mean's noise. Measured: 8
    // VPL seeds of 8192 VPLs, −0.37 % (seeds within ±1.3 %, standard error of the mean 0.27 %); 4 seeds of
    // 16384 at 64², −0.10 %. A light path one vertex too short or too long moves the mean by −2.7 % / +2.2 %.
    let Some(dir) = common::shared_scenes() else { return };
    let dir = dir.join("bitterli-cornell-box-v3");
    let reference = common::downsample(&cachert::image::read(&dir.join("path-ref.pfm")).unwrap(), 8);
    let (w, h) = (reference.width, reference.height);
    let bright = |x: usize, y: usize| reference.get(x, y).iter().any(|&v| v >= 1.0);
    let off_light = |x: usize, y: usize| {
        (x.saturating_sub(1)..(x + 2).min(w)).all(|i| (y.saturating_sub(1)..(y + 2).min(h)).all(|j| !bright(i, j)))
    };
    let masked_mean = |im: &Image| {
        let (mut s, mut n) = (0.0f64, 0usize);
        for y in 0..h {
            for x in (0..w).filter(|&x| off_light(x, y)) {
                s += im.get(x, y).iter().map(|&v| v as f64).sum::<f64>() / 3.0;
                n += 1;
            }
        }
        s / n as f64
    };
    let loaded =
        load(&dir.join("path-ref.pbrt"), LoadOptions { resolution: Some([w as u32, h as u32]), ..Default::default() })
            .unwrap();
    let mut means = Vec::new();
    for seed in 0..8 {
        let s = seed.to_string();
        let set = [
            ("placement", "none"),
            ("vpls", "8192"),
            ("vpldepth", "4"),
            ("clamp", "0"),
            ("subpixels", "1"),
            ("vplseed", &s),
        ];
        means.push(masked_mean(&image(&loaded, &set, 1)));
    }
    let ours = means.iter().sum::<f64>() / means.len() as f64;
    let theirs = masked_mean(&reference);
    eprintln!(
        "VPL solution off the light {means:?}: {ours:.5} vs pbrt-v3 path {theirs:.5} ({:+.2} %)",
        100.0 * (ours / theirs - 1.0)
    );
    assert!((ours / theirs - 1.0).abs() < 0.01, "{ours} vs {theirs}");
    // The clamp only removes energy.
    let set = [("placement", "none"), ("vpls", "2048"), ("vpldepth", "4"), ("subpixels", "1")];
    let clamped = masked_mean(&image(&loaded, &set, 1));
    assert!(clamped < means[0], "{clamped} vs {}", means[0]);
}

#[test]
fn vpls_and_images_are_deterministic_per_seed_and_thread_count() {
    let loaded = loaded_text(&open_corner(20));
    let set = [("vpls", "300"), ("caches", "20")];
    let a = render_with(&loaded, &set, 5, Some(1)).unwrap().image;
    let b = render_with(&loaded, &set, 5, Some(2)).unwrap().image;
    assert_eq!(a.pixels, b.pixels, "thread count changed the image");
    let c = render_with(&loaded, &set, 6, Some(2)).unwrap().image;
    assert_ne!(a.pixels, c.pixels, "the seed should move the caches and draws");
    // The reference depends on the VPL seed only.
    let none = [("vpls", "300"), ("placement", "none")];
    let r1 = render_with(&loaded, &none, 5, Some(2)).unwrap().image;
    let r2 = render_with(&loaded, &none, 6, Some(1)).unwrap().image;
    assert_eq!(r1.pixels, r2.pixels);
    let other = [("vpls", "300"), ("placement", "none"), ("vplseed", "3")];
    assert_ne!(r1.pixels, render_with(&loaded, &other, 5, None).unwrap().image.pixels);
}

#[test]
fn stats_report_the_records_and_geometry_free_dgs() {
    let loaded = loaded_text(&open_corner(24));
    let out = render_with(&loaded, &[("vpls", "1000"), ("caches", "30")], 1, None).unwrap();
    let c = out.cache.unwrap();
    assert_eq!(c.stats.total_caches, 30);
    // Placing: F and U, about one byte per VPL each; shading: F, U and B.
    let per_cache = c.stats.record_bytes as f64 / 30.0;
    let kept = c.stats.record_bytes_kept as f64 / 30.0;
    assert!(per_cache > 2000.0 && per_cache < 2800.0, "{per_cache}");
    assert!(kept > 3000.0 && kept < 4000.0, "{kept}");
    assert_eq!(c.settings["vpls"], 1000);
    assert_eq!(c.settings["distributions"], "fubcg");
    // Eight draws per letter by default; the baselines draw as many as F, U, B and C together; the caches
    // learn their shares, halving U and B up to twice (`learnshares`).
    assert_eq!(c.settings["lightsamples"], 8);
    assert_eq!(c.settings["draws"], 32);
    assert_eq!(c.settings["learnshares"], 2);
    assert_eq!(c.settings["sharelevel"], "mean");
    // A count after a letter repeats it: the same render as the letters spelled out.
    let with = |d: &str, l: &str| {
        let set = [("vpls", "1000"), ("caches", "30"), ("distributions", d), ("learnshares", l)];
        render_with(&loaded, &set, 1, None).unwrap().image.pixels
    };
    assert_eq!(with("f2ubcg", "2"), with("ffubcg", "2"));
    // The learnt shares move the draws; without them the shares are those of `distributions`.
    assert_eq!(with("fubcg", "2"), out.image.pixels);
    assert_ne!(with("fubcg", "0"), out.image.pixels);
    // A shading point takes the mean of its caches' levels by default; `sharelevel min` the least, which only
    // moves draws back to U and B (more of them where a cache near it kept its defence).
    let min = render_with(&loaded, &[("vpls", "1000"), ("caches", "30"), ("sharelevel", "min")], 1, None).unwrap();
    assert_ne!(min.image.pixels, out.image.pixels);
    assert_eq!(min.cache.unwrap().settings["sharelevel"], "min");
    // What the scene gave beside what was asked: every VPL here, from fewer light paths (a path leaves
    // several); making them is a stage of its own, inside the total.
    assert_eq!(c.stats.prepared["vpls_generated"], 1000);
    let paths = c.stats.prepared["light_paths"].as_u64().unwrap();
    assert!(paths > 0 && paths < 1000, "{paths}");
    assert!(c.stats.times.prepare > 0.0 && c.stats.times.prepare < c.stats.times.total);
    // vgc+dgs leaves out the geometry term for importance caching: it places exactly as the diff-only
    // ablation, and not as the geometry-only one.
    let placed = |p: &str| {
        let c = render_with(&loaded, &[("vpls", "1000"), ("caches", "30"), ("placement", p)], 1, None)
            .unwrap()
            .cache
            .unwrap();
        (c.stage2.clone(), c.image.pixels.clone())
    };
    let dgs = placed("vgc+dgs");
    assert!(!dgs.0.is_empty());
    assert_eq!(dgs, placed("vgc+dgs:diff"));
    assert_ne!(dgs.0, placed("vgc+dgs:geom").0);
    let power = render_with(&loaded, &[("vpls", "1000"), ("sampling", "power")], 1, None).unwrap();
    let pc = power.cache.unwrap();
    assert_eq!(pc.stats.total_caches, 0);
    assert!(pc.stats.notes.iter().any(|n| n.contains("without caches")), "{:?}", pc.stats.notes);
}

#[test]
fn bad_parameters_and_absurd_budgets_are_clear_errors() {
    let loaded = loaded_text(&open_corner(8));
    for (k, v, want) in [
        ("vpls", "0", "between 1"),
        ("vpls", "1000000000000", "between 1"),
        ("distributions", "fx", "letters"),
        ("distributions", "f2x", "letters"),
        // Each letter draws `lightsamples` (8) times: 17 f's would be 136 draws of F, five g's 40 of G.
        ("distributions", "fffffffffffffffffu", "at most 64 times"),
        ("distributions", "f17u", "at most 64 times"),
        ("distributions", "fubcg5", "g: 16"),
        ("distributions", "f99999999999", "at most 64 times"),
        ("learnshares", "4", "between 0 and 3"),
        ("sharelevel", "max", "min"),
        ("lightsamples", "0", "between 1 and 16"),
        ("lightsamples", "17", "between 1 and 16"),
        ("distributions", "", "at least one"),
        ("stratify", "maybe", "stratify"),
        ("mis", "max", "alphamax"),
        ("sampling", "all", "power"),
        ("clamp", "-1", "≥ 0"),
        ("vpldepth", "-2", "between 0"),
        ("splitcone", "120", "between 0 and 90"),
        ("splitcone", "-1", "between 0 and 90"),
        ("splitnear", "1000", "between 0 and 100"),
        ("splitnear", "-0.5", "between 0 and 100"),
        ("visangle", "60", "between 0 and 45"),
        ("visangle", "-1", "between 0 and 45"),
        ("visangle", "nan", "between 0 and 45"),
    ] {
        let e = render_with(&loaded, &[(k, v)], 1, None).unwrap_err().to_string();
        assert!(e.contains(k) && e.contains(want), "{k}={v}: {e}");
        if v == "1000000000000" {
            assert!(e.contains("GiB"), "an absurd count says the memory it would need: {e}");
        }
    }
    // 64M VPLs: fine to ask for, but their records at 20 caches would not fit any machine of this kind.
    let e = render_with(&loaded, &[("vpls", "67108864"), ("caches", "64")], 1, None).unwrap_err().to_string();
    assert!(e.contains("GiB") && e.contains("available"), "{e}");
}

#[test]
fn failure_cases_give_finite_images() {
    // No lights: black, with a warning. Lights but nothing to deposit VPLs on (only the emitter): the
    // emission VPLs still light nothing, and the image is the emitter itself.
    let dark = "LookAt 0 0 -3 0 0 0 0 1 0\nCamera \"perspective\"\nFilm \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8\n\
                WorldBegin\nMaterial \"matte\"\nShape \"sphere\"\nWorldEnd\n";
    let out = render_with(&loaded_text(dark), &[("vpls", "50"), ("caches", "4")], 1, None).unwrap();
    assert!(out.image.pixels.iter().flatten().all(|&v| v == 0.0));
    assert_eq!(out.cache.unwrap().stats.prepared["vpls_generated"], 0, "the stats say no VPL was made");
    let lamp = "LookAt 0 0 -3 0 0 0 0 1 0\nCamera \"perspective\"\nFilm \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8\n\
                WorldBegin\nAreaLightSource \"diffuse\" \"rgb L\" [2 2 2]\nShape \"sphere\"\nWorldEnd\n";
    let out = render_with(&loaded_text(lamp), &[("vpls", "50"), ("caches", "4")], 1, None).unwrap();
    assert!(out.image.pixels.iter().flatten().all(|&v| v.is_finite()));
    assert!(common::mean(&out.image) > 0.0);
    // Every VPL behind the camera (the light faces away from everything seen), budgets 1 and above the
    // pixel count, one VPL.
    let behind = "LookAt 0 2 -3 0 0 0 0 1 0\nCamera \"perspective\"\nFilm \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8\n\
                  WorldBegin\nLightSource \"spot\" \"point from\" [0 1 -5] \"point to\" [0 1 -10] \"rgb I\" [5 5 5]\n\
                  Material \"matte\"\nShape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-2 0 -2 2 0 -2 2 0 2 -2 0 2]\nWorldEnd\n";
    for (vpls, caches) in [("100", "1"), ("100", "1000"), ("1", "4")] {
        let out = render_with(&loaded_text(behind), &[("vpls", vpls), ("caches", caches)], 1, None).unwrap();
        assert!(out.image.pixels.iter().flatten().all(|&v| v.is_finite() && v >= 0.0), "{vpls} {caches}");
    }
}

/// Inside a closed cube whose walls all emit `L` = 1 (both sides) and reflect with albedo ρ = 0.5, the
/// radiance toward the camera is the same everywhere: Σ_{k=0}^{D+1} ρ^k with light paths of D = `vpldepth`
/// surface vertices (the wall's emission, its reflection of the emission VPLs, and of each surface VPL).
/// The camera looks into a corner, where the distance clamp removes most.
fn furnace(res: u32) -> String {
    format!(
        "LookAt 0.5 0.5 0.5  -1 -1 -1  0 1 0\nCamera \"perspective\" \"float fov\" 70\n\
         Film \"image\" \"integer xresolution\" {res} \"integer yresolution\" {res}\n\
         WorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" \"true\"\n\
         Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n\
         Shape \"trianglemesh\" \"point P\" [-1 -1 -1  1 -1 -1  1 1 -1  -1 1 -1  -1 -1 1  1 -1 1  1 1 1  -1 1 1]\n\
         \"integer indices\" [0 1 2 0 2 3  4 6 5 4 7 6  0 4 5 0 5 1  3 2 6 3 6 7  0 3 7 0 7 4  1 5 6 1 6 2]\n\
         AttributeEnd\nWorldEnd\n"
    )
}

#[test]
fn the_light_the_clamp_removes_is_put_back() {
    // d_c = 0.2·L. Without compensation the corner loses what the VPLs nearer than d_c would give; with it
    // the image is the closed form up to the second-order loss (the clamp at the surface the compensation
    // ray finds) and the VPL set's noise. Measured (1024 VPLs, 8 VPL seeds, 16², 4 sub-pixel samples):
    // compensate 0: −4.90 %; compensate 4: −0.30 % (−1.04 % with one level of compensation, the
    // loss at the surface the ray finds left out).
    let loaded = loaded_text(&furnace(16));
    let expected: f64 = (0..=5).map(|k| 0.5f64.powi(k)).sum();
    let mean_over_seeds = |compensate: &str| {
        let means: Vec<f64> = (0..8)
            .map(|seed| {
                let s = seed.to_string();
                let set = [
                    ("placement", "none"),
                    ("vpls", "1024"),
                    ("vpldepth", "4"),
                    ("clamp", "0.2"),
                    ("compensate", compensate),
                    ("vplseed", &s),
                ];
                let im = image(&loaded, &set, seed);
                im.pixels.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3 * im.pixels.len()) as f64
            })
            .collect();
        means.iter().sum::<f64>() / means.len() as f64
    };
    let clamped = mean_over_seeds("0") / expected - 1.0;
    let compensated = mean_over_seeds("4") / expected - 1.0;
    eprintln!("furnace corner: clamped {:+.2} %, compensated {:+.2} %", 100.0 * clamped, 100.0 * compensated);
    assert!(clamped < -0.03, "the clamp must remove light here for the test to mean anything: {clamped}");
    assert!(compensated.abs() < 0.008, "{compensated}");
}

#[test]
fn vpls_on_a_mesh_with_shading_normals_reflect_as_pbrt_v3_does() {
    // Light paths from the lights carry importance: at a vertex with shading normals the light a VPL sends
    // on is f · |ω_in·n_s| · |ω_out·n_g| / |ω_in·n_g| (pbrt-v3's CorrectShadingNormal), not the radiance
    // BSDF's f · |ω_out·n_s|. The octahedron's shading normals lean up to 35° from its faces, and the light it
    // reflects onto the floor is a third of the image; the scene's `path` maxdepth 2 gives vpldepth 1.
    // Measured (16384 VPLs, vgc+dgs, 4 VPL seeds): −0.17 %; with the radiance BSDF (c15e6f4): −2.26 %.
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pbrt-v3/shading-normals");
    let reference = cachert::image::read(&dir.join("octahedron.pfm")).unwrap();
    let loaded = load(&dir.join("octahedron.pbrt"), LoadOptions::default()).unwrap();
    let mean = |im: &Image| im.pixels.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3 * im.pixels.len()) as f64;
    let ours: f64 = (0..4)
        .map(|seed| {
            let s = seed.to_string();
            let set = [("vpls", "16384"), ("compensate", "4"), ("vplseed", &s)];
            let out = render_with(&loaded, &set, seed, None).unwrap();
            assert_eq!(out.cache.as_ref().unwrap().settings["vpldepth"], 1, "the scene's path maxdepth 2");
            mean(&out.image)
        })
        .sum::<f64>()
        / 4.0;
    let dev = ours / mean(&reference) - 1.0;
    eprintln!("octahedron: importancecache {:+.2} % against pbrt-v3 path maxdepth 2", 100.0 * dev);
    assert!(dev.abs() < 0.01, "{dev}");
}

#[test]
fn a_wall_seen_only_in_a_mirror_is_shaded_by_the_fallback_draws_without_bias() {
    let loaded = loaded_text(&mirror_and_a_wall_behind(24));
    let base = [("vpls", "256"), ("caches", "12"), ("subpixels", "4")];
    let run = |extra: &[(&str, &str)]| {
        let set: Vec<_> = base.iter().chain(extra).copied().collect();
        render_with(&loaded, &set, 3, None).unwrap_or_else(|e| panic!("{extra:?}: {e}"))
    };
    // The wall is shaded by the fallback: vertices after the mirror that no cache serves.
    let default = run(&[]);
    let paths = default.cache.as_ref().unwrap().stats.camera_paths;
    assert!(paths.by_estimator > 100, "{paths:?}");
    // The default draws four times a baseline sample's 32 there, and the count is what `fallbackdraws` sets.
    let (four, once) = (run(&[("fallbackdraws", "128")]), run(&[("fallbackdraws", "32")]));
    assert_eq!(default.image.pixels, four.image.pixels);
    assert!(four.rays.shadow > once.rays.shadow, "{:?} {:?}", four.rays, once.rays);
    assert_ne!(four.image.pixels, once.image.pixels);
    // Unbiased for the same VPL sum, with the default draws and with few (each pair's second setting restates
    // the default `mis`: the helper takes two settings per case).
    let r = reference(&loaded, &base);
    assert_each_unbiased(
        &loaded,
        &base,
        &[[("fallbackdraws", "0"), ("mis", "balance")], [("fallbackdraws", "2"), ("mis", "balance")]],
        &r,
    );
}
