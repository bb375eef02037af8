//! The golden matrix (issue 13): every registered (placement, application) pair and every per-pixel
//! integrator has a golden in `golden/`, every golden reproduces, and no golden is trusted on its own word:
//! the per-pixel ones are compared with pbrt-v3's images of the same scenes, and each cache-based one with
//! its own `none` golden (the per-sample reference), within a bound stated per application below; the
//! `none` goldens of irradiance and importance caching are compared with pbrt-v3 too. Also the command:
//! `check` fails with the list, `update` says what moved and refuses under CI, `add` serves a user's folder.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use cachert::application::registry::APPLICATIONS;
use cachert::golden::{self, Manifest, Rule, Verdict, matrix};
use cachert::image::{self, Image};
use cachert::metrics::{Metric, compare};
use cachert::placement::registry::NAMES;
use cachert::render::INTEGRATORS;
use common::{TempDir, assert_matches_pbrt_single, mean};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn golden_dir() -> PathBuf {
    root().join("golden")
}

fn manifest() -> Manifest {
    Manifest::read(&golden_dir(), false).expect("golden/MANIFEST.json reads")
}

fn golden_image(m: &Manifest, name: &str) -> Image {
    let e = m.get(name).unwrap_or_else(|| panic!("no golden named {name}"));
    image::read(&golden_dir().join(&e.file)).unwrap_or_else(|err| panic!("{name}: {err}"))
}

#[test]
fn every_registered_placement_and_application_has_a_golden_with_the_matrix_settings() {
    let m = manifest();
    let mut missing = Vec::new();
    // Enumerated here from the registries themselves, not from golden::matrix.
    for scene in matrix::SCENES {
        for app in APPLICATIONS {
            for p in std::iter::once("none").chain(NAMES) {
                let name = format!("{scene}.{}.{p}", app.name);
                match m.get(&name) {
                    Some(e) => {
                        assert_eq!(e.spec.integrator, app.name, "{name}");
                        assert_eq!(e.spec.placement.as_deref(), Some(p), "{name}");
                    }
                    None => missing.push(name),
                }
            }
        }
    }
    for integrator in INTEGRATORS {
        if !m.entries.iter().any(|e| e.spec.integrator == *integrator && e.spec.placement.is_none()) {
            missing.push(format!("{integrator} (per-pixel)"));
        }
    }
    assert!(missing.is_empty(), "no golden for: {missing:?}\nmake them with: cachert golden update --matrix");
    // Every matrix entry is in the manifest with exactly the matrix's settings, its file exists and its
    // recorded mean is the file's.
    for (name, spec) in matrix::entries() {
        let e = m.get(&name).unwrap_or_else(|| panic!("{name} missing"));
        assert_eq!(e.spec, spec, "{name}: the manifest's settings are not the matrix's (run golden update)");
        let im = golden_image(&m, &name);
        let (a, b) = (im.mean(), e.recorded.mean);
        assert!((0..3).all(|c| (a[c] - b[c]).abs() <= 1e-12 * a[c].abs()), "{name}: mean {a:?}, recorded {b:?}");
        assert!(!e.recorded.commit.is_empty() && !e.recorded.settings.is_empty(), "{name}");
    }
}

#[test]
fn every_golden_reproduces() {
    let outcomes = golden::check(&golden_dir(), None, None, false, &mut |o| eprintln!("{}", o.line())).unwrap();
    let failed: Vec<String> = outcomes.iter().filter(|o| !o.verdict.passed()).map(|o| o.line()).collect();
    let secs: f64 = outcomes.iter().map(|o| o.secs).sum();
    eprintln!("{} goldens in {secs:.1} s", outcomes.len());
    assert!(failed.is_empty(), "golden failures:\n{}", failed.join("\n"));
    assert_eq!(outcomes.len(), manifest().entries.len());
    // On the goldens' own platform nothing passes by the tolerance.
    let here = golden::platform();
    for (o, e) in outcomes.iter().zip(&manifest().entries) {
        if e.recorded.platform == here {
            assert_eq!((&o.rule, &o.verdict), (&Rule::Bits, &Verdict::Identical), "{}", o.line());
        }
    }
}

