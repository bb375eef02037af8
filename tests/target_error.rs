//! refine with a target error instead of a count (issue 43): the error it achieves against the per-sample
//! reference (rendered here, independently of the estimate) is near what was asked, the estimates are in
//! the statistics, a target it cannot meet is a note, and a target given to any other placement is refused
//! with the place it was written and exit status 2.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use cachert::image::Image;
use cachert::integrator::RenderSettings;
use cachert::integrator::cache::{CacheOverrides, Placement};
use cachert::scene::LoadOptions;
use common::{TempDir, mean, render_file, settings};

fn room() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/room.pbrt")
}

/// The shipped room with cache AO at 128×96, placed by `placement` with `target` and a ceiling of every pixel.
fn render(placement: Placement, target: Option<f64>, caches: usize) -> cachert::integrator::RenderOutput {
    render_with("cacheao", &[], placement, target, caches)
}

/// The shipped room at 128×96 with `integrator` and its parameters `set`, placed by `placement` with `target`
/// and a ceiling of `caches`.
fn render_with(
    integrator: &str,
    set: &[(&str, &str)],
    placement: Placement,
    target: Option<f64>,
    caches: usize,
) -> cachert::integrator::RenderOutput {
    let s = RenderSettings {
        integrator: Some(integrator.into()),
        set: set.iter().map(|&(k, v)| (k.to_string(), v.to_string())).collect(),
        cache: CacheOverrides {
            placement: Some(placement),
            caches: Some(caches),
            subpixels: None,
            target_error: target,
        },
        ..settings(7)
    };
    let opts = LoadOptions { resolution: Some([128, 96]), ..Default::default() };
    render_file(&room(), opts, &s).unwrap_or_else(|e| panic!("{e}")).0
}

fn relative_rmse(test: &Image, reference: &Image) -> f64 {
    cachert::metrics::rmse(test, reference).unwrap() / mean(reference)
}

#[test]
fn the_achieved_error_is_near_the_target_and_the_estimates_are_reported() {
    let reference = render(Placement::Reference, None, 1).image;
    for target in [0.05, 0.1] {
        let out = render(Placement::Strategy("refine"), Some(target), 1_000_000);
        let stats = &out.cache.as_ref().unwrap().stats;
        let achieved = relative_rmse(&out.image, &reference);
        let est = &stats.error_estimates;
        println!("target {target}: {} caches, estimates {est:?}, achieved {achieved:.4}", stats.total_caches);
        let last = est.last().expect("refine records its estimates");
        assert_eq!(last.caches, stats.total_caches);
        assert!(last.relative_rmse as f64 <= target, "the rounds stopped before the estimate met {target}");
        assert!(est.windows(2).all(|w| w[1].caches > w[0].caches));
        // The band is 0.67–1.5× on the stability scenes (experiments/results/refine-target); this
        // small image is held to it too.
        let ratio = achieved / target;
        assert!((0.67..=1.5).contains(&ratio), "target {target}: achieved {achieved:.4} ({ratio:.2}×)");
        assert!(stats.total_caches < 128 * 96 / 2, "{} caches for {target}", stats.total_caches);
    }
}

#[test]
fn importance_caching_meets_a_target_from_the_noise_its_neighbours_sample_with() {
    // Its shading is unbiased: the estimate is the variance of a pixel drawing lights from a cache's
    // neighbours' distributions (src/application/importance/leave_one_out.rs), not a miss of its value.
    let imc = |placement, target| render_with("importancecache", &[("vpls", "1024")], placement, target, 1_000_000);
    let reference = imc(Placement::Reference, None).image;
    for target in [0.05, 0.1] {
        let out = imc(Placement::Strategy("refine"), Some(target));
        let stats = &out.cache.as_ref().unwrap().stats;
        let achieved = relative_rmse(&out.image, &reference);
        let est = &stats.error_estimates;
        println!(
            "importance caching, target {target}: {} caches, estimates {est:?}, achieved {achieved:.4}",
            stats.total_caches
        );
        assert!(est.last().is_some_and(|e| e.relative_rmse as f64 <= target), "{est:?}");
        assert!(stats.notes.iter().all(|n| !n.contains("not met")), "{:?}", stats.notes);
        let ratio = achieved / target;
        assert!((0.67..=1.5).contains(&ratio), "target {target}: achieved {achieved:.4} ({ratio:.2}×)");
    }
}

