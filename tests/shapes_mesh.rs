//! pbrt-v3's mesh-producing shapes — `loopsubdiv`, `heightfield`, `nurbs` — load, render like pbrt-v3 renders
//! them, and refuse bad parameters with located errors (or warnings) instead of panicking or allocating
//! without bound.
//!
//! `tests/data/pbrt-v3/shapes-mesh/<scene>.pbrt` are small ambient-occlusion scenes; `<scene>-{a,b}.pfm` are
//! pbrt-v3 renders of them made by `make.sh` there: `b` is the scene as written (stratified 4×4), `a` the
//! same with pbrt-v3's random sampler (16 samples). RMSE(a, b) is pbrt-v3's noise floor; we render the scene
//! as written (b's sampler settings) and compare with `a`, requiring RMSE ≤ 1.3 × floor and the mean within
//! 0.5 %, as `tests/shipped_scenes.rs` does. No pbrt-v3 is needed to run this test.

mod common;

use std::path::{Path, PathBuf};

use cachert::scene::{LoadOptions, LoadedScene, load};
use common::{TempDir, shared_scenes};

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pbrt-v3/shapes-mesh")
}

/// Loads `<scene>.pbrt` (no warnings allowed), renders it and compares it with pbrt-v3's references.
fn matches_pbrt_v3(scene: &str) -> LoadedScene {
    common::file_matches_pbrt_pair(&data_dir(), scene)
}

#[test]
fn closed_loopsubdiv_in_instances_matches_pbrt_v3() {
    let loaded = matches_pbrt_v3("loopsubdiv-closed");
    // Ground 2 + cube 12·4² (stored once, instanced twice) + tetrahedron 4·4.
    assert_eq!(loaded.stats.triangles, 2 + 12 * 16 + 4 * 4);
    assert_eq!(loaded.stats.instances, 2);
}

#[test]
fn open_loopsubdiv_matches_pbrt_v3() {
    let loaded = matches_pbrt_v3("loopsubdiv-open");
    // Ground 2 + open box 10·4 + sheet 12·4³ + fan 6·4.
    assert_eq!(loaded.stats.triangles, 2 + 10 * 4 + 12 * 64 + 6 * 4);
}

#[test]
fn heightfield_matches_pbrt_v3() {
    let loaded = matches_pbrt_v3("heightfield");
    assert_eq!(loaded.stats.triangles, 2 + 2 * 8 * 6 + 2 * 2);
}

#[test]
fn nurbs_match_pbrt_v3() {
    let loaded = matches_pbrt_v3("nurbs");
    assert_eq!(loaded.stats.triangles, 2 + 2 * (2 * 29 * 29));
}

// ---- parameters pbrt-v3 would crash, hang or run out of memory on ----

/// Four lines of render options; `WorldBegin` is line 5, so a world body starts on line 6.
const HEADER: &str = "Film \"image\" \"integer xresolution\" [4] \"integer yresolution\" [4]\n\
                      Sampler \"random\" \"integer pixelsamples\" [1]\n\
                      PixelFilter \"box\"\n\
                      Integrator \"ambientocclusion\" \"integer nsamples\" [2]\n";

/// Writes a scene whose world is `body` and loads it: the result and the file's path.
fn load_world(tag: &str, body: &str) -> (cachert::Result<LoadedScene>, String, TempDir) {
    let dir = TempDir::new(tag);
    let path = dir.write("scene.pbrt", format!("{HEADER}WorldBegin\n{body}\nWorldEnd\n"));
    (load(&path, LoadOptions::default()), path.display().to_string(), dir)
}

/// The error of loading `body`, with the file's path replaced by `{file}`.
fn world_error(tag: &str, body: &str) -> String {
    let (res, file, _dir) = load_world(tag, body);
    match res {
        Ok(_) => panic!("{tag} loaded, but it is wrong:\n{body}"),
        Err(e) => e.to_string().replace(&file, "{file}"),
    }
}

const TETRA: &str = "\"point P\" [1 1 1  1 -1 -1  -1 1 -1  -1 -1 1] \"integer indices\" [0 1 2  0 3 1  0 2 3  1 3 2]";