/// The architecture part of a platform string (`x86_64` of `x86_64-linux`).
fn arch(platform: &str) -> &str {
    platform.split('-').next().unwrap_or_default()
}

#[test]
fn an_x86_64_golden_on_an_x86_64_machine_is_judged_by_its_bits() {
    // Issue 39: goldens made on Intel reproduce bit for bit on AMD and back, and a rule that judged them by
    // the tolerance across CPU models hid a change of every irradiance-caching image. The project's goldens
    // name their platform, and on the same architecture (and system) the rule is bits, whatever CPU model
    // made them or checks them.
    let m = manifest();
    let here = golden::platform();
    for e in &m.entries {
        assert_eq!(arch(&e.recorded.platform), "x86_64", "{}: made on {}", e.name, e.recorded.platform);
        assert!(!e.recorded.commit.ends_with("-dirty"), "{}: recorded from uncommitted code", e.name);
        if arch(&here) == "x86_64" {
            assert_eq!(golden::rule(&e.recorded.platform, &here, false), Rule::Bits, "{} on {here}", e.name);
        }
    }
    for (made, cpu) in [("x86_64-linux", "Intel(R) Xeon(R) Platinum 8488C"), ("x86_64-linux", "AMD EPYC 9R14")] {
        assert_eq!(golden::rule(made, "x86_64-linux", false), Rule::Bits, "{cpu}");
    }
}

/// pbrt-v3's image of a per-pixel golden, from tests/data/pbrt-v3/golden (made by its make.sh), and the
/// ratio of its pixel samples to the golden's.
fn pbrt_reference(name: &str) -> (Image, f64) {
    let spp = |n: &str| if n.starts_with("path") { 4096.0 } else { 1024.0 };
    let path = root().join(format!("tests/data/pbrt-v3/golden/{name}.pfm"));
    let im = image::read(&path).unwrap_or_else(|e| panic!("{name}: no pbrt-v3 reference ({e}): run its make.sh"));
    (im, spp(name) / matrix::PER_PIXEL_SPP as f64)
}

#[test]
fn per_pixel_goldens_match_pbrt_v3() {
    // The statistics of the foundation: RMSE within 1.3 × the noise floor (from a second seed of ours, scaled
    // to the reference's sample count) and the mean within 1 %.
    let m = manifest();
    for e in m.entries.iter().filter(|e| e.spec.placement.is_none()) {
        let scene = Path::new(&e.spec.scene).file_stem().unwrap().to_string_lossy().to_string();
        let (reference, ratio) = pbrt_reference(&format!("{}-{scene}", e.spec.integrator));
        let golden = golden_image(&m, &e.name);
        let mut other = e.spec.clone();
        other.seed += 1;
        let second = golden::render_spec(&golden_dir(), &other, None).unwrap().image;
        assert_matches_pbrt_single(&e.name, &golden, &second, &reference, ratio, 0.01);
    }
}

/// The largest error of a cache-based golden against its own `none` golden, per application and scene:
/// RMSE relative to the mean of `none`, mean HDR-FLIP, and the relative difference of the means. Each bound
/// is about 1.5× the largest measured over the eight placements when the goldens were re-recorded at the
/// code of issue 39 (64×48, 500 caches, the applications' quick settings; VGC's σ_a from the cache
/// density); the measured figures are in the comments, placement in brackets. A golden that is silently
/// wrong by a visible amount exceeds them. The spheres' indirect light is dim and varies fast, so their
/// irradiance-caching bound stays near the old 0.55.
fn bound(application: &str, scene: &str) -> Option<(f64, f64, f64)> {
    match (application, scene) {
        // 0.0679 (vgc+dgs:geom), 0.0365 (im), 2.44 % (vgc+dgs:geom)
        ("cacheao", "spheres") => Some((0.10, 0.055, 0.037)),
        // 0.0777 (im), 0.0505 (vgc+dgs:diff), 1.38 % (vgc+dgs:diff)
        ("cacheao", "room") => Some((0.12, 0.076, 0.021)),
        // 0.3707 (im), 0.1763 (vgc+dgs:geom), 3.23 % (vgc+dgs:geom)
        ("irradiancecache", "spheres") => Some((0.56, 0.27, 0.049)),
        // 0.0705 (im), 0.0572 (im), 0.67 % (vgc+dgs:geom)
        ("irradiancecache", "room") => Some((0.106, 0.086, 0.010)),
        // 0.0165 (vgc+dgs:geom), 0.0078 (sd), 0.02 % (im): the means agree to the noise of a 64×48
        // image's mean, so their bound is a floor of 0.25 %, not 1.5× that.
        ("importancecache", "spheres") => Some((0.025, 0.012, 0.0025)),
        // 0.0513 (im), 0.0320 (sd), 0.14 % (sd+as); the same floor for the mean
        ("importancecache", "room") => Some((0.077, 0.048, 0.0025)),
        _ => None,
    }
}

