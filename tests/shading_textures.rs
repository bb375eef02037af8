//! Textures against pbrt-v3 itself, and their bad-input behaviour.
//!
//! Each scene in `tests/data/pbrt-v3/textures` is one textured matte square filling an orthographic
//! 64×64 view, lit by a distant light of radiance π along the view direction; pbrt-v3's `directlighting`
//! rendered it twice (`make.sh`): `-a` with 256 random samples per pixel, `-b` with a stratified 16×16
//! jittered sampler. The test does not go through cachert's integrators: it forms the closed form
//! directly, isolating the textures: for 610 lattice points in each pixel it traces cachert's camera ray, intersects the
//! square, evaluates the texture at the hit and takes Kd·L·|cos θ|/π (pbrt-v3's Lambertian clamps Kd at 0).
//! The pixel means must match pbrt-v3's `-a` image within its noise, RMSE(ours, a) ≤ 1.3·RMSE(a, b)
//! (the two references' disagreement bounds a's noise from above), and the image mean within 1 %.
//! Set `TEX_DUMP=<folder>` to write cachert's images there as `<scene>.pfm` for inspection.

mod common;

use std::path::{Path, PathBuf};

use cachert::image::{self, Image};
use cachert::metrics::rmse;
use cachert::scene::props::Prop;
use cachert::scene::{LoadOptions, Scene, load, load_str};
use cachert::shading::texture::Textures;
use cachert::{Warning, Warnings};
use common::TempDir;
use glam::Vec3A;

/// The distant light's radiance in the scenes ("rgb L" [3.14159265 …], which is π in f32).
const L: f32 = std::f32::consts::PI;
/// Points per pixel of the closed-form estimate: a Fibonacci lattice (F₁₅ points, generator F₁₄), whose
/// projections on both axes are evenly spaced, so axis-aligned texture edges (checks, the wrap of `uv`)
/// are integrated to within 1/(2·610) of a pixel — a plain n×n grid would put every point of a row on
/// the same side of a horizontal edge and bias whole rows of pixels by up to 1/(2n).
const LATTICE: (usize, usize) = (610, 377);

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pbrt-v3/textures")
}

/// The spectrum texture the material at `si` reads as Kd.
fn kd_texture(scene: &Scene, material: u32) -> u32 {
    match scene.materials[material as usize].props.get("Kd") {
        Some(Prop::SpectrumTexture(id)) => *id,
        other => panic!("the test scenes give Kd as a texture, found {other:?}"),
    }
}

/// The closed-form image of a scene: per pixel, the mean over the lattice points of Kd·L·|cos|/π.
fn closed_form(scene: &Scene, textures: &Textures) -> Image {
    let [w, h] = [scene.film.resolution[0] as usize, scene.film.resolution[1] as usize];
    let to_light = Vec3A::Z;
    let mut img = Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let mut sum = Vec3A::ZERO;
            let (n, g) = LATTICE;
            for i in 0..n {
                let (u, v) = ((i as f64 + 0.5) / n as f64, ((i * g) % n) as f64 / n as f64 + 0.5 / n as f64);
                let p = [x as f32 + u as f32, y as f32 + v as f32];
                let ray = scene.camera.generate_ray(p, [0.5, 0.5]);
                let Some(si) = scene.geometry.intersect(&ray) else { continue };
                let kd = textures.spectrum(kd_texture(scene, si.material), &si).max(Vec3A::ZERO);
                sum += kd * L * si.ns.dot(to_light).abs() / std::f32::consts::PI;
            }
            img.set(x, y, (sum / n as f32).into());
        }
    }
    img
}

fn mean(im: &Image) -> f64 {
    let m = im.mean();
    (m[0] + m[1] + m[2]) / 3.0
}

/// Loads `scene.pbrt` (or `text` in its place) and builds its textures.
fn prepare(name: &str, text: Option<&str>) -> (Scene, Textures, Warnings) {
    let path = data_dir().join(format!("{name}.pbrt"));
    let loaded = match text {
        Some(t) => load_str(t, &path, LoadOptions::default()),
        None => load(&path, LoadOptions::default()),
    }
    .unwrap_or_else(|e| panic!("{name}: {e}"));
    let mut warnings = loaded.warnings;
    let textures = Textures::build(&loaded.scene, &mut warnings).expect("textures build");
    (loaded.scene, textures, warnings)
}

