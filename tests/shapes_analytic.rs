//! cone, paraboloid, hyperboloid and curve render like pbrt-v3 renders them.
//!
//! `tests/data/pbrt-v3/shapes-analytic/<scene>-{a,b}.pfm` are pbrt-v3 renders of `<scene>.pbrt` there, made
//! by its `make.sh`: `b` with the file's own render options (stratified 4×4 sampler, box filter), `a` with a
//! random sampler of 16 pixel samples instead. RMSE(a, b) is pbrt-v3's noise floor; we render with `b`'s
//! settings (the file as it is) and compare with `a`, requiring RMSE ≤ 1.3 × floor and the mean within
//! 0.5 % (the rule of `tests/shipped_scenes.rs`). No pbrt-v3 is needed to run this test.

mod common;

use std::path::{Path, PathBuf};

use cachert::image;
use cachert::metrics::rmse;
use cachert::scene::{LoadOptions, load};
use common::{mean, render_loaded, settings};

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pbrt-v3/shapes-analytic")
}

fn matches_pbrt_v3(scene: &str) {
    let dir = data_dir();
    let loaded = load(&dir.join(format!("{scene}.pbrt")), LoadOptions::default()).expect("loads");
    assert_eq!(loaded.warnings.len(), 0, "{scene}: {:?}", loaded.warnings);
    let out = render_loaded(&loaded, &settings(4)).expect("renders");
    let a = image::read(&dir.join(format!("{scene}-a.pfm"))).expect("reference a");
    let b = image::read(&dir.join(format!("{scene}-b.pfm"))).expect("reference b");
    let floor = rmse(&b, &a).expect("same size");
    let err = rmse(&out.image, &a).expect("same size");
    let (ours, theirs) = (mean(&out.image), mean(&a));
    let dev = (ours - theirs).abs() / theirs;
    if let Some(dump) = std::env::var_os("CACHERT_DUMP_DIR") {
        image::write(&out.image, &Path::new(&dump).join(format!("{scene}-ours.pfm"))).expect("dump");
    }
    eprintln!(
        "{scene}: RMSE {err:.4}, pbrt-v3 floor {floor:.4}, ratio {:.3}; mean {ours:.4} vs {theirs:.4} ({:.3} %)",
        err / floor,
        100.0 * dev
    );
    assert!(err <= 1.3 * floor, "{scene}: RMSE {err} is {:.2}× pbrt-v3's noise floor {floor}", err / floor);
    assert!(dev <= 0.005, "{scene}: mean {ours} vs pbrt-v3's {theirs}");
}

#[test]
fn cone_paraboloid_hyperboloids_match_pbrt_v3() {
    matches_pbrt_v3("quadrics");
}

#[test]
fn flat_cylinder_and_ribbon_curves_match_pbrt_v3() {
    matches_pbrt_v3("curves");
}
