//! The registry of cache applications and the generic cache driver (issue 15): an application defined here,
//! in the test, renders through the same driver with every placement and no edit of `src/`; every
//! registered application has its parameter table in the README and in `render --help`; no file of `src/`
//! outside `src/application/` names an application; typed placement and budget from the command line, and
//! the resolved settings in the `--stats` report.

mod common;

use std::path::Path;

use cachert::Warnings;
use cachert::application::registry::APPLICATIONS;
use cachert::application::{Application, Neighbour};
use cachert::gbuffer::ShadingPoint;
use cachert::gbuffer::scale::SceneScale;
use cachert::integrator::cache::{self, CacheOverrides, Placement, render_with};
use cachert::integrator::{RenderOutput, RenderSettings};
use cachert::parse::integrator::{IntegratorParams, ParamDef, Parameter, markdown_table};
use cachert::placement::registry::NAMES;
use cachert::render::RayCounters;
use cachert::sampling::{Rng, Stratum};
use cachert::scene::{LoadOptions, Scene, load_str};

/// A toy application: caches the shading normal's z (times `scale`) and remembers where it was computed,
/// so shading can check the position and normal the driver hands it for each neighbour.
struct NormalZ {
    scale: f32,
}

struct ZRecord {
    z: f32,
    p: glam::Vec3A,
    n: glam::Vec3A,
}

/// The toy's one parameter, declared once: its default and meaning are the table's and the reader's.
const SCALE: ParamDef<f64> = ParamDef::float("scale", 1.0, "multiplies z");

impl Application for NormalZ {
    const NAME: &'static str = "cachenz";
    const ABOUT: &'static str = "the shading normal's z, interpolated (a test)";
    const PARAMETERS: &'static [Parameter] = &[SCALE.row];
    type Record = ZRecord;
    type Prepared<'s> = ();

    fn from_params(p: &IntegratorParams<'_>, _: &SceneScale) -> cachert::Result<Self> {
        Ok(NormalZ { scale: p.get(&SCALE)? as f32 })
    }

    fn prepare(&self, _: &Scene, _: &mut Warnings) -> cachert::Result<()> {
        Ok(())
    }

    fn settings(&self) -> Vec<(&'static str, serde_json::Value)> {
        vec![("scale", self.scale.into())]
    }

    fn compute_record(&self, _: &(), at: &ShadingPoint, _: &mut Rng, _: &mut RayCounters) -> ZRecord {
        ZRecord { z: self.scale * at.n.z, p: at.p, n: at.n }
    }

    fn diff(&self, a: &ZRecord, b: &ZRecord) -> f32 {
        (a.z - b.z).abs()
    }

