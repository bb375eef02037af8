//! Every scene file under `../shared/scenes` and `scenes/` renders with the integrator its own file names
//! (issue 42), at 12×12 and one sample per pixel: what pbrt-v3 completes, cachert completes. The files that
//! are not pbrt-v3 scenes, or that pbrt-v3 cannot read either, are listed with the error they must give.

mod common;

use std::path::{Path, PathBuf};

use cachert::Warnings;
use cachert::integrator::{RenderSettings, render};
use cachert::scene::{LoadOptions, load};

/// Files that must fail (path relative to the shared scenes, or a prefix ending in `/`), the words their
/// error must contain, and why.
const EXPECTED_ERRORS: &[(&str, &str, &str)] = &[
    ("bitterli-bathroom/bathroom.pbrt", "unknown film \"rgb\"", "the pbrt-v4 form of scene-v3.pbrt"),
    ("bitterli-staircase2/staircase2.pbrt", "unknown film \"rgb\"", "the pbrt-v4 form of scene-v3.pbrt"),
    ("bitterli-cornell-box-v3/pbrt-v2/", "pbrt-v2 directive", "pbrt-v2 scenes, for pbrt-v2's irradiance cache"),
    ("hackmad-pbrt-v3-rs-tests/geometry/cube.pbrt", "WorldBegin", "a fragment that other files include"),
    ("pbrtv3scenes-buddha-fractal/geometry.pbrt", "WorldBegin", "a fragment that other files include"),
    ("hackmad-pbrt-v3-rs-tests/materials/fourier.pbrt", "cannot read", "reads pbrt-v3-scenes' dragon"),
    ("hackmad-pbrt-v3-rs-tests/materials/glass.pbrt", "cannot read", "reads pbrt-v3-scenes' dragon"),
    ("hackmad-pbrt-v3-rs-tests/materials/matte.pbrt", "cannot read", "reads pbrt-v3-scenes' dragon"),
    ("hackmad-pbrt-v3-rs-tests/materials/metal.pbrt", "cannot read", "reads pbrt-v3-scenes' dragon"),
    ("hackmad-pbrt-v3-rs-tests/materials/mirror.pbrt", "cannot read", "reads pbrt-v3-scenes' dragon"),
    ("hackmad-pbrt-v3-rs-tests/materials/mix.pbrt", "cannot read", "reads pbrt-v3-scenes' dragon"),
    ("hackmad-pbrt-v3-rs-tests/materials/plastic.pbrt", "cannot read", "reads pbrt-v3-scenes' dragon"),
    ("hackmad-pbrt-v3-rs-tests/materials/substrate.pbrt", "cannot read", "reads pbrt-v3-scenes' dragon"),
    ("hackmad-pbrt-v3-rs-tests/materials/translucent.pbrt", "cannot read", "reads pbrt-v3-scenes' dragon"),
    ("hackmad-pbrt-v3-rs-tests/materials/uber.pbrt", "cannot read", "reads pbrt-v3-scenes' dragon"),
    ("hackmad-pbrt-v3-rs-tests/shapes/loopsubdiv.pbrt", "cannot read", "includes pbrt-v3-scenes' killeroo"),
    ("hackmad-pbrt-v3-rs-tests/shapes/plymesh.pbrt", "cannot read", "reads pbrt-v3-scenes' ganesha"),
    ("hackmad-pbrt-v3-rs-tests/textures/3d-checkerboard.pbrt", "cannot read", "reads a dragon not shipped"),
    ("hackmad-pbrt-v3-rs-tests/cameras/realistic.pbrt", "realistic", "cachert has no lens-system camera"),
];

/// Every `.pbrt` file under `dir`, sorted.
fn scene_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            scene_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "pbrt") {
            out.push(p);
        }
    }
}

/// Renders `file` with its own integrator at 12×12, one sample per pixel: the error's text, if any.
fn render_file(file: &Path) -> Result<(), String> {
    let options = LoadOptions { resolution: Some([12, 12]), ..Default::default() };
    let loaded = load(file, options).map_err(|e| e.to_string())?;
    let settings = RenderSettings { spp: Some(1), quick: true, threads: Some(2), ..Default::default() };
    let out = render(&loaded.scene, loaded.integrator.as_ref(), &settings, &mut Warnings::default())
        .map_err(|e| e.to_string())?;
    match out.image.first_non_finite() {
        Some(p) => Err(format!("a non-finite pixel at {p:?}")),
        None => Ok(()),
    }
}

#[test]
fn every_scene_renders_with_its_own_integrator() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    scene_files(&repo.join("scenes"), &mut files);
    let shared = common::shared_scenes();
    if let Some(dir) = &shared {
        scene_files(dir, &mut files);
    }
    let mut failures = Vec::new();
    let (mut rendered, mut refused) = (0, 0);
    for file in &files {
        let rel = shared.as_ref().and_then(|d| file.strip_prefix(d).ok()).map(|r| r.to_string_lossy().into_owned());
        let expected = rel.as_deref().and_then(|r| {
            EXPECTED_ERRORS.iter().find(|(p, _, _)| if p.ends_with('/') { r.starts_with(p) } else { r == *p })
        });
        match (render_file(file), expected) {
            (Ok(()), None) => rendered += 1,
            (Err(e), Some((_, words, _))) if e.contains(words) => refused += 1,
            (Err(e), Some((_, words, why))) => {
                failures.push(format!("{}: expected an error with {words:?} ({why}), got: {e}", file.display()))
            }
            (Ok(()), Some((_, _, why))) => {
                failures.push(format!("{}: rendered, but listed as failing ({why})", file.display()))
            }
            (Err(e), None) => failures.push(format!("{}: {e}", file.display())),
        }
    }
    eprintln!("{rendered} scene files rendered, {refused} refused as expected, {} failures", failures.len());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