/// RMSE against pbrt-v3's `-a` image over its noise floor, and the relative mean difference.
fn compare(name: &str, ours: &Image) -> (f64, f64) {
    let dir = data_dir();
    let a = image::read(&dir.join(format!("{name}-a.pfm"))).expect("reference a");
    let b = image::read(&dir.join(format!("{name}-b.pfm"))).expect("reference b");
    let floor = rmse(&a, &b).expect("same size");
    let err = rmse(ours, &a).expect("same size");
    let err_b = rmse(ours, &b).expect("same size");
    let ratio = err / floor.max(1e-6);
    let mean_dev = (mean(ours) - mean(&a)).abs() / mean(&a);
    eprintln!(
        "{name}: RMSE vs pbrt-v3 (random) {err:.5}, noise floor RMSE(a, b) {floor:.5}, ratio {ratio:.3}; \
         RMSE vs pbrt-v3 (stratified) {err_b:.5}; mean {:.5} vs {:.5} ({:+.3} %)",
        mean(ours),
        mean(&a),
        100.0 * (mean(ours) - mean(&a)) / mean(&a)
    );
    (ratio, mean_dev)
}

fn check(name: &str) {
    let (scene, textures, warnings) = prepare(name, None);
    assert!(warnings.is_empty(), "{name}: unexpected warnings {:?}", warnings.iter().collect::<Vec<_>>());
    let ours = closed_form(&scene, &textures);
    if let Some(dir) = std::env::var_os("TEX_DUMP") {
        image::write(&ours, &Path::new(&dir).join(format!("{name}.pfm"))).unwrap();
    }
    let (ratio, mean_dev) = compare(name, &ours);
    assert!(ratio <= 1.3, "{name}: RMSE is {ratio:.3}× pbrt-v3's noise floor (limit 1.3)");
    assert!(mean_dev <= 0.01, "{name}: mean differs from pbrt-v3's by {:.3} % (limit 1 %)", 100.0 * mean_dev);
}

#[test]
fn checkerboard_uv_mapping_with_scale_and_delta() {
    check("checker-uv");
}

#[test]
fn checkerboard_planar_mapping() {
    check("checker-planar");
}

#[test]
fn checkerboard_3d_in_texture_space() {
    check("checker-3d");
}

#[test]
fn uv_texture_spherical_mapping() {
    check("uv-spherical");
}

#[test]
fn uv_texture_cylindrical_mapping() {
    check("uv-cylindrical");
}

#[test]
fn bilerp_texture() {
    check("bilerp");
}

#[test]
fn scale_and_mix_of_textures() {
    check("scale-mix");
}

#[test]
fn dots_texture() {
    check("dots");
}

#[test]
fn png_imagemap_srgb_with_ewa_filter() {
    check("png-ewa");
}

#[test]
fn png_imagemap_non_power_of_two_bilinear_scaled() {
    check("png-trilinear-npot");
}

#[test]
fn png_imagemap_repeat_without_gamma() {
    check("png-repeat");
}

#[test]
fn tga_float_imagemap_drives_mix() {
    check("tga-float-mix");
}

#[test]
fn pfm_imagemap_clamp_wrap() {
    check("pfm-clamp");
}

#[test]
fn exr_imagemap_black_wrap() {
    check("exr-black");
}

