//! `cachert info SCENE` lists every warning `cachert render SCENE` prints (issue 41): the scene's, and the
//! integrator's own — an unused `Integrator` parameter, a Sampler or a non-box PixelFilter that a
//! cache-based integrator does not use, what an application's preparation says — because both go through
//! `integrator::render`'s one code path (`integrator::dry_run` stops it before the first pixel).

mod common;

use std::collections::BTreeSet;
use std::process::{Command, Output};

use common::TempDir;

fn cachert(dir: &TempDir, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cachert")).args(args).current_dir(dir.path("")).output().unwrap()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A scene with `options` before WorldBegin and `world` after it: a lit wall and a sphere.
fn scene(options: &str, world: &str) -> String {
    format!(
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [40]\n\
         Film \"image\" \"integer xresolution\" [32] \"integer yresolution\" [32]\n{options}\n\
         WorldBegin\nLightSource \"point\" \"point from\" [1 1 3] \"rgb I\" [8 8 8]\n\
         Shape \"trianglemesh\" \"point P\" [-4 -4 0  4 -4 0  4 4 0  -4 4 0] \"integer indices\" [0 1 2 0 2 3]\n\
         Shape \"sphere\" \"float radius\" [0.5]\n{world}\nWorldEnd\n"
    )
}

/// Renders `text` with `render --quick --resolution 8x8` and runs `info` on it; checks that every warning
/// line render printed is a warning line of info, and that each of `expected` is among them. Returns
/// render's warning lines.
fn check(tag: &str, text: &str, expected: &[&str]) -> BTreeSet<String> {
    let dir = TempDir::new(tag);
    dir.write("s.pbrt", text);
    let args = ["render", "s.pbrt", "--quick", "--resolution", "8x8", "--quiet", "--outfile", "o.exr"];
    let render = cachert(&dir, &args);
    assert!(render.status.success(), "{tag}: render failed: {}", self::text(&render.stderr));
    let rendered: BTreeSet<String> = self::text(&render.stderr).lines().map(str::to_string).collect();
    for what in expected {
        assert!(rendered.iter().any(|w| w.contains(what)), "{tag}: render prints no warning on {what}: {rendered:#?}");
    }
    let info = cachert(&dir, &["info", "s.pbrt"]);
    assert!(info.status.success(), "{tag}: info failed: {}", self::text(&info.stderr));
    let out = self::text(&info.stdout);
    let listed: BTreeSet<String> = out
        .lines()
        .skip_while(|l| !l.starts_with("warnings "))
        .skip(1)
        .map(|l| l.strip_prefix("  ").unwrap_or(l).to_string())
        .collect();
    let missing: Vec<&String> = rendered.difference(&listed).collect();
    assert!(missing.is_empty(), "{tag}: info leaves out what render prints: {missing:#?}\ninfo:\n{out}");
    rendered
}

#[test]
fn an_unused_integrator_parameter_and_an_unused_shape_parameter() {
    let text = scene(
        "Integrator \"path\" \"integer maxdepth\" [2] \"integer bogus\" [3]",
        "Shape \"sphere\" \"float radius\" [0.2] \"float bogosity\" [1]",
    );
    check("unused", &text, &["unused parameter \"integer bogus\"", "bogosity"]);
}

#[test]
fn a_sampler_with_a_cache_integrator() {
    let text = scene(
        "Sampler \"halton\" \"integer pixelsamples\" [4]\n\
         Integrator \"cacheao\" \"integer caches\" [8] \"integer gather\" [4] \"float typo\" [1]",
        "",
    );
    check("sampler", &text, &["Sampler \"halton\" is not used by cache-based integrators", "\"float typo\""]);
}

#[test]
fn a_gaussian_filter_with_a_cache_integrator_and_its_preparation() {
    let text = scene(
        "PixelFilter \"gaussian\"\n\
         Integrator \"irradiancecache\" \"integer caches\" [8] \"integer gather\" [4] \"integer maxdepth\" [0]",
        "",
    );
    check("filter", &text, &["PixelFilter is not used by the cached part of the image", "\"maxdepth\" 0"]);
}

#[test]
fn an_ignored_directive_and_a_scene_without_lights() {
    let text = scene("MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\nIntegrator \"directlighting\"", "")
        .replace("LightSource \"point\" \"point from\" [1 1 3] \"rgb I\" [8 8 8]\n", "");
    check("medium", &text, &["MakeNamedMedium is accepted and ignored", "no light sources"]);
}
