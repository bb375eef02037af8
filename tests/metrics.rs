//! Behaviour of the metrics as experiments use them: agreement with NVIDIA's FLIP on the shared test
//! vectors, known answers, thread-count independence, and the `compare` command end to end.

mod common;

use std::path::{Path, PathBuf};

use cachert::image::{self, Image};
use cachert::metrics::pattern::pattern;
use cachert::metrics::{self, Metric, flip};
use common::flip_vectors;

/// The shared FLIP test vectors must be here: fails, with the reason, where they are absent (outside CI the
/// test that needs them prints a `skipped` line and passes; under CI it fails too).
#[test]
fn shared_flip_vectors_present() {
    common::assert_flip_vectors_present();
}

#[test]
fn flip_matches_nvidia_flip_evaluator_on_the_shared_vectors() {
    let Some(dir) = flip_vectors() else { return };
    let expected = std::fs::read_to_string(dir.join("expected.txt")).unwrap();
    let mut checked = 0;
    for line in expected.lines().filter(|l| !l.starts_with('#') && !l.trim().is_empty()) {
        let f: Vec<&str> = line.split_whitespace().collect();
        let [pair, reference, test, mode, value] = f[..] else { panic!("bad line {line:?}") };
        let want: f64 = value.parse().unwrap();
        let reference = image::read(&dir.join(reference)).unwrap();
        let test = image::read(&dir.join(test)).unwrap();
        let got = match mode {
            "ldr" => flip::ldr_flip_map(&test, &reference, flip::DEFAULT_PPD).unwrap().mean(),
            "hdr" => flip::hdr_flip_map(&test, &reference, flip::DEFAULT_PPD).unwrap().map.mean(),
            _ => panic!("unknown mode {mode}"),
        };
        println!("{pair:16} {mode}: expected {want:.6}, got {got:.6}, difference {:+.2e}", got - want);
        assert!((got - want).abs() <= 1e-3, "{pair} {mode}: expected {want}, got {got}");
        checked += 1;
    }
    assert_eq!(checked, 6);
}

#[test]
fn one_changed_pixel_matches_flip_evaluator() {
    // 17×11: columns 0–10 at 0.25, the rest at 4.0; the test differs only at (x 5, y 7).
    // Expected values from flip-evaluator 1.7 (numpy rows are image rows, top first).
    let mut reference = Image::new(17, 11);
    for y in 0..11 {
        for x in 0..17 {
            reference.set(x, y, [if x < 11 { 0.25 } else { 4.0 }; 3]);
        }
    }
    let mut test = reference.clone();
    test.set(5, 7, [1.0, 0.2, 0.5]);

    let ldr = flip::ldr_flip_map(&test, &reference, flip::DEFAULT_PPD).unwrap();
    assert!((ldr.mean() - 0.019_195_951).abs() < 1e-6, "{}", ldr.mean());
    assert!((ldr.values[7 * 17 + 5] - 0.278_477_67).abs() < 1e-6);
    let worst = (0..ldr.values.len()).max_by(|&a, &b| ldr.values[a].total_cmp(&ldr.values[b])).unwrap();
    assert_eq!((worst % 17, worst / 17), (5, 7));
    assert_eq!(ldr.values[16], 0.0);

    let hdr = flip::hdr_flip_map(&test, &reference, flip::DEFAULT_PPD).unwrap();
    assert_eq!(hdr.exposures.count, 4);
    assert!((hdr.exposures.start - -0.916_702_8).abs() < 1e-6 && (hdr.exposures.stop - 3.083_297_3).abs() < 1e-6);
    assert!((hdr.map.mean() - 0.016_448_347).abs() < 1e-6, "{}", hdr.map.mean());
    assert!((hdr.map.values[7 * 17 + 5] - 0.214_383_33).abs() < 1e-6);
}