/// pbrt-v3 cannot decode truncated.png and renders a grey 0.5 texel, sRGB-decoded and scaled by 2
/// (0.42808 everywhere); so must we, with a warning at the texture.
#[test]
fn truncated_png_is_pbrt_v3s_grey_with_a_warning() {
    let (scene, textures, warnings) = prepare("truncated", None);
    let w: Vec<&Warning> = warnings.iter().collect();
    assert_eq!(w.len(), 1, "{w:?}");
    let loc = w[0].loc.as_ref().expect("a location");
    assert!(loc.file.ends_with("truncated.pbrt") && loc.line == 11, "{loc}");
    assert!(w[0].msg.contains("truncated.png"), "{}", w[0].msg);
    let ours = closed_form(&scene, &textures);
    let a = image::read(&data_dir().join("truncated-a.pfm")).expect("reference");
    assert!(rmse(&ours, &a).unwrap() < 1e-5, "{} vs pbrt-v3 {}", mean(&ours), mean(&a));
}

/// The test can fail: the same PNG looked up bilinearly (pbrt-v3's trilinear path) is far outside the
/// noise of pbrt-v3's default (EWA) image, so the EWA match above is not luck.
#[test]
fn bilinear_lookup_would_not_match_pbrt_v3s_ewa() {
    let text = std::fs::read_to_string(data_dir().join("png-ewa.pbrt")).unwrap();
    let text = text.replace("\"rand8.png\"", "\"rand8.png\" \"bool trilinear\" \"true\"");
    let (scene, textures, _) = prepare("png-ewa", Some(&text));
    let (ratio, _) = compare("png-ewa", &closed_form(&scene, &textures));
    assert!(ratio > 3.0, "bilinear is only {ratio:.3}× the noise floor away from pbrt-v3's EWA image");
}

// ---- Bad input and bookkeeping, at the centre of a unit square ----

/// Writes a scene with `textures` (and Kd = texture "tex") into `dir` and returns its path.
fn scene_with(dir: &TempDir, textures: &str) -> PathBuf {
    let text = format!(
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"orthographic\"\n\
         Film \"image\" \"integer xresolution\" [4] \"integer yresolution\" [4]\nWorldBegin\n\
         {textures}\nMaterial \"matte\" \"texture Kd\" \"tex\"\n\
         Shape \"trianglemesh\" \"point P\" [-1 -1 0 1 -1 0 1 1 0 -1 1 0] \"float uv\" [0 0 1 0 1 1 0 1]\n\
         \"integer indices\" [0 1 2 0 2 3]\nWorldEnd\n"
    );
    dir.write("scene.pbrt", text)
}

/// Kd at film point `p` (raster units of the 4×4 image), with the warnings of loading and building.
fn kd_at(path: &Path, p: [f32; 2]) -> (Vec3A, Vec<Warning>, Textures) {
    let loaded = load(path, LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let mut warnings = loaded.warnings;
    let textures = Textures::build(&loaded.scene, &mut warnings).expect("textures build");
    let scene = &loaded.scene;
    let si = scene.geometry.intersect(&scene.camera.generate_ray(p, [0.5, 0.5])).expect("the square is hit");
    let kd = textures.spectrum(kd_texture(scene, si.material), &si);
    (kd, warnings.iter().cloned().collect(), textures)
}

fn assert_close(v: Vec3A, want: [f32; 3]) {
    assert!((v - Vec3A::from(want)).abs().max_element() < 1e-5, "{v} vs {want:?}");
}

#[test]
fn a_file_that_is_not_an_image_is_grey_with_a_warning() {
    let dir = TempDir::new("tex-notimage");
    dir.write("bad.png", "this is not a PNG file");
    let path = scene_with(&dir, "Texture \"tex\" \"spectrum\" \"imagemap\" \"string filename\" \"bad.png\"");
    let (kd, w, _) = kd_at(&path, [2.0, 2.0]);
    assert_close(kd, [0.214_041_14; 3]);
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!(w[0].loc.as_ref().map(|l| l.line), Some(5));
    assert!(w[0].msg.contains("bad.png") && w[0].msg.contains("grey"), "{}", w[0].msg);
}

#[test]
fn an_image_of_size_zero_is_grey_with_a_warning() {
    let dir = TempDir::new("tex-empty");
    dir.write("empty.pfm", "PF\n0 0\n-1\n");
    let path = scene_with(
        &dir,
        "Texture \"tex\" \"spectrum\" \"imagemap\" \"string filename\" \"empty.pfm\" \"float scale\" [3]",
    );
    let (kd, w, _) = kd_at(&path, [2.0, 2.0]);
    assert_close(kd, [1.5; 3]);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].msg.contains("empty.pfm"), "{}", w[0].msg);
}

