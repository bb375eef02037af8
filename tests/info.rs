//! `cachert info` prints every warning rendering the scene prints before its first pixel (issue 39: it said
//! "warnings 0" on a scene where `render` printed two, an unsupported material and an unreadable
//! environment map), and refuses what render refuses.

mod common;

use std::process::{Command, Output};

use common::TempDir;

const SCENE: &str = r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" [40]
Film "image" "integer xresolution" [8] "integer yresolution" [8]
Sampler "random" "integer pixelsamples" [1]
Integrator "path"
WorldBegin
LightSource "infinite" "string mapname" "missing.exr"
Material "fourier" "string bsdffile" "missing.bsdf"
Shape "sphere" "float radius" [1]
Texture "t" "spectrum" "imagemap" "string filename" "missing.png"
Material "matte" "texture Kd" "t"
Shape "sphere" "float radius" [0.5]
WorldEnd
"#;

fn cachert(dir: &TempDir, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cachert")).args(args).current_dir(dir.path("")).output().unwrap()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[test]
fn info_prints_every_warning_that_render_prints() {
    let dir = TempDir::new("info-warnings");
    dir.write("s.pbrt", SCENE);
    let render = cachert(&dir, &["render", "s.pbrt", "--quiet", "--outfile", "o.exr"]);
    assert!(render.status.success(), "{}", text(&render.stderr));
    let rendered: Vec<String> = text(&render.stderr).lines().map(str::to_string).collect();
    assert!(rendered.len() >= 3, "{rendered:?}");
    for what in ["\"fourier\" is not supported", "environment map unusable", "missing.png"] {
        assert!(rendered.iter().any(|w| w.contains(what)), "render: no warning on {what}: {rendered:?}");
    }
    let info = cachert(&dir, &["info", "s.pbrt"]);
    assert!(info.status.success(), "{}", text(&info.stderr));
    let out = text(&info.stdout);
    assert!(out.contains(&format!("warnings    {}\n", rendered.len())), "{out}");
    for w in &rendered {
        assert!(out.contains(&format!("  {w}\n")), "info leaves out {w}:\n{out}");
    }
}

#[test]
fn info_refuses_a_light_that_render_refuses() {
    let dir = TempDir::new("info-errors");
    let scene = SCENE.replace(
        "LightSource \"infinite\" \"string mapname\" \"missing.exr\"",
        "LightSource \"spot\" \"point from\" [0 0 1] \"point to\" [0 0 1]",
    );
    dir.write("s.pbrt", &scene);
    let render = cachert(&dir, &["render", "s.pbrt", "--quiet", "--outfile", "o.exr"]);
    let info = cachert(&dir, &["info", "s.pbrt"]);
    let what = "error: s.pbrt:7:1: LightSource \"spot\": \"from\" and \"to\" are the same point";
    for (cmd, o) in [("render", &render), ("info", &info)] {
        assert_eq!(o.status.code(), Some(2), "{cmd}");
        assert!(text(&o.stderr).contains(what), "{cmd}: {}", text(&o.stderr));
    }
    assert!(!dir.path("o.exr").exists());
}
