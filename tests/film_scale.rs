//! The Film's `"float scale"` and `"float maxsampleluminance"` reach every integrator's image (issue 41):
//! the three per-pixel integrators (`path`, `directlighting`, `ambientocclusion`) and the three cache-based
//! ones (`cacheao`, `importancecache`, `irradiancecache`, the last with `output full`, whose per-pixel
//! direct term was once scaled alone).
//!
//! Scale is exact here, not just to rounding: every integrator's finished image is multiplied by the scale
//! once, pixel by pixel in f32 (`render::film::apply_scale`, as pbrt-v3's `Film::WriteImage` does), after
//! every sum and average, and nothing before it depends on the scale; the renders are deterministic, so
//! the image with scale 3 is bit for bit the image without it times 3.0f32, the product this test takes.

use std::path::Path;

use cachert::Warnings;
use cachert::image::Image;
use cachert::integrator::{RenderSettings, render};
use cachert::scene::{LoadOptions, load_str};

/// A lit wall with a bright emitting sphere in front of it, seen from 5 units away; `film` is added to the
/// Film line.
fn scene(film: &str) -> String {
    format!(
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n\
         Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16 {film}\n\
         Sampler \"random\" \"integer pixelsamples\" 2\nPixelFilter \"box\"\n\
         WorldBegin\n\
         LightSource \"point\" \"point from\" [1 1 3] \"rgb I\" [8 8 8]\n\
         Shape \"trianglemesh\" \"point P\" [-4 -4 0  4 -4 0  4 4 0  -4 4 0] \"integer indices\" [0 1 2 0 2 3]\n\
         AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [50 50 50]\nTranslate 0 0 1\n\
         Shape \"sphere\" \"float radius\" 0.4\nAttributeEnd\n\
         WorldEnd\n"
    )
}

/// Each integrator with small settings, so that a render takes milliseconds.
const INTEGRATORS: [(&str, &[(&str, &str)]); 6] = [
    ("path", &[("maxdepth", "2")]),
    ("directlighting", &[]),
    ("ambientocclusion", &[("nsamples", "2")]),
    ("cacheao", &[("caches", "8"), ("gather", "4"), ("subpixels", "2")]),
    ("importancecache", &[("caches", "8"), ("vpls", "64"), ("subpixels", "2")]),
    ("irradiancecache", &[("caches", "8"), ("gather", "4"), ("subpixels", "2"), ("output", "full")]),
];

/// Renders `text` with `integrator` and `--set` pairs `set`, seed 3; returns the image and the warnings.
fn render_text(text: &str, integrator: &str, set: &[(&str, &str)]) -> (Image, Vec<String>) {
    let loaded = load_str(text, Path::new("film.pbrt"), LoadOptions::default()).expect("loads");
    let mut w: Warnings = loaded.warnings.clone();
    let settings = RenderSettings {
        integrator: Some(integrator.to_string()),
        set: set.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
        seed: 3,
        ..Default::default()
    };
    let out = render(&loaded.scene, loaded.integrator.as_ref(), &settings, &mut w)
        .unwrap_or_else(|e| panic!("{integrator}: {e}"));
    (out.image, w.iter().map(|w| w.to_string()).collect())
}

fn luminance(p: [f32; 3]) -> f32 {
    0.212671 * p[0] + 0.715160 * p[1] + 0.072169 * p[2]
}

fn check_scale(integrator: &str, set: &[(&str, &str)]) {
    let (plain, _) = render_text(&scene(""), integrator, set);
    let (scaled, warnings) = render_text(&scene("\"float scale\" [3]"), integrator, set);
    assert!(plain.pixels.iter().any(|p| p.iter().any(|&v| v > 0.0)), "{integrator}: a black image tests nothing");
    let expected: Vec<[f32; 3]> = plain.pixels.iter().map(|p| p.map(|v| v * 3.0)).collect();
    let off = scaled.pixels.iter().zip(&expected).filter(|(a, b)| a != b).count();
    let (i, _) = scaled
        .pixels
        .iter()
        .zip(&expected)
        .enumerate()
        .find(|(_, (a, b))| a != b)
        .unwrap_or((0, (&[0.0; 3], &[0.0; 3])));
    assert_eq!(
        off, 0,
        "{integrator}: {off} pixels are not 3 × the unscaled image (first: pixel {i}, {:?} against 3 × {:?})",
        scaled.pixels[i], plain.pixels[i]
    );
    assert!(!warnings.iter().any(|w| w.contains("scale")), "{integrator}: {warnings:#?}");
}

#[test]
fn scale_multiplies_the_path_image() {
    check_scale(INTEGRATORS[0].0, INTEGRATORS[0].1);
}

#[test]
fn scale_multiplies_the_directlighting_image() {
    check_scale(INTEGRATORS[1].0, INTEGRATORS[1].1);
}

#[test]
fn scale_multiplies_the_ambientocclusion_image() {
    check_scale(INTEGRATORS[2].0, INTEGRATORS[2].1);
}

#[test]
fn scale_multiplies_the_cacheao_image() {
    check_scale(INTEGRATORS[3].0, INTEGRATORS[3].1);
}

#[test]
fn scale_multiplies_the_importancecache_image() {
    check_scale(INTEGRATORS[4].0, INTEGRATORS[4].1);
}

#[test]
fn scale_multiplies_the_irradiancecache_full_image_once() {
    check_scale(INTEGRATORS[5].0, INTEGRATORS[5].1);
}

/// The centre pixel sees only the emitting sphere (L = 50, luminance 50); every sample of it is clamped to
/// luminance 5, so the pixel's luminance is 5 to rounding, and no pixel is brighter.
fn check_clamp(integrator: &str, set: &[(&str, &str)]) {
    let (plain, _) = render_text(&scene(""), integrator, set);
    let (clamped, warnings) = render_text(&scene("\"float maxsampleluminance\" [5]"), integrator, set);
    let centre = |im: &Image| luminance(im.get(8, 8));
    assert!(centre(&plain) > 40.0, "{integrator}: the centre does not see the emitter ({})", centre(&plain));
    assert!((centre(&clamped) - 5.0).abs() < 5e-5, "{integrator}: centre luminance {}", centre(&clamped));
    let max = clamped.pixels.iter().map(|&p| luminance(p)).fold(0.0, f32::max);
    assert!(max < 5.0 * (1.0 + 1e-5), "{integrator}: a pixel of luminance {max}");
    assert!(!warnings.iter().any(|w| w.contains("maxsampleluminance")), "{integrator}: {warnings:#?}");
}

#[test]
fn maxsampleluminance_clamps_each_sample_of_a_cache_integrator() {
    check_clamp(INTEGRATORS[4].0, INTEGRATORS[4].1);
}

#[test]
fn maxsampleluminance_still_clamps_each_sample_of_a_per_pixel_integrator() {
    check_clamp(INTEGRATORS[1].0, INTEGRATORS[1].1);
}