#[test]
fn non_finite_test_values_match_flip_evaluator() {
    // 9×9 reference: columns 0–3 at 2.0, the rest 0.5; the test's red at (4, 4) is NaN, +∞ or −∞.
    // Expected (LDR, HDR) means from flip-evaluator 1.7.
    let mut reference = Image::new(9, 9);
    for y in 0..9 {
        for x in 0..9 {
            reference.set(x, y, [if x < 4 { 2.0 } else { 0.5 }; 3]);
        }
    }
    for (v, ldr, hdr) in [
        (f32::NAN, 0.025_070_2, 0.035_242_5),
        (f32::INFINITY, 0.025_214_5, 0.035_242_5),
        (f32::NEG_INFINITY, 0.025_070_2, 0.035_242_5),
    ] {
        let mut test = reference.clone();
        test.set(4, 4, [v, 0.5, 0.5]);
        let l = flip::ldr_flip_map(&test, &reference, flip::DEFAULT_PPD).unwrap().mean();
        let h = flip::hdr_flip_map(&test, &reference, flip::DEFAULT_PPD).unwrap().map.mean();
        assert!((l - ldr).abs() < 1e-6 && (h - hdr).abs() < 1e-6, "{v}: {l} {h}");
    }
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let reference = pattern(61, 47, 1, 0.0);
    let test = pattern(61, 47, 2, 0.3);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let hdr = flip::hdr_flip_map(&test, &reference, flip::DEFAULT_PPD).unwrap();
            let ldr = flip::ldr_flip_map(&test, &reference, flip::DEFAULT_PPD).unwrap();
            let rmse = metrics::rmse(&test, &reference).unwrap();
            let relmse = metrics::relmse(&test, &reference).unwrap();
            (hdr, ldr, rmse.to_bits(), relmse.to_bits())
        })
    };
    let one = run(1);
    for threads in [2, 3, 5] {
        let other = run(threads);
        assert!(one.0.map.values.iter().zip(&other.0.map.values).all(|(a, b)| a.to_bits() == b.to_bits()));
        assert!(one.1.values.iter().zip(&other.1.values).all(|(a, b)| a.to_bits() == b.to_bits()));
        assert_eq!((one.2, one.3), (other.2, other.3));
        assert_eq!(one.0.map.mean().to_bits(), other.0.map.mean().to_bits());
    }
}

#[test]
fn flip_grows_with_the_error() {
    let reference = pattern(48, 32, 1, 0.0);
    let mut last = 0.0;
    for (i, noise) in [0.01f32, 0.1, 0.5, 2.0].into_iter().enumerate() {
        let test = pattern(48, 32, 10 + i as u64, noise);
        let v = metrics::compare(&test, &reference, &[Metric::Flip]).unwrap()[0].1;
        assert!(v > last && v < 1.0, "noise {noise}: {v} after {last}");
        last = v;
    }
}

/// A fresh scratch directory under the system temp dir.
fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cachert-metrics-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