#[test]
fn importance_caching_draws_fewer_lights_for_a_target_its_first_caches_beat() {
    // Its error hardly grows with fewer caches, so a loose target is met by the first stage several times over;
    // shading then draws fewer lights (refine asks the estimate again with them), and the image is cheaper and
    // nearer the error asked for.
    let imc = |placement, target| render_with("importancecache", &[("vpls", "1024")], placement, target, 1_000_000);
    let reference = imc(Placement::Reference, None).image;
    let out = imc(Placement::Strategy("refine"), Some(0.25));
    let cache = out.cache.as_ref().unwrap();
    let (stats, est) = (&cache.stats, &cache.stats.error_estimates);
    let achieved = relative_rmse(&out.image, &reference);
    println!("importance caching, target 0.25: estimates {est:?}, notes {:?}, achieved {achieved:.4}", stats.notes);
    assert!(stats.notes.iter().any(|n| n.contains("shading draws 0.25 of its samples")), "{:?}", stats.notes);
    assert_eq!(cache.settings["lightsamples"], 2, "8 draws per technique thinned to 2");
    let (first, last) = (est[0], est[est.len() - 1]);
    assert!(last.caches == first.caches && last.relative_rmse > first.relative_rmse && last.relative_rmse <= 0.25);
    let ratio = achieved / 0.25;
    assert!((0.67..=1.5).contains(&ratio), "achieved {achieved:.4} ({ratio:.2}×)");
    // Cache AO's error is its interpolation's: its draws are never thinned.
    let ao = render(Placement::Strategy("refine"), Some(0.5), 1_000_000);
    assert!(ao.cache.unwrap().stats.notes.iter().all(|n| !n.contains("shading draws")));
}

#[test]
fn irradiance_caching_meets_a_target_near_its_gathering_noise_without_a_cache_at_every_pixel() {
    // 8×8 gathering paths per record: the records are noisy, and so is the reference (the same gathering at
    // each sub-pixel sample), so a cache at every pixel still leaves an error. The estimate takes the
    // records' noise out of their misses and counts the blend's and the reference's as floors
    // (IrradianceCache::predict); counted as miss, that noise read the floor 1.26× high here and a target
    // 1.3× above the floor placed every pixel.
    let set = [("gather", "8"), ("output", "indirect")];
    let irc = |placement, target| render_with("irradiancecache", &set, placement, target, 1_000_000);
    let reference = irc(Placement::Reference, None).image;
    let every = irc(Placement::Strategy("refine"), Some(1e-4));
    let floor = relative_rmse(&every.image, &reference);
    assert_eq!(every.cache.as_ref().unwrap().stats.total_caches, 128 * 96, "the room has no background");
    let target = 0.08;
    let out = irc(Placement::Strategy("refine"), Some(target));
    let stats = &out.cache.as_ref().unwrap().stats;
    let achieved = relative_rmse(&out.image, &reference);
    let est = &stats.error_estimates;
    println!(
        "irradiance caching: floor {floor:.4}; target {target}: {} caches, estimates {est:?}, achieved {achieved:.4}",
        stats.total_caches
    );
    assert!(floor < target && target < 1.5 * floor, "floor {floor:.4}: the target is meant to sit just above it");
    assert!(est.last().is_some_and(|e| e.relative_rmse as f64 <= target), "{est:?}");
    assert!(stats.total_caches < 128 * 96 / 4, "{} caches for {target}", stats.total_caches);
    let ratio = achieved / target;
    assert!((0.67..=1.5).contains(&ratio), "target {target}: achieved {achieved:.4} ({ratio:.2}×)");
}

#[test]
fn a_target_the_ceiling_cannot_reach_places_the_ceiling_with_a_note() {
    let out = render(Placement::Strategy("refine"), Some(1e-4), 300);
    let stats = &out.cache.as_ref().unwrap().stats;
    assert_eq!(stats.total_caches, 300);
    assert!(stats.notes.iter().any(|n| n.contains("targeterror") && n.contains("not met")), "{:?}", stats.notes);
}

#[test]
fn a_target_for_another_placement_is_refused_where_it_was_written() {
    let dir = TempDir::new("target-error");
    let scene = "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [30]\n\
                 Film \"image\" \"integer xresolution\" [8] \"integer yresolution\" [8]\n\
                 Integrator \"cacheao\" \"string placement\" \"vgc+dgs\" \"float targeterror\" [0.05]\n\
                 WorldBegin\nShape \"sphere\"\nWorldEnd\n";
    dir.write("t.pbrt", scene);
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_cachert")).args(args).current_dir(&dir.0).output().expect("the binary runs")
    };
    let o = run(&["render", "t.pbrt", "--outfile", "out.exr"]);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.starts_with("error: t.pbrt:4:"), "{err}");
    assert!(err.contains("\"targeterror\" needs placement \"refine\" (the placement is \"vgc+dgs\")"), "{err}");
    let o = run(&["render", "t.pbrt", "--outfile", "out.exr", "--placement", "im", "--target-error", "0.1"]);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--target-error needs placement \"refine\" (the placement is \"im\")"), "{err}");
    let o = run(&["render", "t.pbrt", "--outfile", "out.exr", "--placement", "refine", "--target-error", "-1"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(err.contains("--target-error") && err.contains("expected a positive relative RMSE such as 0.05"), "{err}");
    assert_eq!(dir.entries(), vec!["t.pbrt"], "a refused render leaves nothing behind");
    // With refine the scene's target is taken.
    let o = run(&["render", "t.pbrt", "--outfile", "out.exr", "--placement", "refine", "--quiet"]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
}
