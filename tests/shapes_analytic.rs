//! cone, paraboloid, hyperboloid and curve render like pbrt-v3 renders them.
//!
//! `tests/data/pbrt-v3/shapes-analytic/<scene>-{a,b}.pfm` are pbrt-v3 renders of `<scene>.pbrt` there, made
//! by its `make.sh`: `b` with the file's own render options (stratified 4×4 sampler, box filter), `a` with a
//! random sampler of 16 pixel samples instead. RMSE(a, b) is pbrt-v3's noise floor; we render with `b`'s
//! settings (the file as it is) and compare with `a`, requiring RMSE ≤ 1.3 × floor and the mean within
//! 0.5 % (the rule of `tests/shipped_scenes.rs`). No pbrt-v3 is needed to run this test.

mod common;

use std::path::{Path, PathBuf};

use cachert::scene::{LoadOptions, LoadedScene, load_str};
use common::header;

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pbrt-v3/shapes-analytic")
}

fn matches_pbrt_v3(scene: &str) {
    common::file_matches_pbrt_pair(&data_dir(), scene);
}

#[test]
fn cone_paraboloid_hyperboloids_match_pbrt_v3() {
    matches_pbrt_v3("quadrics");
}

#[test]
fn flat_cylinder_and_ribbon_curves_match_pbrt_v3() {
    matches_pbrt_v3("curves");
}

#[test]
fn curves_and_quadrics_in_instanced_objects_match_pbrt_v3() {
    matches_pbrt_v3("instanced");
}

fn load_world(world: &str) -> cachert::Result<LoadedScene> {
    let text = format!("{}WorldBegin\n{world}\nWorldEnd\n", header(8, 1, 1));
    load_str(&text, Path::new("shapes.pbrt"), LoadOptions::default())
}

fn refused(world: &str, needle: &str) {
    match load_world(world) {
        Ok(_) => panic!("loaded: {world}"),
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.contains(needle), "{world}: {msg}");
            assert!(msg.contains("shapes.pbrt:"), "located: {msg}");
        }
    }
}

#[test]
fn curve_pieces_segments_and_split_depth_limits() {
    // Degree 3 Bézier, 7 points: two pieces of 2^3 segments.
    let l = load_world(r#"Shape "curve" "point P" [0 0 0 1 0 0 2 0 0 3 0 0 4 0 0 5 0 0 6 0 0]"#).unwrap();
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
    let a = &l.scene.geometry.accel;
    assert_eq!((a.curves.len(), a.curve_segments.len()), (2, 16));
    // Degree 2 B-spline of 5 points: three pieces; splitdepth as a float, as pbrt-v3 accepts.
    let l = load_world(
        r#"Shape "curve" "integer degree" 2 "string basis" "bspline" "float splitdepth" 1 "point P" [0 0 0 1 0 0 2 1 0 3 0 0 4 0 0]"#,
    )
    .unwrap();
    assert_eq!((l.scene.geometry.accel.curves.len(), l.scene.geometry.accel.curve_segments.len()), (3, 6));
    // An absurd split depth is clamped with a warning, never 2^40 segments.
    let l = load_world(r#"Shape "curve" "integer splitdepth" 40 "point P" [0 0 0 1 0 0 2 0 0 3 0 0]"#).unwrap();
    assert_eq!(l.scene.geometry.accel.curve_segments.len(), 1024);
    assert!(l.warnings.iter().any(|w| w.to_string().contains("splitdepth")), "{:?}", l.warnings);
    // Normals on a non-ribbon curve are ignored with a warning, as in pbrt-v3.
    let l = load_world(r#"Shape "curve" "point P" [0 0 0 1 0 0 2 0 0 3 0 0] "normal N" [0 0 1 0 0 1]"#).unwrap();
    assert_eq!(l.warnings.len(), 1, "{:?}", l.warnings);
}

#[test]
fn invalid_curves_and_quadrics_are_refused_where_they_are_written() {
    refused(r#"Shape "curve" "integer splitdepth" -1 "point P" [0 0 0 1 0 0 2 0 0 3 0 0]"#, "splitdepth");
    // Beyond the BVH's coordinate range, like every other shape (and inside an object definition too).
    refused(r#"Shape "curve" "point P" [0 0 0 1 0 0 2 0 0 3e10 0 0]"#, "coordinates beyond");
    refused(
        r#"ObjectBegin "o" Shape "curve" "float width" 1e10 "point P" [0 0 0 1 0 0 2 0 0 3 0 0] ObjectEnd"#,
        "beyond",
    );
    refused(r#"Shape "curve" "point P" [0 0 0 1 0 0 2 0 0 3 0 0 4 0 0]"#, "control points");
    refused(r#"Shape "curve" "integer degree" 4 "point P" [0 0 0 1 0 0 2 0 0 3 0 0 4 0 0]"#, "degree");
    refused(r#"Shape "curve" "string basis" "catmullrom" "point P" [0 0 0 1 0 0 2 0 0 3 0 0]"#, "basis");
    refused(r#"Shape "curve" "string type" "tube" "point P" [0 0 0 1 0 0 2 0 0 3 0 0]"#, "type");
    refused(r#"Shape "curve" "string type" "ribbon" "point P" [0 0 0 1 0 0 2 0 0 3 0 0]"#, "normal N");
    refused(
        r#"Shape "curve" "string type" "ribbon" "point P" [0 0 0 1 0 0 2 0 0 3 0 0] "normal N" [0 0 1]"#,
        "normals",
    );
    refused(
        r#"Shape "curve" "string type" "ribbon" "point P" [0 0 0 1 0 0 2 0 0 3 0 0] "normal N" [0 0 1 0 0 0]"#,
        "non-zero",
    );
    refused(r#"Shape "curve" "float width" -1 "point P" [0 0 0 1 0 0 2 0 0 3 0 0]"#, "width");
    refused(r#"Shape "curve" "float width0" 0 "float width1" 0 "point P" [0 0 0 1 0 0 2 0 0 3 0 0]"#, "width");
    refused(r#"Shape "curve" "float width" 1"#, "point P");
    refused(r#"Shape "cone" "float height" -1"#, "height");
    refused(r#"Shape "cone" "float radius" 0"#, "radius");
    refused(r#"Shape "paraboloid" "float zmin" -1 "float zmax" 0"#, "zmax");
    // pbrt-v3's own hyperboloid defaults (a line through the axis) never finish building there.
    refused(r#"Shape "hyperboloid""#, "hyperboloid");
    refused(r#"Shape "hyperboloid" "point p1" [1 0 1] "point p2" [0 1 1]"#, "hyperboloid");
    refused(r#"Shape "hyperboloid" "point p1" [1 0 0] "point p2" [1 0 0]"#, "hyperboloid");
}

#[test]
fn area_lights_on_curves_warn() {
    let l = load_world(
        r#"AttributeBegin AreaLightSource "diffuse" Shape "curve" "point P" [0 0 0 1 0 0 2 0 0 3 0 0] AttributeEnd"#,
    )
    .unwrap();
    assert!(l.warnings.iter().any(|w| w.to_string().contains("curves")), "{:?}", l.warnings);
    assert!(l.scene.area_lights.is_empty());
}
