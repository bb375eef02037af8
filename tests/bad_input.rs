//! Bad input gives a clear error at the right place, never a panic, and nothing half-written.
//!
//! Each scene mistake from the issue list is written to a file in a fresh temp folder and loaded; the test
//! asserts the whole message, `file:line:col: what`. The binary is run on a few of them to check the exit
//! status (2), the printed excerpt with its caret, and that a failed run leaves no output file (nor a
//! temporary one) behind — including runs that fail after the scene loaded.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use cachert::scene::{LoadOptions, LoadedScene, load};
use common::{TempDir, render_loaded, settings};

/// Four lines of render options; `WorldBegin` follows on line 5, so a world body starts on line 6.
const HEADER: &str = "Film \"image\" \"integer xresolution\" [4] \"integer yresolution\" [4]\n\
                      Sampler \"random\" \"integer pixelsamples\" [1]\n\
                      PixelFilter \"box\"\n\
                      Integrator \"ambientocclusion\" \"integer nsamples\" [2]\n";

/// A scene whose world is `body` (its first line is line 6 of the file).
fn world(body: &str) -> String {
    format!("{HEADER}WorldBegin\n{body}\nWorldEnd\n")
}

/// Writes `text` as `name` in `dir`, loads it, and returns the error message; panics if it loads.
fn load_error(dir: &TempDir, name: &str, text: &str) -> (String, PathBuf) {
    let path = dir.write(name, text);
    match load(&path, LoadOptions::default()) {
        Ok(_) => panic!("{name} loaded, but it is wrong:\n{text}"),
        Err(e) => {
            assert!(e.loc().is_some() || matches!(e, cachert::Error::File { .. }), "no location: {e}");
            (e.to_string(), path)
        }
    }
}

/// Loads `body` as a world and asserts the error is `msg` at `line:col` of that file (`{file}` in `msg`
/// stands for the file's path).
fn assert_world_error(tag: &str, body: &str, line: u32, col: u32, msg: &str) {
    let dir = TempDir::new(tag);
    let (got, path) = load_error(&dir, "scene.pbrt", &world(body));
    let file = path.display().to_string();
    assert_eq!(got, format!("{file}:{line}:{col}: {}", msg.replace("{file}", &file)));
}