/// Relative RMSE, HDR-FLIP and relative difference of the means of `test` against `reference`.
fn errors(test: &Image, reference: &Image) -> (f64, f64, f64) {
    let v = compare(test, reference, &[Metric::Rmse, Metric::Flip]).unwrap();
    let (mt, mr) = (mean(test), mean(reference));
    (v[0].1 / mr, v[1].1, (mt - mr).abs() / mr)
}

#[test]
fn cache_goldens_are_near_their_own_per_sample_reference() {
    let m = manifest();
    let mut report = Vec::new();
    for app in APPLICATIONS {
        for scene in matrix::SCENES {
            let (max_rel, max_flip, max_dmean) =
                bound(app.name, scene).unwrap_or_else(|| panic!("state a golden bound for {} on {scene}", app.name));
            let none = golden_image(&m, &matrix::name(scene, app.name, Some("none")));
            for p in NAMES {
                let name = matrix::name(scene, app.name, Some(p));
                let (rel, flip, dmean) = errors(&golden_image(&m, &name), &none);
                report.push(format!("{name}: rel. RMSE {rel:.4}, FLIP {flip:.4}, mean {:+.2} %", 100.0 * dmean));
                assert!(rel <= max_rel && flip <= max_flip, "{name}: rel. RMSE {rel} FLIP {flip} vs none");
                // The caches interpolate the same estimator: the mean moves by less than the error spreads.
                assert!(dmean <= max_dmean, "{name}: mean {:.2} % off none", 100.0 * dmean);
            }
        }
    }
    eprintln!("{}", report.join("\n"));
}

#[test]
fn the_per_sample_references_of_irradiance_caching_agree_with_pbrt_v3() {
    // Irradiance caching's default image is the indirect light; with maxdepth 3 its light paths are those
    // of pbrt-v3's `path` with maxdepth 4 minus the emission and direct light of `directlighting`. The cache
    // integrators average sub-pixel samples (a box filter) where pbrt-v3 uses the scene's Gaussian filter,
    // so the images are compared by their means.
    let m = manifest();
    let path = image::read(&root().join("tests/data/pbrt-v3/golden/path-maxdepth4-room.pfm")).unwrap();
    let direct = image::read(&root().join("tests/data/pbrt-v3/golden/directlighting-room.pfm")).unwrap();
    let indirect = mean(&path) - mean(&direct);
    let ours = mean(&golden_image(&m, "room.irradiancecache.none"));
    let dev = (ours - indirect) / indirect;
    eprintln!(
        "room indirect: irradiancecache none {ours:.5}, pbrt-v3 path − directlighting {indirect:.5} ({:+.2} %)",
        100.0 * dev
    );
    // Measured at the goldens of issue 39: −0.21 %; the bound is about twice that, the pbrt-v3 references'
    // own noise in the mean being of that order.
    assert!(dev.abs() <= 0.005, "{dev}");
}