#[test]
fn absurd_subdivision_levels_are_lowered_with_a_warning() {
    let (res, file, _dir) = load_world("loop-levels", &format!("Shape \"loopsubdiv\" \"integer levels\" [30] {TETRA}"));
    let loaded = res.expect("loads");
    let w: Vec<String> = loaded.warnings.iter().map(|w| w.to_string().replace(&file, "{file}")).collect();
    assert_eq!(
        w,
        ["{file}:6:20: warning: loopsubdiv: 30 levels would make more than 4194304 triangles from 4 control \
          triangles; using 10 levels"]
    );
    assert_eq!(loaded.stats.triangles, 4 << 20);
    // nlevels is pbrt-v3's other name; negative levels do no subdivision.
    let (res, _, _dir) = load_world("loop-nlevels", &format!("Shape \"loopsubdiv\" \"integer nlevels\" [1] {TETRA}"));
    assert_eq!(res.expect("loads").stats.triangles, 16);
    let (res, _, _dir) = load_world("loop-negative", &format!("Shape \"loopsubdiv\" \"integer levels\" [-2] {TETRA}"));
    let loaded = res.expect("loads");
    assert_eq!(loaded.stats.triangles, 4);
    assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
    // The default is 3 levels.
    let (res, _, _dir) = load_world("loop-default", &format!("Shape \"loopsubdiv\" {TETRA}"));
    assert_eq!(res.expect("loads").stats.triangles, 4 * 64);
}

#[test]
fn bad_loopsubdiv_meshes_are_located_errors() {
    let p = "\"point P\" [0 0 0  1 0 0  0 1 0  0 0 1  1 1 1]";
    let cases = [
        (
            format!("Shape \"loopsubdiv\" {p} \"integer indices\" [0 1 2  0 1 5]"),
            "{file}:6:66: loopsubdiv: parameter \"indices\": value 5 at position 5 is out of range: there are 5 \
             vertices",
        ),
        (
            format!("Shape \"loopsubdiv\" {p} \"integer indices\" [0 1 2  0 1]"),
            "{file}:6:66: loopsubdiv: parameter \"indices\": 5 values is not a multiple of 3",
        ),
        (
            format!("Shape \"loopsubdiv\" {p} \"integer indices\" [0 1 2  1 0 3  0 1 4]"),
            "{file}:6:66: loopsubdiv: the edge from vertex 0 to vertex 1 of triangles 0 and 2 is shared by more \
             than two triangles",
        ),
        (
            format!("Shape \"loopsubdiv\" {p} \"integer indices\" [0 1 2  0 1 3]"),
            "{file}:6:66: loopsubdiv: the edge from vertex 0 to vertex 1 of triangles 0 and 1 is traversed in the \
             same direction by both triangles (they are not consistently oriented)",
        ),
        (
            format!("Shape \"loopsubdiv\" {p} \"integer indices\" [0 1 2  3 3 4]"),
            "{file}:6:66: loopsubdiv: triangle 1 uses vertex 3 more than once (3, 3, 4)",
        ),
        (format!("Shape \"loopsubdiv\" {p}"), "{file}:6:1: loopsubdiv: missing required parameter \"integer indices\""),
        (
            "Shape \"loopsubdiv\" \"integer indices\" [0 1 2]".to_string(),
            "{file}:6:1: loopsubdiv: missing required parameter \"point3 P\"",
        ),
    ];
    for (body, want) in cases {
        assert_eq!(world_error("loop-bad", &body), want, "{body}");
    }
    // Unused vertices are ignored with a warning (pbrt-v3 would crash on them).
    let (res, _, _dir) = load_world(
        "loop-unused",
        &format!("Shape \"loopsubdiv\" \"integer levels\" [1] {p} \"integer indices\" [0 1 2]"),
    );
    let loaded = res.expect("loads");
    assert_eq!(loaded.stats.triangles, 4);
    let w: Vec<&str> = loaded.warnings.iter().map(|w| w.msg.as_str()).collect();
    assert_eq!(w, ["loopsubdiv: 2 of 5 vertices are used by no triangle; ignoring them"]);
}

