//! The per-pixel `directlighting` and `path` integrators against pbrt-v3's own images of the same scenes.
//!
//! The Cornell box references in ../shared/scenes/bitterli-cornell-box-v3 are 256×256 (box filter); we render
//! the same files at 128×128 (the camera is unchanged) and compare with the reference averaged over 2×2
//! blocks, which is the same estimator per pixel. The noise floor comes from two seeds of our own, scaled to
//! the reference's sample count (see `common::assert_matches_pbrt_single`).

mod common;

use std::path::Path;

use cachert::image;
use cachert::scene::{LoadOptions, load, load_str};
use common::{assert_matches_pbrt_single, downsample, render_loaded, settings, shared_scenes};

/// Renders `file` at `res` with `spp` samples and seeds 1 and 2, with `--set` overrides; returns both images.
fn two_seeds(file: &Path, res: [u32; 2], spp: u32, set: &[(&str, &str)]) -> (image::Image, image::Image) {
    let loaded = load(file, LoadOptions { resolution: Some(res), ..Default::default() })
        .unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    let render = |seed| {
        let mut s = settings(seed);
        s.spp = Some(spp);
        s.set = set.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        render_loaded(&loaded, &s).unwrap_or_else(|e| panic!("{}: {e}", file.display())).image
    };
    (render(1), render(2))
}

fn cornell(file: &str, ref_spp: u32, spp: u32, set: &[(&str, &str)], name: &str) {
    let Some(dir) = shared_scenes() else { return };
    let dir = dir.join("bitterli-cornell-box-v3");
    let reference = image::read(&dir.join(format!("{file}.pfm"))).expect("reference reads");
    let reference = downsample(&reference, 2);
    let (a, b) = two_seeds(&dir.join(format!("{file}.pbrt")), [128, 128], spp, set);
    assert_matches_pbrt_single(name, &a, &b, &reference, 4.0 * ref_spp as f64 / spp as f64, 0.01);
}

/// The shared scenes must be here: fails, with the reason, where they are absent (outside CI the tests that
/// need them print a `skipped` line and pass; under CI they fail too).
#[test]
fn shared_scenes_present() {
    common::assert_shared_scenes_present();
}

#[test]
fn cornell_directlighting_matches_pbrt_v3() {
    cornell("direct-ref", 1024, 16, &[], "cornell-direct");
}

#[test]
fn cornell_path_matches_pbrt_v3() {
    cornell("path-ref", 2048, 16, &[], "cornell-path");
}

/// The render options of one reference in tests/data/pbrt-v3/shading (see its README): the scene (relative
/// to ../shared/scenes), the integrator and its `--set` parameters, the resolution, pbrt-v3's spp, and the
/// text substitutions make.sh applied (files the scene names that are not in its repository).
struct Reference {
    name: &'static str,
    scene: &'static str,
    integrator: &'static str,
    set: &'static [(&'static str, &'static str)],
    res: [u32; 2],
    ref_spp: u32,
    subst: &'static [(&'static str, &'static str)],
}

const ENVMAP: &str = "\"../../bitterli-cornell-box-v3/path-ref.pfm\"";
const RENO: (&str, &str) = ("\"../../../pbrt-v3-scenes/sanmiguel/textures/RenoSuburb01_sm.exr\"", ENVMAP);
const WELLS: (&str, &str) = ("\"../../../pbrt-v3-scenes/dragon/textures/20060807_wells6_hd.exr\"", ENVMAP);
const DRAGON: (&str, &str) = (
    "Shape \"plymesh\" \"string filename\" \"../../../pbrt-v3-scenes/dragon/geometry/dragon_remeshed.ply\"",
    "Translate 0 60 0 Shape \"sphere\" \"float radius\" [60]",
);
const GOLD_ETA: (&str, &str) =
    ("\"spectrum eta\" \"../../../pbrt-v3-scenes/dragon/spds/Au.eta.spd\"", "\"rgb eta\" [0.143 0.374 1.442]");
const GOLD_K: (&str, &str) =
    ("\"spectrum k\" \"../../../pbrt-v3-scenes/dragon/spds/Au.k.spd\"", "\"rgb k\" [3.983 2.385 1.603]");
const LINES: (&str, &str) = ("\"../../../pbrt-v3-scenes/simple/textures/lines.png\"", "\"../images/checkerboard.png\"");

const DL: &[(&str, &str)] = &[("strategy", "all"), ("maxdepth", "5")];
const PATH: &[(&str, &str)] = &[("maxdepth", "5")];

/// Renders `r` with `spp` samples, seeds 1 and 2, and checks it against its pbrt-v3 reference.
fn check(r: &Reference, spp: u32, mean_tol: f64) {
    let Some(scenes) = shared_scenes() else { return };
    let data = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/pbrt-v3/shading"));
    let reference = image::read(&data.join(format!("{}.pfm", r.name))).expect("reference reads");
    let file = scenes.join(r.scene);
    let mut text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    for (from, to) in r.subst {
        assert!(text.contains(from), "{}: nothing to substitute for {from}", r.name);
        text = text.replace(from, to);
    }
    let opts = LoadOptions { resolution: Some(r.res), ..Default::default() };
    let loaded = load_str(&text, &file, opts).unwrap_or_else(|e| panic!("{}: {e}", r.name));
    let render = |seed| {
        let mut s = settings(seed);
        s.spp = Some(spp);
        s.integrator = Some(r.integrator.to_string());
        s.set = r.set.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        render_loaded(&loaded, &s).unwrap_or_else(|e| panic!("{}: {e}", r.name)).image
    };
    let (a, b) = (render(1), render(2));
    assert_matches_pbrt_single(r.name, &a, &b, &reference, r.ref_spp as f64 / spp as f64, mean_tol);
}