    /// Channel 0: the blend of z; channel 1: 1 when every neighbour's position and normal are its record's
    /// and its weight is positive, else 0; channel 2: 1 where an emitter is seen directly.
    fn shade(
        &self,
        _: &(),
        s: &ShadingPoint,
        near: &[Neighbour<'_, ZRecord>],
        _: &mut Rng,
        _: Stratum,
        _: &mut RayCounters,
    ) -> [f32; 3] {
        let (mut sum, mut wsum) = (0.0f32, 0.0f32);
        let mut consistent = !near.is_empty();
        for c in near {
            sum += c.weight * c.record.z;
            wsum += c.weight;
            consistent &= c.p == c.record.p && c.n == c.record.n && c.weight > 0.0;
        }
        [sum / wsum, consistent as u8 as f32, s.area_light.is_some() as u8 as f32]
    }

    /// Channel 0: z; channel 1: |∂p/∂u · n| / |∂p/∂u| (0 for a tangent); channel 2: the emitter flag.
    fn reference(&self, _: &(), s: &ShadingPoint, _: &mut Rng, _: Stratum, _: &mut RayCounters) -> [f32; 3] {
        let along = s.dpdu.normalize_or_zero().dot(s.n).abs();
        [self.scale * s.n.z, along, s.area_light.is_some() as u8 as f32]
    }

    fn record_bytes(&self, _: &ZRecord) -> usize {
        std::mem::size_of::<ZRecord>()
    }

    fn record_bytes_bound(&self) -> usize {
        std::mem::size_of::<ZRecord>()
    }
}

/// A plane (z up) under an emitting sphere, seen from above at 32×32 pixels.
const SCENE: &str = "LookAt 0 0 10  0 0 0  0 1 0\nCamera \"orthographic\" \"float screenwindow\" [-4 4 -4 4]\n\
     Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 32\nWorldBegin\n\
     Shape \"trianglemesh\" \"point P\" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] \"integer indices\" [0 1 2 0 2 3]\n\
     AttributeBegin\nAreaLightSource \"diffuse\"\nTranslate 0.5 -0.3 1.5\nShape \"sphere\" \"float radius\" 1.5\n\
     AttributeEnd\nWorldEnd\n";

fn toy(placement: Placement, caches: usize, set: &[(&str, &str)]) -> RenderOutput {
    let loaded = load_str(SCENE, Path::new("toy.pbrt"), LoadOptions::default()).unwrap();
    let settings = RenderSettings {
        seed: 5,
        set: set.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
        cache: CacheOverrides { placement: Some(placement), caches: Some(caches), subpixels: None, target_error: None },
        ..Default::default()
    };
    render_with::<NormalZ>(&loaded.scene, loaded.integrator.as_ref(), &settings, &mut Warnings::default()).unwrap()
}

/// Closed form of the reference's channel 0 over pixel (x, y): the range of the normal's z over the pixel's
/// footprint (1 on the plane, √(1 − r²/R²) on the sphere); `None` for a pixel the silhouette crosses.
fn normal_z(x: usize, y: usize) -> Option<(f32, f32)> {
    let (mut lo, mut hi, mut inside) = (f32::INFINITY, f32::NEG_INFINITY, 0);
    for k in 0..81 {
        let (fx, fy) = ((k % 9) as f32 / 8.0, (k / 9) as f32 / 8.0);
        // pbrt's camera is left-handed: raster x runs along world −x looking down −z with +y up.
        let px = -(-4.0 + (x as f32 + fx) / 32.0 * 8.0);
        let py = 4.0 - (y as f32 + fy) / 32.0 * 8.0;
        let r2 = (px - 0.5).powi(2) + (py + 0.3).powi(2);
        let z = if r2 < 2.25 { (1.0 - r2 / 2.25).sqrt() } else { 1.0 };
        inside += (r2 < 2.25) as usize;
        (lo, hi) = (lo.min(z), hi.max(z));
    }
    (inside == 0 || inside == 81).then_some((lo, hi))
}

#[test]
fn an_application_defined_in_a_test_renders_with_every_placement() {
    let reference = toy(Placement::Reference, 1, &[]).image;
    let (mut checked, mut emitters) = (0, 0);
    for y in 0..32 {
        for x in 0..32 {
            let [z, along, emits] = reference.get(x, y);
            assert!(along < 1e-4, "({x}, {y}): ∂p/∂u is not tangent: {along}");
            if let Some((lo, hi)) = normal_z(x, y) {
                assert!(z >= lo - 1e-4 && z <= hi + 1e-4, "({x}, {y}): {z} outside [{lo}, {hi}]");
                assert_eq!(emits, if lo < 1.0 { 1.0 } else { 0.0 }, "({x}, {y})");
                emitters += (emits == 1.0) as usize;
                checked += 1;
            }
        }
    }
    assert!(checked > 800 && emitters > 60, "{checked} {emitters}");
    for name in NAMES {
        let p = Placement::parse(name).unwrap();
        let out = toy(p, 150, &[]);
        let c = out.cache.as_ref().unwrap();
        assert_eq!(c.stats.total_caches, 150, "{name}");
        assert_eq!(out.integrator, format!("cachenz, placement {name}"));
        let mut sq = 0.0f64;
        for (a, b) in out.image.pixels.iter().zip(&reference.pixels) {
            assert_eq!(a[1], 1.0, "{name}: a neighbour's position or normal is not its cache's");
            sq += ((a[0] - b[0]) as f64).powi(2);
        }
        let rmse = (sq / out.image.pixels.len() as f64).sqrt();
        assert!(rmse < 0.1, "{name}: rmse {rmse}");
    }
    // The toy's own parameter goes through --set like any other, and is reported.
    let out = toy(Placement::parse("im").unwrap(), 100, &[("scale", "2")]);
    let c = out.cache.unwrap();
    assert_eq!(c.settings["scale"], serde_json::json!(2.0));
    assert!(out.image.pixels.iter().all(|p| (p[0] - 2.0).abs() < 1e-6 || p[2] == 1.0 || p[0] < 2.0));
    assert!(out.image.pixels.iter().any(|p| p[0] == 2.0));
}

#[test]
fn every_registered_application_has_its_tables_in_its_page_and_the_help() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let placements = std::fs::read_to_string(dir.join("docs/placements.md")).unwrap();
    assert!(placements.contains(&markdown_table(cache::PARAMETERS)), "the generic table is not in docs/placements.md");
    let help = cache::help();
    for e in APPLICATIONS {
        let rel = format!("docs/integrators/{}.md", e.name);
        let page = std::fs::read_to_string(dir.join(&rel)).unwrap_or_else(|err| panic!("{rel}: {err}"));
        let table = markdown_table(e.parameters);
        assert!(page.contains(&table), "{rel} lacks the table:\n{table}");
        assert!(help.contains(e.name) && e.parameters.iter().all(|p| help.contains(p.name)), "{help}");
    }
}