#[test]
fn a_truncated_pfm_is_grey_with_a_warning() {
    let dir = TempDir::new("tex-truncpfm");
    dir.write("cut.pfm", b"PF\n4 4\n-1\n\x00\x00\x80\x3f\x00\x00");
    let path = scene_with(
        &dir,
        "Texture \"f\" \"float\" \"imagemap\" \"string filename\" \"cut.pfm\"\n\
         Texture \"tex\" \"spectrum\" \"constant\"",
    );
    // The float texture (id 0) is pbrt-v3's grey 0.5 (no gamma for PFM).
    let loaded = load(&path, LoadOptions::default()).unwrap();
    let mut warnings = loaded.warnings;
    let textures = Textures::build(&loaded.scene, &mut warnings).unwrap();
    assert!(warnings.iter().any(|w| w.msg.contains("cut.pfm")));
    let scene = &loaded.scene;
    let si = scene.geometry.intersect(&scene.camera.generate_ray([2.0, 2.0], [0.5, 0.5])).unwrap();
    assert!((textures.float(0, &si) - 0.5).abs() < 1e-6);
}

#[test]
fn mix_with_a_missing_amount_texture_uses_half_and_warns() {
    let dir = TempDir::new("tex-mixmissing");
    let path = scene_with(
        &dir,
        "Texture \"tex\" \"spectrum\" \"mix\" \"rgb tex1\" [1 0 0] \"rgb tex2\" [0 0 1] \"texture amount\" \"nosuch\"",
    );
    let (kd, w, _) = kd_at(&path, [2.0, 2.0]);
    assert_close(kd, [0.5, 0.0, 0.5]);
    assert!(w.iter().any(|w| w.msg.contains("nosuch")), "{w:?}");
}

#[test]
fn unsupported_classes_warn_once_each_with_their_line() {
    let dir = TempDir::new("tex-fbm");
    let path = scene_with(
        &dir,
        "Texture \"bumps\" \"float\" \"fbm\" \"integer octaves\" [4]\n\
         Texture \"m\" \"spectrum\" \"marble\"\n\
         Texture \"tex\" \"spectrum\" \"scale\" \"texture tex1\" \"m\" \"rgb tex2\" [0.5 0.25 1]",
    );
    let (kd, w, _) = kd_at(&path, [1.0, 3.0]);
    assert_close(kd, [0.5, 0.25, 1.0]);
    assert_eq!(w.len(), 2, "{w:?}");
    assert!(w[0].msg.contains("\"fbm\"") && w[0].loc.as_ref().unwrap().line == 5, "{:?}", w[0]);
    assert!(w[1].msg.contains("\"marble\"") && w[1].loc.as_ref().unwrap().line == 6, "{:?}", w[1]);
}

#[test]
fn unknown_mapping_and_wrap_fall_back_with_warnings() {
    let dir = TempDir::new("tex-badmap");
    let one = [b"PF\n1 1\n-1\n".as_slice(), &[0.25f32, 0.5, 1.0].map(f32::to_le_bytes).concat()].concat();
    dir.write("one.pfm", one);
    let path = scene_with(
        &dir,
        "Texture \"tex\" \"spectrum\" \"uv\" \"string mapping\" \"cubic\" \"float uscale\" [2]\n\
         Texture \"img\" \"spectrum\" \"imagemap\" \"string filename\" \"one.pfm\" \"string wrap\" \"mirror\"",
    );
    // Film point (2, 1) of 4×4 is world (0, 0.5): uv (0.5, 0.75); the fallback uv mapping is unscaled,
    // as pbrt-v3's (uscale is dropped with the unknown mapping).
    let (kd, w, _) = kd_at(&path, [2.0, 1.0]);
    assert_close(kd, [0.5, 0.75, 0.0]);
    assert!(w.iter().any(|w| w.msg.contains("\"cubic\"")), "{w:?}");
    assert!(w.iter().any(|w| w.msg.contains("\"mirror\"")), "{w:?}");
}