mod compare_command {
    use super::*;
    use cachert::cli::compare::{CompareArgs, run};
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: CompareArgs,
    }

    fn args(list: &[&str]) -> CompareArgs {
        Cli::try_parse_from(std::iter::once("compare").chain(list.iter().copied())).unwrap().args
    }

    fn files(dir: &Path) -> (String, String) {
        let reference = pattern(40, 30, 1, 0.0);
        let test = pattern(40, 30, 2, 0.2);
        let (t, r) = (dir.join("test.pfm"), dir.join("ref.exr"));
        image::write(&test, &t).unwrap();
        image::write(&reference, &r).unwrap();
        (t.display().to_string(), r.display().to_string())
    }

    #[test]
    fn default_metrics_one_line_each() {
        let dir = scratch("cli-default");
        let (t, r) = files(&dir);
        let a = args(&[&t, &r]);
        assert_eq!(a.metric, vec![Metric::Rmse, Metric::Flip]);
        let out = run(&a).unwrap();
        let lines: Vec<&str> = out.lines().collect();
        assert_eq!(lines.len(), 2, "{out}");
        assert!(lines[0].starts_with("rmse ") && lines[1].starts_with("flip "), "{out}");
        let rmse: f64 = lines[0][5..].parse().unwrap();
        let expected =
            metrics::rmse(&image::read(Path::new(&t)).unwrap(), &image::read(Path::new(&r)).unwrap()).unwrap();
        assert!((rmse - expected).abs() < 1e-6);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn json_and_maps() {
        let dir = scratch("cli-json");
        let (t, r) = files(&dir);
        let (fm, dm) = (dir.join("flip.png"), dir.join("diff.exr"));
        let a = args(&[
            &t,
            &r,
            "--metric",
            "ldrflip,relmse,flip",
            "--json",
            "--flip-map",
            fm.to_str().unwrap(),
            "--diff-map",
            dm.to_str().unwrap(),
        ]);
        let out = run(&a).unwrap();
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["width"], 40);
        let flip_value = v["metrics"]["flip"].as_f64().unwrap();
        assert!(flip_value > 0.0 && flip_value < 1.0);
        assert!(v["metrics"]["ldrflip"].as_f64().is_some() && v["metrics"]["relmse"].as_f64().is_some());
        assert!(v["hdr_flip"]["exposures"]["count"].as_u64().unwrap() >= 2);
        let png = image::read(&fm).unwrap();
        assert_eq!((png.width, png.height), (40, 30));
        let diff = image::read(&dm).unwrap();
        let test = image::read(Path::new(&t)).unwrap();
        let reference = image::read(Path::new(&r)).unwrap();
        assert_eq!(diff.get(3, 4)[1], (test.get(3, 4)[1] - reference.get(3, 4)[1]).abs());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn raw_flip_map_as_exr_has_the_flip_mean() {
        let dir = scratch("cli-raw");
        let (t, r) = files(&dir);
        let fm = dir.join("flip.pfm");
        let out = run(&args(&[&t, &r, "--metric", "rmse", "--flip-map", fm.to_str().unwrap()])).unwrap();
        assert_eq!(out.lines().count(), 1);
        let map = image::read(&fm).unwrap();
        let mean = map.mean()[0];
        let direct = flip::hdr_flip_map(
            &image::read(Path::new(&t)).unwrap(),
            &image::read(Path::new(&r)).unwrap(),
            flip::DEFAULT_PPD,
        )
        .unwrap();
        assert!((mean - direct.map.mean()).abs() < 1e-12);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_inputs_name_the_file() {
        let dir = scratch("cli-bad");
        let (t, r) = files(&dir);
        let missing = dir.join("missing.exr");
        let e = run(&args(&[&t, missing.to_str().unwrap()])).unwrap_err().to_string();
        assert!(e.contains("missing.exr"), "{e}");

        let small = dir.join("small.pfm");
        image::write(&Image::new(4, 4), &small).unwrap();
        let e = run(&args(&[small.to_str().unwrap(), &r])).unwrap_err().to_string();
        assert!(e.contains("small.pfm") && e.contains("4×4") && e.contains("40×30"), "{e}");

        let mut nan = pattern(40, 30, 1, 0.0);
        nan.set(12, 3, [0.0, f32::NAN, 0.0]);
        let nan_path = dir.join("nan.pfm");
        image::write(&nan, &nan_path).unwrap();
        let e = run(&args(&[&t, nan_path.to_str().unwrap()])).unwrap_err().to_string();
        assert!(e.contains("nan.pfm") && e.contains("(12, 3)") && e.contains("channel G"), "{e}");

        let e = run(&args(&[&t, &r, "--flip-map", "out.jpg"])).unwrap_err().to_string();
        assert!(e.contains(".exr, .pfm or .png"), "{e}");
        assert!(Cli::try_parse_from(["compare", &t, &r, "--metric", "psnr"]).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