#[test]
fn no_file_of_src_outside_application_names_an_application() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    // The modules of the applications themselves (everything in application/ but the trait and the registry).
    let modules: Vec<String> = std::fs::read_dir(src.join("application"))
        .unwrap()
        .map(|e| e.unwrap().path().file_stem().unwrap().to_string_lossy().into_owned())
        .filter(|m| m != "mod" && m != "registry")
        .collect();
    assert!(modules.len() >= 3, "{modules:?}");
    let mut stack = vec![src.clone()];
    let mut files = 0;
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            // The benchmark against pbrt-v2's irradiance cache compares one application with an outside
            // peer by design; nothing else outside `application/` may name one, by its name or its module.
            let peer_bench = ["experiment/bench/irc_peer.rs", "experiment/bench/peer_chart.rs"].map(|f| src.join(f));
            if path == src.join("application") || peer_bench.contains(&path) {
                continue;
            }
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let text = std::fs::read_to_string(&path).unwrap();
                for e in APPLICATIONS {
                    assert!(!text.contains(e.name), "{} names \"{}\"", path.display(), e.name);
                }
                for m in &modules {
                    let import = format!("application::{m}");
                    assert!(!text.contains(&import), "{} imports {import}", path.display());
                }
                files += 1;
            }
        }
    }
    assert!(files > 20, "{files}");
}

#[test]
fn unknown_integrators_and_misplaced_cache_flags_list_the_registry() {
    let loaded = load_str(SCENE, Path::new("toy.pbrt"), LoadOptions::default()).unwrap();
    let go = |s: RenderSettings| {
        cachert::integrator::render(&loaded.scene, None, &s, &mut Warnings::default()).unwrap_err().to_string()
    };
    let e = go(RenderSettings { integrator: Some("nope".into()), ..Default::default() });
    assert!(APPLICATIONS.iter().all(|a| e.contains(a.name)) && e.contains("ambientocclusion"), "{e}");
    let cache = CacheOverrides { caches: Some(10), ..Default::default() };
    let e = go(RenderSettings { integrator: Some("ambientocclusion".into()), cache, ..Default::default() });
    assert!(e.contains("--caches") && APPLICATIONS.iter().all(|a| e.contains(a.name)), "{e}");
    let e = Placement::parse("vgc+foo").unwrap_err().to_string();
    assert!(e.contains("none") && NAMES.iter().all(|n| e.contains(n)), "{e}");
}

#[test]
fn the_command_line_placement_and_budget_win_and_the_stats_report_the_resolved_settings() {
    use clap::Parser;
    let dir = common::TempDir::new("registry-cli");
    let name = APPLICATIONS[0].name;
    let scene = dir.write(
        "s.pbrt",
        SCENE.replace(
            "WorldBegin",
            &format!("Integrator \"{name}\" \"string placement\" \"vgc\" \"integer caches\" 7\nWorldBegin"),
        ),
    );
    let (out, stats) = (dir.path("o.pfm"), dir.path("stats.json"));
    let args = ["cachert", "render", "--quiet", "--placement", "sd+as", "--caches", "90"];
    let files = [scene.to_str().unwrap(), "--outfile", out.to_str().unwrap(), "--stats", stats.to_str().unwrap()];
    let cli = cachert::cli::Cli::try_parse_from(args.iter().chain(&files)).unwrap();
    cachert::cli::run(&cli).unwrap();
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let p = &json["settings"]["parameters"];
    assert_eq!((p["placement"].as_str(), p["caches"].as_u64()), (Some("sd+as"), Some(90)), "{json:#}");
    assert_eq!(p["subpixels"].as_u64(), Some(4), "{json:#}");
    for e in APPLICATIONS.iter().filter(|e| e.name == name) {
        assert!(e.parameters.iter().all(|q| p.get(q.name).is_some()), "{json:#}");
    }
    assert!(cache::PARAMETERS.iter().all(|q| p.get(q.name).is_some()), "{json:#}");
    // A bad placement is refused while the flags are read, before anything renders.
    let e = cachert::cli::Cli::try_parse_from(["cachert", "render", "--placement", "vgc+foo", "x.pbrt"]).unwrap_err();
    assert!(e.to_string().contains("vgc+dgs:geom"), "{e}");
}

/// `--stats -` writes the statistics to standard output, as `-` means for every pbrt-style tool, and makes
/// no file named `-`.
#[test]
fn stats_to_a_dash_go_to_standard_output() {
    let dir = common::TempDir::new("registry-stats-dash");
    let scene = dir.write("s.pbrt", SCENE);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_cachert"))
        .args(["render", "--quick", "--quiet", "--integrator", APPLICATIONS[0].name, "--stats", "-"])
        .args(["--outfile", "o.pfm", scene.to_str().unwrap()])
        .current_dir(&dir.0)
        .output()
        .expect("the binary runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let json = &stdout[stdout.find('{').expect("JSON on standard output")..];
    let v: serde_json::Value = serde_json::from_str(json.trim()).expect("one JSON object");
    assert!(v["stats"]["times"]["total"].is_number(), "{v:#}");
    assert!(!dir.path("-").exists(), "a file named - was written");
}