macro_rules! reference_tests {
    ($($test:ident: $name:literal, $scene:literal, $integrator:literal, $set:expr, $res:expr, $ref_spp:literal,
       $subst:expr, $spp:literal, $tol:literal;)*) => {$(
        #[test]
        fn $test() {
            check(
                &Reference {
                    name: $name,
                    scene: $scene,
                    integrator: $integrator,
                    set: $set,
                    res: $res,
                    ref_spp: $ref_spp,
                    subst: $subst,
                },
                $spp,
                $tol,
            );
        }
    )*};
}

reference_tests! {
    path_veach_mis: "path-veach-mis", "pbrtv3scenes-veach-mis/mis.pbrt", "path", PATH, [128, 96], 7500, &[], 64, 0.01;
    path_staircase2: "path-staircase2", "bitterli-staircase2/scene-v3.pbrt", "path", PATH, [128, 128], 2500, &[], 32, 0.01;
    direct_one_cornell: "direct-one-cornell", "bitterli-cornell-box-v3/scene.pbrt", "directlighting",
        &[("strategy", "one"), ("maxdepth", "5")], [128, 128], 10000, &[], 32, 0.01;
    direct_point: "direct-point", "hackmad-pbrt-v3-rs-tests/lights/point.pbrt", "directlighting", DL, [96, 96], 4096, &[], 16, 0.01;
    direct_spot: "direct-spot", "hackmad-pbrt-v3-rs-tests/lights/spot.pbrt", "directlighting", DL, [96, 96], 4096, &[], 16, 0.01;
    direct_distant: "direct-distant", "hackmad-pbrt-v3-rs-tests/lights/distant.pbrt", "directlighting", DL, [96, 96], 4096, &[], 16, 0.01;
    direct_diffuse: "direct-diffuse", "hackmad-pbrt-v3-rs-tests/lights/diffuse.pbrt", "directlighting", DL, [96, 96], 1024, &[], 16, 0.01;
    direct_infinite_no_map: "direct-infinite-no-map", "hackmad-pbrt-v3-rs-tests/lights/infinite-no-map.pbrt", "directlighting", DL, [96, 96], 8192, &[], 32, 0.01;
    direct_infinite_with_map: "direct-infinite-with-map", "hackmad-pbrt-v3-rs-tests/lights/infinite-with-map.pbrt", "directlighting", DL, [96, 96], 4096, &[RENO], 32, 0.01;
    direct_plastic: "direct-plastic", "hackmad-pbrt-v3-rs-tests/materials/plastic.pbrt", "directlighting", DL, [80, 80], 4096, &[DRAGON, WELLS], 32, 0.01;
    direct_metal: "direct-metal", "hackmad-pbrt-v3-rs-tests/materials/metal.pbrt", "directlighting", DL, [80, 80], 4096, &[DRAGON, WELLS, GOLD_ETA, GOLD_K], 32, 0.01;
    direct_glass: "direct-glass", "hackmad-pbrt-v3-rs-tests/materials/glass.pbrt", "directlighting", DL, [80, 80], 3072, &[DRAGON, WELLS], 32, 0.01;
    direct_substrate: "direct-substrate", "hackmad-pbrt-v3-rs-tests/materials/substrate.pbrt", "directlighting", DL, [80, 80], 4096, &[DRAGON, WELLS], 32, 0.01;
    direct_uber: "direct-uber", "hackmad-pbrt-v3-rs-tests/materials/uber.pbrt", "directlighting", DL, [80, 80], 4096, &[DRAGON, WELLS], 32, 0.01;
    direct_mix: "direct-mix", "hackmad-pbrt-v3-rs-tests/materials/mix.pbrt", "directlighting", DL, [80, 80], 2048, &[DRAGON, WELLS], 32, 0.01;
    direct_translucent: "direct-translucent", "hackmad-pbrt-v3-rs-tests/materials/translucent.pbrt", "directlighting", DL, [80, 80], 4096, &[DRAGON, WELLS], 32, 0.01;
    direct_mirror: "direct-mirror", "hackmad-pbrt-v3-rs-tests/materials/mirror.pbrt", "directlighting", DL, [80, 80], 2048, &[DRAGON, WELLS], 32, 0.01;
    direct_2d_checkerboard: "direct-2d-checkerboard", "hackmad-pbrt-v3-rs-tests/textures/2d-checkerboard.pbrt", "directlighting", DL, [96, 96], 1536, &[], 16, 0.01;
    direct_2d_mappings: "direct-2d-mappings", "hackmad-pbrt-v3-rs-tests/textures/2d-mappings.pbrt", "directlighting", DL, [128, 64], 1536, &[], 16, 0.01;
    direct_trilinear_filtering: "direct-trilinear-filtering", "hackmad-pbrt-v3-rs-tests/textures/trilinear-filtering.pbrt", "directlighting", DL, [96, 96], 1536, &[LINES], 16, 0.01;
    path_uniform_cornell: "path-uniform-cornell", "bitterli-cornell-box-v3/scene.pbrt", "path",
        &[("maxdepth", "5"), ("lightsamplestrategy", "uniform")], [128, 128], 1400, &[], 16, 0.01;
    path_bathroom: "path-bathroom", "bitterli-bathroom/scene-v3.pbrt", "path", PATH, [128, 128], 1200, &[], 16, 0.01;
    path_buddha_fractal: "path-buddha-fractal", "pbrtv3scenes-buddha-fractal/buddha-fractal.pbrt", "path", PATH, [80, 128], 3000, &[], 16, 0.01;
}