#[test]
fn the_per_sample_reference_of_importance_caching_agrees_with_pbrt_v3_in_the_mean() {
    // Importance caching's reference sums all VPLs of one set of light paths, each clamped at d_c, plus the
    // clamp's loss put back (`compensate`): with `vpldepth` 4 it estimates pbrt-v3's `path` (maxdepth 5) up
    // to that one set's error. The golden's 1024 VPLs of vplseed 0 are one heavy-tailed draw (−3.8 %; seeds
    // 1 and 2: −0.6 %, −1.0 %), so the golden's settings are rendered here with 8192 VPLs. Measured: −0.52 %
    // (−1.47 % with compensate 0; before issue 41, vpldepth 5 and no compensation gave the golden −2.08 %).
    let loaded = cachert::scene::load(
        &root().join("scenes/room.pbrt"),
        cachert::scene::LoadOptions { resolution: Some([64, 48]), ..Default::default() },
    )
    .unwrap();
    let settings = cachert::integrator::RenderSettings {
        integrator: Some("importancecache".into()),
        set: [("placement", "none"), ("vpls", "8192")].map(|(k, v)| (k.to_string(), v.to_string())).to_vec(),
        ..Default::default()
    };
    let ours = cachert::integrator::render(&loaded.scene, None, &settings, &mut cachert::Warnings::default()).unwrap();
    let ours = mean(&ours.image);
    let path = mean(&image::read(&root().join("tests/data/pbrt-v3/golden/path-room.pfm")).unwrap());
    let dev = (ours - path) / path;
    eprintln!("room: importancecache none (8192 VPLs) {ours:.5}, pbrt-v3 path {path:.5} ({:+.2} %)", 100.0 * dev);
    assert!(dev.abs() <= 0.015, "{dev}");
}

/// Runs the `cachert` binary with `args`, the environment variable CI set or not.
fn cachert(args: &[&str], ci: bool) -> (i32, String, String) {
    let mut c = Command::new(env!("CARGO_BIN_EXE_cachert"));
    c.args(args);
    if ci {
        c.env("CI", "true");
    } else {
        c.env_remove("CI");
    }
    let out = c.output().unwrap();
    let s = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (out.status.code().unwrap_or(-1), s(&out.stdout), s(&out.stderr))
}

