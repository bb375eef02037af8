//! The scenes in `scenes/` load with what they are meant to show, and render like pbrt-v3 renders them.
//!
//! `tests/data/pbrt-v3/<scene>-{a,b}.pfm` are pbrt-v3 renders of each scene with its render options replaced
//! (64×48 film, box filter, 16 pixel samples — random for `a`, stratified 4×4 for `b` — and 64 AO rays;
//! camera and world unchanged), made by `tests/data/pbrt-v3/make.sh`. RMSE(a, b)² = σa² + σb² is pbrt-v3's
//! noise floor. We render with `b`'s sampler settings and compare with `a`: a correct renderer has
//! RMSE(ours, a)² ≈ σb² + σa², the same floor, so we require RMSE ≤ 1.3 × floor and the mean within 0.5 %.
//! (Comparing a random-sampler render with `a` would expect 2σa² > floor², a ratio near 1.2.)
//! No pbrt-v3 is needed to run this test.

mod common;

use std::path::{Path, PathBuf};

use cachert::scene::{LoadOptions, load, load_str};
use common::{render_loaded, settings};

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)
}

/// The substitutions `tests/data/pbrt-v3/make.sh` makes with sed for reference `b`, line by line.
fn reference_variant(text: &str) -> String {
    text.lines()
        .map(|l| {
            if l.starts_with("Film ") {
                "Film \"image\" \"integer xresolution\" [64] \"integer yresolution\" [48]".to_string()
            } else if l.starts_with("Sampler ") {
                "Sampler \"stratified\" \"integer xsamples\" [4] \"integer ysamples\" [4]".to_string()
            } else if l.starts_with("PixelFilter ") {
                "PixelFilter \"box\"".to_string()
            } else {
                l.replace("\"integer nsamples\" [16]", "\"integer nsamples\" [64]")
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn matches_pbrt_v3(scene: &str) {
    let path = scene_path(&format!("{scene}.pbrt"));
    let text = std::fs::read_to_string(&path).expect("the shipped scene reads");
    // Loaded as if it were the scene file, so models/… resolves against scenes/.
    let loaded = load_str(&reference_variant(&text), &path, LoadOptions::default()).expect("loads");
    assert_eq!(loaded.warnings.len(), 0, "{scene}: {:?}", loaded.warnings);
    let out = render_loaded(&loaded, &settings(4)).expect("renders");
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pbrt-v3");
    let (a, b) = (data.join(format!("{scene}-a.pfm")), data.join(format!("{scene}-b.pfm")));
    common::assert_matches_pbrt_pair(scene, &out.image, &a, &b);
}

#[test]
fn spheres_match_pbrt_v3() {
    matches_pbrt_v3("spheres");
}

#[test]
fn room_matches_pbrt_v3() {
    matches_pbrt_v3("room");
}

#[test]
fn room_has_its_ply_and_instances() {
    let loaded = load(&scene_path("room.pbrt"), LoadOptions::default()).expect("loads");
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let s = &loaded.scene;
    assert_eq!(loaded.stats.instances, 4, "four table legs from one object");
    assert_eq!(s.geometry.objects.len(), 1);
    // Walls (10) + table top (12) + torus (576).
    assert_eq!(loaded.stats.triangles, 10 + 12 + 576);
    assert_eq!(s.area_lights.len(), 1);
    assert_eq!((s.film.resolution, s.sampler.spp), ([400, 300], 4));
}

#[test]
fn spheres_loads_without_warnings() {
    let loaded = load(&scene_path("spheres.pbrt"), LoadOptions::default()).expect("loads");
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    assert_eq!(loaded.scene.geometry.accel.quadrics.len(), 6);
}