#[test]
fn bad_heightfields_are_located_errors() {
    let cases = [
        (
            "Shape \"heightfield\" \"integer nu\" [3] \"integer nv\" [2] \"float Pz\" [0 0 0 0 0]",
            "{file}:6:55: heightfield: 3×2 grid needs 6 heights \"Pz\", got 5",
        ),
        (
            "Shape \"heightfield\" \"integer nu\" [1] \"integer nv\" [2] \"float Pz\" [0 0]",
            "{file}:6:21: heightfield: \"nu\" must be at least 2, got 1",
        ),
        (
            "Shape \"heightfield\" \"integer nu\" [2000000000] \"integer nv\" [2000000000] \"float Pz\" [0 0 0 0]",
            "{file}:6:73: heightfield: 2000000000×2000000000 grid needs 4000000000000000000 heights \"Pz\", got 4",
        ),
        (
            "Shape \"heightfield\" \"integer nu\" [2] \"float Pz\" [0 0]",
            "{file}:6:1: heightfield: missing required parameter \"integer nv\"",
        ),
    ];
    for (body, want) in cases {
        assert_eq!(world_error("hf-bad", body), want, "{body}");
    }
}

#[test]
fn bad_nurbs_are_located_errors() {
    let ok_v = "\"integer nv\" [2] \"integer vorder\" [2] \"float vknots\" [0 0 1 1]";
    let p4 = "\"point P\" [0 0 0  1 0 0  0 1 0  1 1 0]";
    let cases = [
        (
            format!("Shape \"nurbs\" \"integer nu\" [2] \"integer uorder\" [2] \"float uknots\" [0 0 1] {ok_v} {p4}"),
            "{file}:6:53: nurbs: 3 knots in \"uknots\" do not match nu 2 + uorder 2",
        ),
        (
            format!(
                "Shape \"nurbs\" \"integer nu\" [2] \"integer uorder\" [3] \"float uknots\" [0 0 0 1 1] {ok_v} {p4}"
            ),
            "{file}:6:53: nurbs: \"uorder\" 3 is larger than the number of control points nu 2",
        ),
        (
            format!("Shape \"nurbs\" \"integer nu\" [2] \"integer uorder\" [2] \"float uknots\" [0 1 0 1] {ok_v} {p4}"),
            "{file}:6:53: nurbs: \"uknots\" decrease at value 2: 0 after 1",
        ),
        (
            format!(
                "Shape \"nurbs\" \"integer nu\" [2] \"integer uorder\" [2] \"float uknots\" [0 0 1 1] {ok_v} \
                 \"point P\" [0 0 0  1 0 0  0 1 0]"
            ),
            "{file}:6:141: nurbs: expected 2×2=4 control points, got 3",
        ),
        (
            format!(
                "Shape \"nurbs\" \"integer nu\" [2] \"integer uorder\" [2] \"float uknots\" [0 0 1 1] {ok_v} \
                 \"float u1\" [2] {p4}"
            ),
            "{file}:6:141: nurbs: \"u1\" 2 is outside the knots' parameter range [0, 1]",
        ),
        (
            format!("Shape \"nurbs\" \"integer nu\" [2] \"integer uorder\" [2] \"float uknots\" [0 0 1 1] {ok_v}"),
            "{file}:6:1: nurbs: missing control points: \"point3 P\" or \"float Pw\"",
        ),
        (
            format!(
                "Shape \"nurbs\" \"integer nu\" [2] \"integer uorder\" [2] \"float uknots\" [0 0 1 1] {ok_v} \
                 \"float Pw\" [0 0 0 1  1 0 0 1  0 1 0 1  1 1 0]"
            ),
            "{file}:6:141: nurbs: 15 values in \"Pw\" is not a multiple of 4",
        ),
        (
            format!("Shape \"nurbs\" \"integer uorder\" [2] \"float uknots\" [0 0 1 1] {ok_v} {p4}"),
            "{file}:6:1: nurbs: missing required parameter \"integer nu\"",
        ),
    ];
    for (body, want) in cases {
        assert_eq!(world_error("nurbs-bad", &body), want, "{body}");
    }
}

/// The shared scenes must be here: fails, with the reason, where they are absent (outside CI the tests that
/// need them print a `skipped` line and pass; under CI they fail too).
#[test]
fn shared_scenes_present() {
    common::assert_shared_scenes_present();
}

#[test]
fn hackmad_all_shapes_loopsubdiv_loads() {
    let Some(root) = shared_scenes() else { return };
    let path = root.join("hackmad-pbrt-v3-rs-tests/shapes/all-shapes.pbrt");
    let loaded = load(&path, LoadOptions::default()).unwrap_or_else(|e| panic!("all-shapes: {e}"));
    let skipped: Vec<String> =
        loaded.warnings.iter().filter(|w| w.msg.contains("not supported")).map(|w| w.msg.clone()).collect();
    assert!(!skipped.iter().any(|m| m.contains("loopsubdiv")), "{skipped:#?}");
}