#[test]
fn deep_nesting_is_cut_with_a_warning() {
    let dir = TempDir::new("tex-deep");
    let mut text = String::from("Texture \"t0\" \"spectrum\" \"constant\" \"rgb value\" [0.5 0.5 0.5]\n");
    for i in 1..=80 {
        text += &format!("Texture \"t{i}\" \"spectrum\" \"scale\" \"texture tex1\" \"t{}\"\n", i - 1);
    }
    text += "Texture \"tex\" \"spectrum\" \"scale\" \"texture tex1\" \"t80\"";
    let path = scene_with(&dir, &text);
    let (kd, w, _) = kd_at(&path, [2.0, 2.0]);
    assert!(kd.is_finite());
    assert!(w.iter().any(|w| w.msg.contains("nests more than")), "{w:?}");
}

#[test]
fn images_shared_by_textures_are_loaded_once() {
    let dir = TempDir::new("tex-cache");
    let png = std::fs::read(data_dir().join("rand8.png")).unwrap();
    dir.write("a.png", &png);
    let path = scene_with(
        &dir,
        "Texture \"x\" \"spectrum\" \"imagemap\" \"string filename\" \"a.png\" \"float uscale\" [2]\n\
         Texture \"y\" \"spectrum\" \"imagemap\" \"string filename\" \"a.png\" \"float vdelta\" [0.5]\n\
         Texture \"z\" \"spectrum\" \"imagemap\" \"string filename\" \"a.png\" \"float scale\" [2]\n\
         Texture \"f\" \"float\" \"imagemap\" \"string filename\" \"a.png\"\n\
         Texture \"tex\" \"spectrum\" \"scale\" \"texture tex1\" \"x\" \"texture tex2\" \"y\"",
    );
    let (kd, _, textures) = kd_at(&path, [2.0, 2.0]);
    assert!(kd.is_finite());
    // x and y share one image; z (other scale) and f (float) need their own.
    assert_eq!(textures.image_count(), 3);
}

#[test]
fn png_texels_are_srgb_decoded_and_flipped() {
    // A 1×2 PNG: top pixel 188 (sRGB 0.737 → linear 0.5029), bottom pixel 0. t = 0 is the bottom row,
    // so with point-like lookups near t = 1 we see the top pixel.
    let dir = TempDir::new("tex-png");
    let img = Image::from_pixels(1, 2, vec![[0.502_886; 3], [0.0; 3]]).unwrap();
    image::write(&img, &dir.path("two.png")).unwrap();
    let path = scene_with(
        &dir,
        "Texture \"tex\" \"spectrum\" \"imagemap\" \"string filename\" \"two.png\" \"string wrap\" \"clamp\"",
    );
    let (top, w, _) = kd_at(&path, [2.0, 0.1]);
    assert!(w.is_empty(), "{w:?}");
    assert!((top.x - 0.502_886).abs() < 2e-3, "{top}");
    let (bottom, _, _) = kd_at(&path, [2.0, 3.9]);
    assert!(bottom.x.abs() < 1e-6, "{bottom}");
}

/// An uncompressed 24-bit TGA of a 1×2 image (top pixel `top`, bottom pixel `bottom`, grey levels),
/// stored with its rows in either order (image descriptor bit 5: top-left origin).
fn tga_1x2(top: u8, bottom: u8, top_origin: bool) -> Vec<u8> {
    let mut v = vec![0u8, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 2, 0, 24, if top_origin { 0x20 } else { 0 }];
    let rows = if top_origin { [top, bottom] } else { [bottom, top] };
    for g in rows {
        v.extend([g, g, g]);
    }
    v
}

