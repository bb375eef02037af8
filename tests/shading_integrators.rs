//! Behaviour of the per-pixel `directlighting` and `path` integrators beyond agreement with pbrt-v3: closed
//! forms, scenes without lights, bad parameters, and the same image for any thread count.

mod common;

use std::path::Path;

use cachert::Warnings;
use cachert::integrator::{RenderOutput, RenderSettings, render};
use cachert::scene::{LoadOptions, load_str};

fn run(text: &str, settings: RenderSettings) -> cachert::Result<(RenderOutput, Vec<String>)> {
    let loaded = load_str(text, Path::new("shade.pbrt"), LoadOptions::default()).expect("loads");
    let mut w: Warnings = loaded.warnings.clone();
    let out = render(&loaded.scene, loaded.integrator.as_ref(), &settings, &mut w)?;
    Ok((out, w.iter().map(|w| w.to_string()).collect()))
}

fn with(integrator: &str, set: &[(&str, &str)]) -> RenderSettings {
    RenderSettings {
        integrator: Some(integrator.into()),
        set: set.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
        spp: Some(4),
        ..Default::default()
    }
}

/// A unit-Kd-0.5 matte square filling the view, camera looking down −z; `lights` go in the world block.
fn plane(lights: &str) -> String {
    format!(
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 20\n\
         Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8\nSampler \"random\"\n\
         WorldBegin\n{lights}\nMaterial \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n\
         Shape \"trianglemesh\" \"point P\" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] \"integer indices\" [0 1 2 0 2 3]\n\
         WorldEnd\n"
    )
}

#[test]
fn a_scene_without_lights_renders_black_with_a_warning() {
    for integrator in ["directlighting", "path"] {
        let (out, warnings) = run(&plane(""), with(integrator, &[])).expect("renders");
        assert!(out.image.pixels.iter().all(|p| *p == [0.0; 3]), "{integrator}: black");
        assert!(warnings.iter().any(|w| w.contains("no light")), "{integrator}: {warnings:#?}");
    }
}

#[test]
fn a_distant_light_on_a_matte_plane_gives_the_closed_form() {
    // Radiance of a Lambertian plane of albedo ρ under a distant light of radiance-scale L at normal
    // incidence: ρ/π · L (the distant light delivers irradiance L). Exact for every sample: no noise.
    let scene = plane("LightSource \"distant\" \"point from\" [0 0 1] \"point to\" [0 0 0] \"rgb L\" [2 3 4]");
    for integrator in ["directlighting", "path"] {
        let (out, _) = run(&scene, with(integrator, &[])).expect("renders");
        for p in &out.image.pixels {
            for (k, l) in [2.0f32, 3.0, 4.0].iter().enumerate() {
                let want = 0.5 / std::f32::consts::PI * l;
                assert!((p[k] - want).abs() < 1e-4 * want, "{integrator}: {p:?} vs {want}");
            }
        }
    }
}

#[test]
fn bad_integrator_parameters_are_located_errors() {
    let scene = plane("LightSource \"point\" \"point from\" [0 0 1]");
    for (integrator, key, value) in
        [("directlighting", "maxdepth", "-1"), ("path", "maxdepth", "-3"), ("path", "rrthreshold", "-2")]
    {
        let e = run(&scene, with(integrator, &[(key, value)])).expect_err("refused");
        assert!(e.to_string().contains(key), "{integrator}: {e}");
    }
}

#[test]
fn unknown_strategies_fall_back_with_a_warning() {
    let scene = plane("LightSource \"point\" \"point from\" [0 0 1]");
    let (_, w) = run(&scene, with("directlighting", &[("strategy", "some")])).expect("renders");
    assert!(w.iter().any(|w| w.contains("unknown strategy")), "{w:#?}");
    let (_, w) = run(&scene, with("path", &[("lightsamplestrategy", "some")])).expect("renders");
    assert!(w.iter().any(|w| w.contains("unknown light sample strategy")), "{w:#?}");
}

#[test]
fn same_image_for_any_thread_count() {
    let scene = plane(
        "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\nTranslate 0 0 2\n\
         Shape \"sphere\" \"float radius\" 0.3\nAttributeEnd\nMaterial \"plastic\"\n\
         Translate 0.3 0 0.5\nShape \"sphere\" \"float radius\" 0.3",
    );
    for integrator in ["directlighting", "path"] {
        let one = run(&scene, RenderSettings { threads: Some(1), ..with(integrator, &[]) }).expect("renders").0;
        let two = run(&scene, RenderSettings { threads: Some(2), ..with(integrator, &[]) }).expect("renders").0;
        assert_eq!(one.image.pixels, two.image.pixels, "{integrator}");
    }
}
