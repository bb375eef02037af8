//! Issue 41: the defaults that scale with the scene (λ, cache AO's `maxdistance`, importance caching's d_c,
//! the placement searches) read the scene's length scale L, which is bounded by what the camera sees: an
//! open scene (a small subject on a huge ground plane) gets a scale near its subject, a closed one keeps
//! its bounding-box diagonal exactly (so its images keep their bits).

use std::path::Path;

use cachert::Warnings;
use cachert::gbuffer::scale::{ScaleSource, SceneScale, VIEW_FACTOR};
use cachert::integrator::cache::ScaleReport;
use cachert::integrator::{RenderSettings, render};
use cachert::parse::integrator::json_f32;
use cachert::render::with_threads;
use cachert::scene::{LoadOptions, LoadedScene, load, load_str};

/// A unit sphere resting on an 8000×8000 ground plane, seen from 5 units away with the horizon in view:
/// the bounding-box diagonal is 11314, the sphere and the ground around it span a few units.
const OPEN: &str = "LookAt 0 -5 2  0 0 1  0 0 1\nCamera \"perspective\" \"float fov\" 40\n\
     Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 24\nWorldBegin\n\
     LightSource \"point\" \"point from\" [2 -3 5] \"rgb I\" [30 30 30]\n\
     Shape \"trianglemesh\" \"point P\" [-4000 -4000 0  4000 -4000 0  4000 4000 0  -4000 4000 0] \"integer indices\" [0 1 2 0 2 3]\n\
     AttributeBegin\nTranslate 0 0 1\nShape \"sphere\" \"float radius\" 1\nAttributeEnd\nWorldEnd\n";

/// A closed 10×8×6 box with a unit sphere inside, seen from inside (one wall behind the camera).
const CLOSED: &str = "LookAt 0 -3.5 3  0 4 1.5  0 0 1\nCamera \"perspective\" \"float fov\" 60\n\
     Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 24\nWorldBegin\n\
     LightSource \"point\" \"point from\" [0 0 5] \"rgb I\" [10 10 10]\n\
     ReverseOrientation\nShape \"trianglemesh\" \"point P\" [-5 -4 0  5 -4 0  5 4 0  -5 4 0  -5 -4 6  5 -4 6  5 4 6  -5 4 6] \
     \"integer indices\" [0 1 2 0 2 3  4 6 5 4 7 6  0 4 5 0 5 1  1 5 6 1 6 2  2 6 7 2 7 3  3 7 4 3 4 0]\n\
     AttributeBegin\nTranslate 1 1 1\nShape \"sphere\" \"float radius\" 1\nAttributeEnd\nWorldEnd\n";

/// The open scene's largest acceptable L: the trimmed box of what the camera sees (the sphere, and the
/// ground out to where 5 % of the seen points lie beyond) measures about 50 units here, so L ≈ 200; 300 is
/// under 3 % of the diagonal.
const OPEN_BOUND: f32 = 300.0;

fn scene(text: &str) -> LoadedScene {
    load_str(text, Path::new("scale.pbrt"), LoadOptions::default()).unwrap()
}

fn stats_scale(l: &LoadedScene, integrator: &str, set: &[(&str, &str)]) -> ScaleReport {
    let settings = RenderSettings {
        integrator: Some(integrator.into()),
        set: set.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
        threads: Some(2),
        ..Default::default()
    };
    let out = render(&l.scene, l.integrator.as_ref(), &settings, &mut Warnings::default()).unwrap();
    out.cache.expect("a cache-based render").stats.scale.expect("a cache-based render reports its scale")
}

fn derived(r: &ScaleReport, key: &str) -> Option<f64> {
    r.derived.get(key).and_then(|v| v.as_f64())
}

#[test]
fn an_open_scene_gets_a_scale_near_what_the_camera_sees() {
    let l = scene(OPEN);
    let d = l.scene.diagonal();
    assert!((d - 11313.7).abs() < 1.0, "{d}");
    let s = SceneScale::of(&l.scene);
    assert_eq!(s.source, ScaleSource::CameraView);
    assert!(s.length > 2.0 && s.length < OPEN_BOUND, "{s:?}");
    assert_eq!(s.length, VIEW_FACTOR * s.view_extent.unwrap());
    assert_eq!(s.scene_diagonal, d);
}

#[test]
fn a_closed_scene_keeps_its_diagonal() {
    let l = scene(CLOSED);
    let s = SceneScale::of(&l.scene);
    assert_eq!((s.length, s.source), (l.scene.diagonal(), ScaleSource::SceneDiagonal), "{s:?}");
    assert_eq!(s.seen, s.rays, "every ray sees a wall");
}

#[test]
fn the_shipped_scenes_keep_their_diagonal() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for name in ["room.pbrt", "spheres.pbrt"] {
        let l = load(&root.join(name), LoadOptions::default()).unwrap();
        let s = SceneScale::of(&l.scene);
        assert_eq!((s.length, s.source), (l.scene.diagonal(), ScaleSource::SceneDiagonal), "{name}: {s:?}");
    }
}

#[test]
fn the_scale_does_not_depend_on_threads() {
    let l = scene(OPEN);
    let one = with_threads(Some(1), || SceneScale::of(&l.scene)).unwrap();
    let three = with_threads(Some(3), || SceneScale::of(&l.scene)).unwrap();
    assert_eq!(one, three);
}

/// Before issue 41, cache AO's default ray length here was 0.1 · 11314 = 1131 and importance caching's
/// d_c was 0.025 · 11314 = 283.
#[test]
fn cache_ao_distance_and_importance_clamp_follow_the_view_on_an_open_scene() {
    let l = scene(OPEN);
    let ao = stats_scale(&l, "cacheao", &[("gather", "4"), ("caches", "40")]);
    assert_eq!(ao.scale.source, ScaleSource::CameraView);
    let length = ao.scale.length as f64;
    let max_distance = derived(&ao, "maxdistance").unwrap();
    assert!((max_distance - 0.1 * length).abs() < 1e-3 * length, "{ao:?}");
    assert!(max_distance < 0.1 * OPEN_BOUND as f64, "{ao:?}");
    assert!((derived(&ao, "lambda").unwrap() - 0.5 / length).abs() < 1e-6 / length, "{ao:?}");

    let ic = stats_scale(&l, "importancecache", &[("vpls", "16"), ("caches", "40")]);
    assert_eq!(ic.scale, ao.scale);
    let d_c = derived(&ic, "clamp_distance").unwrap();
    assert!((d_c - 0.025 * length).abs() < 1e-3 * length, "{ic:?}");
    assert!(d_c < 0.025 * OPEN_BOUND as f64, "{ic:?}");
}

/// A value the user sets is not derived from L, and an explicit λ leaves the report's λ out.
#[test]
fn set_values_are_not_reported_as_derived() {
    let l = scene(CLOSED);
    let r = stats_scale(&l, "cacheao", &[("gather", "4"), ("caches", "40"), ("maxdistance", "2"), ("lambda", "0.1")]);
    assert!(r.derived.is_empty(), "{r:?}");
    let r = stats_scale(&l, "cacheao", &[("gather", "4"), ("caches", "40")]);
    assert_eq!(derived(&r, "maxdistance"), json_f32(0.1 * l.scene.diagonal()).as_f64());
}