#[test]
fn a_user_folder_is_made_checked_broken_and_updated_through_the_command() {
    let dir = TempDir::new("golden-user");
    let scene = root().join("scenes/spheres.pbrt");
    let (d, s) = (dir.path("g"), scene.to_str().unwrap().to_string());
    let d = d.to_str().unwrap();
    // `--allow-dirty`: this test runs on developers' trees with uncommitted changes too; the refusal itself is
    // src/golden/provenance.rs's test.
    let add = |name: &str, extra: &[&str], ci: bool| {
        let mut a = vec!["golden", "add", "--allow-dirty", "--dir", d, "--name", name, &s, "--resolution", "16x12"];
        a.extend_from_slice(extra);
        cachert(&a, ci)
    };
    // Adding is refused under CI, and leaves nothing.
    let (code, _, err) = add("ao", &["--integrator", "cacheao", "--placement", "vgc"], true);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("CI") && !dir.path("g").exists(), "{err}");
    let (code, out, err) = add("ao", &["--integrator", "cacheao", "--placement", "vgc", "--caches", "30"], false);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("added golden \"ao\""), "{out}");
    let (code, _, err) = add("direct", &["--integrator", "directlighting", "--spp", "2", "--seed", "3"], false);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = add("ao", &["--integrator", "cacheao"], false);
    assert!(code == 2 && err.contains("already"), "{err}");
    let m = Manifest::read(Path::new(d), false).unwrap();
    assert_eq!(m.entries.len(), 2);
    assert_eq!(m.get("direct").unwrap().spec.seed, 3);
    assert_eq!(m.get("ao").unwrap().recorded.settings["caches"], serde_json::json!(30));

    let (code, out, err) = cachert(&["golden", "check", "--dir", d], true);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("2 goldens: 2 passed (2 identical), 0 failed"), "{out}");
    assert!(out.contains("2 judged bit for bit on") && out.contains("0 within the tolerance"), "{out}");
    assert!(err.contains("PASS identical bits") && err.contains(" ao") && err.contains(" direct"), "{err}");

    // A golden moved by a fraction of a per cent fails on this machine kind, and the list names it.
    let file = dir.path("g").join(&m.get("ao").unwrap().file);
    let mut im = image::read(&file).unwrap();
    let lit = im.pixels.iter().position(|p| p[0] > 0.1).expect("a lit pixel");
    im.pixels[lit][0] *= 1.001;
    image::write(&im, &file).unwrap();
    let (code, out, _) = cachert(&["golden", "check", "--dir", d], true);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("1 failed") && out.contains("failed:\n  FAIL") && out.contains(" ao: not bit-identical"),
        "{out}"
    );
    // The filter selects; one that matches nothing is an error.
    let (code, out, _) = cachert(&["golden", "check", "--dir", d, "--filter", "dir*"], true);
    assert!(code == 0 && out.contains("1 goldens: 1 passed"), "{out}");
    let (code, _, err) = cachert(&["golden", "check", "--dir", d, "--filter", "nope"], true);
    assert!(code == 2 && err.contains("no golden"), "{err}");

    // Update refuses under CI; otherwise it says what moved and by how much, and check passes again.
    let (code, _, err) = cachert(&["golden", "update", "--allow-dirty", "--dir", d], true);
    assert!(code == 2 && err.contains("CI"), "{err}");
    let (code, out, err) = cachert(&["golden", "update", "--allow-dirty", "--dir", d], false);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("ao: moved: RMSE") && err.contains("direct: unchanged (identical)"), "{err}");
    assert!(out.contains("updated 2 goldens"), "{out}");
    assert_eq!(cachert(&["golden", "check", "--dir", d], true).0, 0);

    // A golden one unit in the last place off fails by its bits; `--tolerance` asks for the tolerance on
    // purpose, and each line says which rule judged it.
    let mut im = image::read(&file).unwrap();
    im.pixels[lit][0] = f32::from_bits(im.pixels[lit][0].to_bits() + 1);
    image::write(&im, &file).unwrap();
    let (code, out, _) = cachert(&["golden", "check", "--dir", d], true);
    assert!(code == 1 && out.contains("FAIL           bits"), "{out}");
    let (code, out, err) = cachert(&["golden", "check", "--tolerance", "--dir", d], true);
    assert!(code == 0 && out.contains("0 judged bit for bit") && out.contains("2 within the tolerance"), "{out}");
    assert!(err.contains("PASS within    tol.") && err.contains("[judged within the tolerance (asked"), "{err}");
    // A golden made on another platform passes within the tolerance, not by bits alone, and says why.
    let text = std::fs::read_to_string(dir.path("g/MANIFEST.json")).unwrap();
    let ours = format!("\"platform\": \"{}\"", golden::platform());
    assert!(text.contains(&ours), "{text}");
    std::fs::write(dir.path("g/MANIFEST.json"), text.replace(&ours, "\"platform\": \"riscv64-linux\"")).unwrap();
    let (code, out, err) = cachert(&["golden", "check", "--dir", d], true);
    assert_eq!(code, 0, "{out}");
    assert!(err.contains("PASS within") && err.contains("PASS identical"), "{err}");
    assert!(err.contains("[judged within the tolerance (made on riscv64-linux)]"), "{err}");
    let outcomes = golden::check(Path::new(d), Some("ao"), Some(1), false, &mut |_| {}).unwrap();
    assert_eq!(outcomes[0].verdict, Verdict::Within);

    // A broken manifest is an error naming the file; a missing folder too.
    std::fs::write(dir.path("g/MANIFEST.json"), "{").unwrap();
    let (code, _, err) = cachert(&["golden", "check", "--dir", d], true);
    assert!(code == 2 && err.contains("MANIFEST.json"), "{err}");
    let (code, _, err) = cachert(&["golden", "check", "--dir", dir.path("none").to_str().unwrap()], true);
    assert!(code == 2 && err.contains("cannot read the golden manifest"), "{err}");
}
