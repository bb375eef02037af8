//! Nothing a user sets is dropped without a word (issue 9): settings a cache-based integrator honours
//! change what it does (`--spp` and `--quick` set the sub-pixel sample count), and the ones it cannot use
//! (the scene's Sampler and PixelFilter, the parameters of an Integrator replaced by `--integrator`) are
//! named in a warning at the line that set them. The Film's scale and sample clamp are honoured by every
//! integrator (tests/film_scale.rs), so they get none.

mod common;

use std::path::Path;

use cachert::Warnings;
use cachert::integrator::{RenderOutput, RenderSettings, render};
use cachert::scene::{LoadOptions, load_str};

const WORLD: &str = "WorldBegin\nShape \"trianglemesh\" \"point P\" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] \
                     \"integer indices\" [0 1 2 0 2 3]\nShape \"sphere\" \"float radius\" 0.5\nWorldEnd\n";

fn scene(options: &str, integrator: &str) -> String {
    format!(
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n\
         Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16\n{options}\n{integrator}\n{WORLD}"
    )
}

fn run(text: &str, settings: RenderSettings) -> (RenderOutput, Vec<String>) {
    let loaded = load_str(text, Path::new("flags.pbrt"), LoadOptions::default()).expect("loads");
    let mut w: Warnings = loaded.warnings.clone();
    let out = render(&loaded.scene, loaded.integrator.as_ref(), &settings, &mut w).expect("renders");
    (out, w.iter().map(|w| w.to_string()).collect())
}

fn cache(set: &[(&str, &str)]) -> RenderSettings {
    RenderSettings {
        integrator: Some("cacheao".into()),
        set: set.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
        ..Default::default()
    }
}

const CACHES: (&str, &str) = ("caches", "20");

#[test]
fn spp_sets_the_sub_pixel_count_of_a_cache_render() {
    let (out, warnings) = run(&scene("", ""), RenderSettings { spp: Some(2), ..cache(&[CACHES]) });
    assert_eq!(out.spp, 2, "--spp 2 gives 2 sub-pixel samples");
    assert!(warnings.is_empty(), "{warnings:#?}");
    let (out, _) = run(&scene("", ""), RenderSettings { quick: true, ..cache(&[CACHES]) });
    assert_eq!(out.spp, 1, "--quick gives one sample per pixel");
}

#[test]
fn spp_is_named_when_subpixels_wins() {
    let (out, warnings) = run(&scene("", ""), RenderSettings { spp: Some(2), ..cache(&[CACHES, ("subpixels", "3")]) });
    assert_eq!(out.spp, 3);
    assert!(warnings.iter().any(|w| w.contains("--spp (2 samples per pixel) is not used")), "{warnings:#?}");
}

#[test]
fn the_scene_sampler_and_filter_are_named_with_their_lines() {
    let options = "Sampler \"halton\" \"integer pixelsamples\" 8\nPixelFilter \"gaussian\"";
    let (_, warnings) = run(&scene(options, ""), cache(&[CACHES]));
    // Two routine facts, one note, at the Sampler's line and naming the PixelFilter's.
    let facts: Vec<_> = warnings.iter().filter(|w| w.contains("not used by cache-based integrators")).collect();
    assert_eq!(facts.len(), 1, "{warnings:#?}");
    assert!(
        facts[0].starts_with("flags.pbrt:4:")
            && facts[0].contains(": note: Sampler \"halton\" and PixelFilter (line 5) are not used"),
        "{warnings:#?}"
    );
    let (_, warnings) = run(&scene("PixelFilter \"gaussian\"", ""), cache(&[CACHES]));
    assert!(
        warnings.iter().any(|w| w.starts_with("flags.pbrt:4:") && w.contains(": note: PixelFilter is not used")),
        "{warnings:#?}"
    );
    // A box filter of radius 0.5 is what the cache driver does anyway: nothing to say.
    let (_, warnings) = run(&scene("PixelFilter \"box\"", ""), cache(&[CACHES]));
    assert!(warnings.is_empty(), "{warnings:#?}");
}

#[test]
fn film_scale_and_clamp_are_honoured_without_a_word() {
    // Issue 41: the cache driver applies both (tests/film_scale.rs), so nothing is said of them.
    let text = scene("", "").replace(
        "\"integer yresolution\" 16",
        "\"integer yresolution\" 16 \"float scale\" 2 \"float maxsampleluminance\" 10",
    );
    let (_, warnings) = run(&text, cache(&[CACHES]));
    assert!(warnings.is_empty(), "{warnings:#?}");
}

#[test]
fn a_replaced_integrator_names_its_unused_parameters() {
    let text = scene("", "Integrator \"path\" \"integer maxdepth\" 7");
    let settings = RenderSettings {
        integrator: Some("ambientocclusion".into()),
        set: vec![("nsamples".into(), "1".into())],
        ..Default::default()
    };
    let (_, warnings) = run(&text, settings);
    assert!(
        warnings.iter().any(|w| w.starts_with("flags.pbrt:5:")
            && w.contains("Integrator \"path\" is replaced by --integrator ambientocclusion")
            && w.contains("maxdepth")),
        "{warnings:#?}"
    );
}

#[test]
fn the_per_pixel_integrator_honours_the_sampler_silently() {
    let options = "Sampler \"stratified\" \"integer xsamples\" 2 \"integer ysamples\" 2\nPixelFilter \"gaussian\"";
    let (out, warnings) =
        run(&scene(options, "Integrator \"ambientocclusion\" \"integer nsamples\" 2"), RenderSettings::default());
    assert_eq!(out.spp, 4);
    assert!(warnings.is_empty(), "{warnings:#?}");
}

#[test]
fn pixelbounds_is_named_as_not_supported() {
    let text = scene("", "Integrator \"ambientocclusion\" \"integer nsamples\" 1 \"integer pixelbounds\" [0 4 0 4]");
    let (_, warnings) = run(&text, RenderSettings::default());
    assert!(
        warnings.iter().any(|w| w.starts_with("flags.pbrt:5:") && w.contains("\"pixelbounds\" is not supported")),
        "{warnings:#?}"
    );
}