#[test]
fn tga_rows_are_read_in_either_storage_order() {
    // The shared scenes' TGAs are stored top row first, the test image rand8.tga bottom row first.
    for top_origin in [false, true] {
        let dir = TempDir::new("tex-tga");
        dir.write("two.tga", tga_1x2(188, 0, top_origin));
        let path = scene_with(
            &dir,
            "Texture \"tex\" \"spectrum\" \"imagemap\" \"string filename\" \"two.tga\" \"string wrap\" \"clamp\"",
        );
        let (top, w, _) = kd_at(&path, [2.0, 0.1]);
        assert!(w.is_empty(), "{w:?}");
        assert!((top.x - 0.502_886).abs() < 1e-5, "top origin {top_origin}: {top}");
        let (bottom, _, _) = kd_at(&path, [2.0, 3.9]);
        assert!(bottom.x.abs() < 1e-6, "top origin {top_origin}: {bottom}");
    }
}

/// The shared scenes must be here: fails, with the reason, where they are absent (outside CI the tests that
/// need them print a `skipped` line and pass; under CI they fail too).
#[test]
fn shared_scenes_present() {
    common::assert_shared_scenes_present();
}

/// The hackmad texture scenes that cannot load here, with the text their error must contain: their assets
/// are not shipped with the shared scenes.
const TEXTURE_SCENES_WITHOUT_ASSETS: [(&str, &str); 1] =
    [("3d-checkerboard.pbrt", "dragon_vrip.ply\": cannot read PLY file")];

/// Every texture of the shared scenes that have textures (the staircase's and bathroom's TGAs, the hackmad
/// texture scenes) builds and gives finite values at the surfaces the camera sees. The scenes whose assets
/// are not shipped ([`TEXTURE_SCENES_WITHOUT_ASSETS`]) must fail with their error; any other scene that is
/// absent or does not load is a failure under CI and a printed skip elsewhere.
#[test]
fn shared_scene_textures_build_and_evaluate() {
    let Some(root) = common::shared_scenes() else { return };
    let mut scenes: Vec<PathBuf> = ["bitterli-staircase2/scene-v3.pbrt", "bitterli-bathroom/scene-v3.pbrt"]
        .iter()
        .filter_map(|f| common::shared_file(&root, f))
        .collect();
    if let Some(hackmad) = common::shared_file(&root, "hackmad-pbrt-v3-rs-tests/textures") {
        let mut names: Vec<PathBuf> = std::fs::read_dir(&hackmad).unwrap().map(|e| e.unwrap().path()).collect();
        names.sort();
        scenes.extend(names);
    }
    for path in scenes {
        let small = LoadOptions { resolution: Some([16, 16]), ..LoadOptions::default() };
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let expected_error = TEXTURE_SCENES_WITHOUT_ASSETS.iter().find(|(n, _)| *n == name).map(|(_, e)| *e);
        let loaded = match (load(&path, small), expected_error) {
            (Ok(l), None) => l,
            (Err(e), Some(expected)) => {
                assert!(e.to_string().contains(expected), "{}: {e}", path.display());
                continue;
            }
            (Ok(_), Some(_)) => panic!("{} loads: take it off TEXTURE_SCENES_WITHOUT_ASSETS", path.display()),
            (Err(e), None) => {
                common::unavailable(&format!("{} does not load: {e}", path.display()));
                continue;
            }
        };
        let t = std::time::Instant::now();
        let mut warnings = loaded.warnings;
        let textures = Textures::build(&loaded.scene, &mut warnings).expect("textures build");
        let scene = &loaded.scene;
        let mut hits = 0;
        for y in 0..16 {
            for x in 0..16 {
                let ray = scene.camera.generate_ray([x as f32 + 0.5, y as f32 + 0.5], [0.5, 0.5]);
                let Some(si) = scene.geometry.intersect(&ray) else { continue };
                hits += 1;
                for id in 0..scene.textures.len() as u32 {
                    let v = textures.spectrum(id, &si);
                    assert!(v.is_finite(), "{}: texture {id} gives {v} at pixel ({x}, {y})", path.display());
                }
            }
        }
        eprintln!(
            "{}: {} textures, {} images, built in {:.2} s, {hits} hits evaluated",
            path.display(),
            scene.textures.len(),
            textures.image_count(),
            t.elapsed().as_secs_f64()
        );
    }
}