fn load_ok(path: &Path) -> LoadedScene {
    load(path, LoadOptions::default()).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

// ---- files that are not there ----

#[test]
fn missing_scene_file() {
    let dir = TempDir::new("missing-scene");
    let path = dir.path("nope.pbrt");
    let err = load(&path, LoadOptions::default()).expect_err("a missing file is an error");
    assert_eq!(
        err.to_string(),
        format!("{}: cannot read scene file: No such file or directory (os error 2)", path.display())
    );
}

#[test]
fn missing_include_file() {
    let dir = TempDir::new("missing-include");
    let (got, path) =
        load_error(&dir, "scene.pbrt", &format!("{HEADER}WorldBegin\n  Include \"parts/nope.pbrt\"\nWorldEnd\n"));
    assert_eq!(
        got,
        format!(
            "{}:6:3: cannot read included file \"parts/nope.pbrt\": No such file or directory (os error 2)",
            path.display()
        )
    );
}

// ---- tokens ----

#[test]
fn unterminated_string() {
    // The error points at the opening quote, whether the file ends in the string or a later line does.
    assert_world_error("unterminated", "Shape \"sphere\n", 6, 7, "unterminated string");
    let dir = TempDir::new("unterminated-eof");
    let (got, path) = load_error(&dir, "eof.pbrt", &format!("{HEADER}WorldBegin\nMaterial \"matte\" \"rgb Kd"));
    assert_eq!(got, format!("{}:6:18: unterminated string", path.display()));
}

#[test]
fn malformed_number() {
    assert_world_error(
        "malformed-param",
        "Shape \"sphere\" \"float radius\" [1.2.3]",
        6,
        32,
        "malformed number \"1.2.3\"",
    );
    assert_world_error("malformed-directive", "Translate 1 2x 3", 6, 13, "malformed number \"2x\"");
}

#[test]
fn unknown_directive() {
    assert_world_error(
        "unknown-directive",
        "  Shpe \"sphere\"",
        6,
        3,
        "unknown directive \"Shpe\" (did you mean \"Shape\"?)",
    );
}

// ---- parameters ----

#[test]
fn wrong_parameter_type() {
    assert_world_error(
        "wrong-type",
        "Shape \"sphere\" \"string radius\" \"one\"",
        6,
        16,
        "parameter \"radius\": expected type float, found string",
    );
    assert_world_error(
        "wrong-value",
        "Shape \"sphere\" \"float radius\" \"abc\"",
        6,
        31,
        "parameter \"radius\": expected a number, found \"abc\"",
    );
}

#[test]
fn wrong_parameter_array_length() {
    assert_world_error(
        "wrong-length",
        "Shape \"sphere\" \"float radius\" [1 2]",
        6,
        16,
        "parameter \"radius\": expected 1 float, got 2",
    );
}

#[test]
fn point_count_not_a_multiple_of_3() {
    assert_world_error(
        "p-not-3",
        "Shape \"trianglemesh\" \"point P\" [0 0 0  1 0 0  0 1] \"integer indices\" [0 1 2]",
        6,
        22,
        "parameter \"P\": expected a multiple of 3 numbers, got 8",
    );
}

#[test]
fn indices_out_of_range() {
    let body = "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0]\n  \"integer indices\" [0 1 3]";
    assert_world_error(
        "index-range",
        body,
        7,
        3,
        "parameter \"indices\": value 3 at position 2 is out of range: there are 3 vertices",
    );
    let body = "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 -1 2]";
    assert_world_error(
        "index-negative",
        body,
        6,
        52,
        "parameter \"indices\": value -1 at position 1 is out of range: there are 3 vertices",
    );
}

#[test]
fn indices_not_a_multiple_of_3() {
    let body = "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2 0]";
    assert_world_error("index-count", body, 6, 52, "parameter \"indices\": 4 values is not a multiple of 3");
}

#[test]
fn empty_triangle_mesh_is_a_warning() {
    // pbrt-v3 draws nothing and says nothing; cachert draws nothing and says so.
    let dir = TempDir::new("empty-mesh");
    let path =
        dir.write("scene.pbrt", world("Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" []"));
    let warnings: Vec<String> = load_ok(&path).warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(
        warnings,
        vec![format!(
            "{}:6:52: warning: trianglemesh with 3 vertices and no triangles: nothing is drawn",
            path.display()
        )]
    );
}

// ---- directives and structure ----

#[test]
fn unknown_shape_type() {
    assert_world_error(
        "unknown-shape",
        "Shape \"spher\"",
        6,
        7,
        "unknown shape type \"spher\"; expected one of trianglemesh, plymesh, objmesh, sphere, disk, cylinder, cone, \
         paraboloid, hyperboloid, curve, loopsubdiv, heightfield, nurbs",
    );
}

#[test]
fn attribute_end_without_attribute_begin() {
    assert_world_error("attribute-end", "AttributeEnd", 6, 1, "AttributeEnd without a matching AttributeBegin");
    assert_world_error(
        "attribute-mismatch",
        "TransformBegin\nAttributeEnd",
        7,
        1,
        "AttributeEnd closes the TransformBegin at {file}:6:1; expected TransformEnd",
    );
}

#[test]
fn object_instance_of_an_undefined_name() {
    assert_world_error(
        "undefined-object",
        "ObjectBegin \"box\"\nShape \"sphere\"\nObjectEnd\nObjectInstance \"bx\"",
        9,
        1,
        "ObjectInstance: no object named \"bx\" has been defined (ObjectBegin \"bx\" … ObjectEnd must come first)",
    );
}

#[test]
fn include_cycle() {
    let dir = TempDir::new("include-cycle");
    dir.write("b.pbrt", "# b\nInclude \"c.pbrt\"\n");
    dir.write("c.pbrt", "Include \"b.pbrt\"\n");
    let (got, _) = load_error(&dir, "a.pbrt", &format!("{HEADER}WorldBegin\nInclude \"b.pbrt\"\nWorldEnd\n"));
    let p = |n: &str| dir.path(n).display().to_string();
    assert_eq!(
        got,
        format!("{}:1:1: Include cycle: {} -> {} -> {}", p("c.pbrt"), p("b.pbrt"), p("c.pbrt"), p("b.pbrt"))
    );
    // A file that includes itself.
    let (got, path) = load_error(&dir, "self.pbrt", "Include \"self.pbrt\"\n");
    assert_eq!(got, format!("{0}:1:1: Include cycle: {0} -> {0}", path.display()));
}

#[test]
fn missing_world_begin() {
    let dir = TempDir::new("no-world-begin");
    let (got, path) = load_error(&dir, "scene.pbrt", &format!("{HEADER}Shape \"sphere\"\nWorldEnd\n"));
    assert_eq!(
        got,
        format!("{}:5:1: Shape must come between WorldBegin and WorldEnd (missing WorldBegin?)", path.display())
    );
    let (got, path) = load_error(&dir, "options-only.pbrt", HEADER);
    assert_eq!(
        got,
        format!(
            "{}:4:1: the scene has no WorldBegin: expected WorldBegin … WorldEnd after the render options",
            path.display()
        )
    );
}

#[test]
fn missing_world_end() {
    let dir = TempDir::new("no-world-end");
    let (got, path) = load_error(&dir, "scene.pbrt", &format!("{HEADER}WorldBegin\nShape \"sphere\"\n"));
    assert_eq!(got, format!("{}:6:1: the scene ends without WorldEnd", path.display()));
}

// ---- transforms ----

#[test]
fn nan_or_infinity_in_a_transform() {
    // NaN cannot be written as a number; the word is pointed at.
    assert_world_error(
        "nan",
        "Translate 1 nan 3",
        6,
        13,
        "Translate: expected 3 numbers, found nan (values must be finite numbers)",
    );
    assert_world_error(
        "inf-word",
        "Scale 1 inf 3",
        6,
        9,
        "Scale: expected 3 numbers, found inf (values must be finite numbers)",
    );
    // A number too large for f64 reads as infinity.
    assert_world_error("inf-overflow", "Scale 1 1e400 3", 6, 1, "Scale: value 2 is not finite (inf)");
    assert_world_error(
        "inf-matrix",
        "Transform [1 0 0 0  0 1 0 0  0 0 1 0  0 0 1e999 1]",
        6,
        1,
        "Transform: value 15 is not finite (inf)",
    );
    // Finite values whose product overflows.
    assert_world_error(
        "inf-product",
        "Scale 1e300 1 1\nTranslate 1e10 0 0",
        7,
        1,
        "the accumulated transform is no longer finite",
    );
}

#[test]
fn look_at_with_eye_equal_to_target() {
    let dir = TempDir::new("lookat");
    let text = format!("LookAt 0 1 2  0 1 2  0 1 0\nCamera \"perspective\"\n{HEADER}WorldBegin\nWorldEnd\n");
    let (got, path) = load_error(&dir, "scene.pbrt", &text);
    assert_eq!(got, format!("{}:1:1: LookAt: the eye and the target are the same point", path.display()));
}

// ---- film ----

#[test]
fn xresolution_zero() {
    let dir = TempDir::new("xres-zero");
    let text = "Film \"image\" \"integer xresolution\" [0] \"integer yresolution\" [4]\nWorldBegin\nWorldEnd\n";
    let (got, path) = load_error(&dir, "scene.pbrt", text);
    assert_eq!(got, format!("{}:1:14: xresolution must be at least 1, got 0", path.display()));
}

#[test]
fn absurd_resolution_is_refused_before_allocating() {
    // 2e6 × 2e6 pixels would be 175 TiB: had the film been allocated, this test would have died instead.
    let dir = TempDir::new("xres-huge");
    let text =
        "Film \"image\"\n  \"integer xresolution\" [2000000] \"integer yresolution\" [2000000]\nWorldBegin\nWorldEnd\n";
    let (got, path) = load_error(&dir, "scene.pbrt", text);
    // The limit is the memory available (machine-dependent), so only the start is fixed.
    let start = format!("{}:1:6: film resolution 2000000x2000000 would need 174.6 TiB of memory; ", path.display());
    assert!(got.starts_with(&start) && got.ends_with("is available"), "{got}");
    let text = "Film \"image\" \"integer xresolution\" [10000000000]\nWorldBegin\nWorldEnd\n";
    let (got, path) = load_error(&dir, "overflow.pbrt", text);
    assert_eq!(got, format!("{}:1:14: xresolution 10000000000 is too large", path.display()));
}

// ---- files named by the scene ----

/// A binary little-endian PLY with one triangle; `keep` bytes of the body are kept.
fn one_triangle_ply(keep: usize) -> Vec<u8> {
    let mut out = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        .to_vec();
    let mut body = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        body.extend_from_slice(&v.to_le_bytes());
    }
    body.push(3);
    for i in [0i32, 1, 2] {
        body.extend_from_slice(&i.to_le_bytes());
    }
    out.extend_from_slice(&body[..keep.min(body.len())]);
    out
}

#[test]
fn truncated_binary_ply() {
    let dir = TempDir::new("ply-truncated");
    dir.write("whole.ply", one_triangle_ply(usize::MAX));
    let whole = load_ok(&dir.write("ok.pbrt", world("Shape \"plymesh\" \"string filename\" \"whole.ply\"")));
    assert_eq!(whole.stats.triangles, 1);
    let cases = [(20, "file ends after 1 of 3 vertices"), (40, "file ends after 0 of 1 faces")];
    for (keep, what) in cases {
        dir.write("cut.ply", one_triangle_ply(keep));
        let (got, path) = load_error(&dir, "scene.pbrt", &world("  Shape \"plymesh\" \"string filename\" \"cut.ply\""));
        assert_eq!(
            got,
            format!(
                "{}:6:19: plymesh \"{}\": {what} (the file is truncated, or its header is wrong)",
                path.display(),
                dir.path("cut.ply").display()
            )
        );
    }
}

#[test]
fn missing_texture_file_warns_and_becomes_pbrt_v3s_grey() {
    let dir = TempDir::new("texture-missing");
    let body = "Texture \"wood\" \"spectrum\" \"imagemap\" \"string filename\" \"textures/wood.png\"\n\
                Material \"matte\" \"texture Kd\" \"wood\"\n\
                Translate 0 0 2 Shape \"sphere\"";
    let path = dir.write("scene.pbrt", world(body));
    let loaded = load_ok(&path);
    let warnings: Vec<String> = loaded.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(
        warnings,
        vec![format!(
            "{}:6:38: warning: texture \"wood\": cannot read image \"{}\"; using pbrt-v3's grey 0.5 texel",
            path.display(),
            dir.path("textures/wood.png").display()
        )]
    );
    let t = &loaded.scene.textures[0];
    assert_eq!((t.name.as_str(), t.class.as_str()), ("wood", "imagemap"));
    // And the scene still renders, with ambient occlusion and with shading (where the texture is pbrt-v3's
    // grey texel, 0.5 sRGB-decoded for a PNG); no second warning from the shading stage.
    let out = render_loaded(&loaded, &settings(0)).expect("renders");
    assert!(common::mean(&out.image) > 0.0);
    let mut w = cachert::Warnings::default();
    let textures = cachert::shading::texture::Textures::build(&loaded.scene, &mut w).expect("builds");
    assert_eq!(w.len(), 0, "{w:?}");
    let [w, h] = loaded.scene.film.resolution;
    let ray = loaded.scene.camera.generate_ray([w as f32 / 2.0, h as f32 / 2.0], [0.5, 0.5]);
    let si = loaded.scene.geometry.intersect(&ray).expect("the centre sees the sphere");
    let v = textures.spectrum(0, &si);
    assert!((v.x - 0.214_041).abs() < 1e-5, "{v:?}");
}

#[test]
fn empty_world_renders_black() {
    let dir = TempDir::new("empty-world");
    let loaded = load_ok(&dir.write("scene.pbrt", world("")));
    assert_eq!(loaded.scene.bounds(), None);
    let out = render_loaded(&loaded, &settings(3)).expect("renders");
    assert_eq!((out.image.width, out.image.height), (4, 4));
    assert!(out.image.pixels.iter().all(|p| *p == [0.0; 3]), "{:?}", out.image.pixels);
}

// ---- the binary: exit status, excerpt, nothing left behind ----

fn cachert(dir: &TempDir, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cachert")).args(args).current_dir(&dir.0).output().expect("the binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn binary_prints_location_and_caret_and_exits_2() {
    let dir = TempDir::new("bin-error");
    dir.write("bad.pbrt", world("  Shape \"spher\" \"float radius\" [1]"));
    for cmd in ["render", "info"] {
        let args: &[&str] =
            if cmd == "render" { &[cmd, "bad.pbrt", "--outfile", "out.exr"] } else { &[cmd, "bad.pbrt"] };
        let o = cachert(&dir, args);
        assert_eq!(o.status.code(), Some(2), "{cmd}");
        assert_eq!(
            stderr(&o),
            "error: bad.pbrt:6:9: unknown shape type \"spher\"; expected one of trianglemesh, plymesh, objmesh, \
             sphere, disk, cylinder, cone, paraboloid, hyperboloid, curve, loopsubdiv, heightfield, nurbs\n    Shape \"spher\" \"float radius\" [1]\n          ^\n",
            "{cmd}"
        );
    }
    assert_eq!(dir.entries(), vec!["bad.pbrt"]);
    let o = cachert(&dir, &["render", "missing.pbrt"]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(stderr(&o), "error: missing.pbrt: cannot read scene file: No such file or directory (os error 2)\n");
}

#[test]
fn failed_runs_leave_no_file_behind() {
    let dir = TempDir::new("bin-no-output");
    dir.write("good.pbrt", world("Shape \"sphere\""));
    dir.write("bad.pbrt", world("Shape \"sphere\" \"float radius\" [-1]"));
    let path_message = format!(
        "error: integrator \"bdpt\" is not implemented by cachert (available: {}); choose one with --integrator",
        cachert::integrator::integrator_names()
    );
    let cases: [(&[&str], &str); 6] = [
        (
            &["render", "bad.pbrt", "--outfile", "out.exr"],
            "error: bad.pbrt:6:16: sphere \"radius\" must be positive and finite, got -1",
        ),
        // These fail after the scene loaded.
        (
            &["render", "good.pbrt", "--outfile", "out.exr", "--set", "nsample=4"],
            "error: --set nsample=4: integrator \"ambientocclusion\" has no parameter \"nsample\" (it reads: cossample, maxdistance, nsamples)",
        ),
        (
            &["render", "good.pbrt", "--outfile", "out.exr", "--set", "nsamples=many"],
            "error: --set nsamples=many: expected an integer",
        ),
        (&["render", "good.pbrt", "--outfile", "out.exr", "--integrator", "bdpt"], &path_message),
        (
            &["render", "good.pbrt", "--outfile", "out.xyz"],
            "error: --outfile: \"out.xyz\": unknown image file extension; use .exr, .pfm or .png",
        ),
        (
            &["render", "good.pbrt", "--outfile", "no/such/dir/out.exr"],
            "error: --outfile no/such/dir/out.exr: the folder \"no/such/dir\" does not exist",
        ),
    ];
    for (args, first_line) in cases {
        let o = cachert(&dir, args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = stderr(&o);
        assert!(err.lines().any(|l| l == first_line), "{args:?}: stderr was\n{err}");
        // Neither the image nor a temporary file is left (hidden names included).
        assert_eq!(dir.entries(), vec!["bad.pbrt", "good.pbrt"], "{args:?}");
    }
}

#[test]
fn failed_run_keeps_an_existing_output_intact() {
    let dir = TempDir::new("bin-keep-output");
    dir.write("good.pbrt", world("Shape \"sphere\""));
    let old = dir.write("out.pfm", "the previous image");
    let o = cachert(&dir, &["render", "good.pbrt", "--outfile", "out.pfm", "--set", "nsamples=0", "--quiet"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&old).expect("still there"), "the previous image");
    assert_eq!(dir.entries(), vec!["good.pbrt", "out.pfm"]);
}

#[test]
fn successful_run_writes_only_the_image() {
    let dir = TempDir::new("bin-ok");
    dir.write("empty.pbrt", world(""));
    let o = cachert(&dir, &["render", "empty.pbrt", "--outfile", "out.pfm", "--quiet"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(dir.entries(), vec!["empty.pbrt", "out.pfm"]);
    let im = cachert::image::read(&dir.path("out.pfm")).expect("a PFM");
    assert_eq!((im.width, im.height), (4, 4));
    assert!(im.pixels.iter().all(|p| *p == [0.0; 3]), "an empty world is black");
}
