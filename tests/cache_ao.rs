//! Behaviour of the `cacheao` integrator (issue 5): analytic answers, every placement converging, exact
//! budgets, determinism, and bad or degenerate inputs giving a clear message or a sensible image.

mod common;

use std::path::Path;

use cachert::Warnings;
use cachert::image::Image;
use cachert::integrator::{RenderOutput, RenderSettings, render};
use cachert::scene::{LoadOptions, load, load_str};

/// Every placement name, plus the per-sample reference.
const PLACEMENTS: [&str; 10] =
    ["none", "im", "sd", "sd+as", "vgc", "vgc+dgs", "vgc+as", "vgc+dgs:diff", "vgc+dgs:geom", "refine"];

fn run(scene: &str, set: &[(&str, &str)], threads: Option<usize>) -> cachert::Result<RenderOutput> {
    let loaded = load_str(scene, Path::new("inline.pbrt"), LoadOptions::default())?;
    let settings = RenderSettings {
        set: set.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
        threads,
        seed: 7,
        ..Default::default()
    };
    render(&loaded.scene, loaded.integrator.as_ref(), &settings, &mut Warnings::default())
}

/// An orthographic camera looking down −z at the square [−4, 4]², 64×64 pixels, over `world`.
fn top_view(world: &str) -> String {
    format!(
        "LookAt 0 0 10  0 0 0  0 1 0\nCamera \"orthographic\" \"float screenwindow\" [-4 4 -4 4]\n\
         Film \"image\" \"integer xresolution\" 64 \"integer yresolution\" 64\n\
         Integrator \"cacheao\" \"float maxdistance\" 1e30\nWorldBegin\n{world}\nWorldEnd\n"
    )
}

const PLANE: &str = "Shape \"trianglemesh\" \"point P\" [-100 -100 0  100 -100 0  100 100 0  -100 100 0] \"integer indices\" [0 1 2 0 2 3]";
const SPHERE_CENTRE: [f64; 3] = [0.5, -0.3, 1.5];

/// The plane point seen by pixel (x, y) of [`top_view`]: pbrt's camera is left-handed, so raster x runs
/// along world −x when looking down −z with +y up.
fn plane_point(x: usize, y: usize) -> [f64; 2] {
    let sx = -4.0 + (x as f64 + 0.5) / 64.0 * 8.0;
    let sy = 4.0 - (y as f64 + 0.5) / 64.0 * 8.0;
    [-sx, sy]
}

/// Closed-form normalised AO on the plane under a unit sphere: 1 − (r/d)²·cos θ (the cosine-weighted
/// fraction of the hemisphere a fully visible sphere covers), or `None` near the sphere's own footprint.
fn sphere_ao(x: usize, y: usize) -> Option<f64> {
    let [px, py] = plane_point(x, y);
    let [cx, cy, cz] = SPHERE_CENTRE;
    if (px - cx).hypot(py - cy) < 1.3 {
        return None;
    }
    let d = ((cx - px).powi(2) + (cy - py).powi(2) + cz * cz).sqrt();
    Some(1.0 - (1.0 / d).powi(2) * (cz / d))
}

fn rmse_to_closed_form(img: &Image) -> (f64, f64) {
    let (mut sum, mut max, mut n) = (0.0, 0.0f64, 0);
    for y in 0..64 {
        for x in 0..64 {
            if let Some(exact) = sphere_ao(x, y) {
                let e = img.get(x, y)[0] as f64 - exact;
                sum += e * e;
                max = max.max(e.abs());
                n += 1;
            }
        }
    }
    ((sum / n as f64).sqrt(), max)
}

fn sphere_scene() -> String {
    let [x, y, z] = SPHERE_CENTRE;
    top_view(&format!("{PLANE}\nTranslate {x} {y} {z}\nShape \"sphere\" \"float radius\" 1"))
}

#[test]
fn an_unoccluded_plane_has_ao_one_for_every_placement() {
    for p in PLACEMENTS {
        let out = run(&top_view(PLANE), &[("placement", p), ("caches", "300")], None).unwrap();
        for px in &out.image.pixels {
            assert!((px[0] - 1.0).abs() < 1e-5, "{p}: {px:?}");
        }
    }
}

#[test]
fn the_reference_meets_the_sphere_closed_form_within_its_discretisation() {
    // The 32×32 equal-area gather integrates the cosine-weighted visibility exactly except in cells the
    // sphere's outline crosses; each cell weighs cos θ_k / Σ cos ≤ 1/512 (Σ cos ≈ n²/2), and a handful of
    // cells straddle the outline with errors of both signs: allow six cells' worth.
    let out = run(&sphere_scene(), &[("placement", "none")], None).unwrap();
    let (rmse, max) = rmse_to_closed_form(&out.image);
    assert!(max < 6.0 / 512.0, "max error {max}, rmse {rmse}");
}

#[test]
fn every_placement_approaches_the_closed_form_as_caches_grow() {
    for p in &PLACEMENTS[1..] {
        let errs: Vec<f64> = ["100", "400", "1600"]
            .iter()
            .map(|c| {
                rmse_to_closed_form(&run(&sphere_scene(), &[("placement", p), ("caches", c)], None).unwrap().image).0
            })
            .collect();
        assert!(errs[2] < errs[0], "{p}: {errs:?}");
        assert!(errs[2] < 0.02, "{p}: {errs:?}");
    }
}

#[test]
fn budgets_are_exact_and_split_by_the_stage_two_share() {
    for p in &PLACEMENTS[1..] {
        let out = run(&sphere_scene(), &[("placement", p), ("caches", "500")], None).unwrap();
        let c = out.cache.unwrap();
        assert_eq!(c.stats.total_caches, 500, "{p}");
        let mut sites: Vec<u32> = c.stage1.iter().chain(&c.stage2).copied().collect();
        sites.sort_unstable();
        sites.dedup();
        assert_eq!(sites.len(), 500, "{p}: two caches on one pixel");
        // The paper's two-stage strategies give stage 2 `ratio` (0.15) of the budget, refine `refineshare` (0.8).
        let stage2 = match *p {
            "refine" => 400,
            p if p.contains('+') => 75,
            _ => 0,
        };
        assert_eq!(c.stage2.len(), stage2, "{p}");
    }
}

#[test]
fn same_seed_same_image_at_one_and_two_threads() {
    for p in ["im", "sd+as", "vgc+dgs"] {
        let a = run(&sphere_scene(), &[("placement", p), ("caches", "200")], Some(1)).unwrap();
        let b = run(&sphere_scene(), &[("placement", p), ("caches", "200")], Some(2)).unwrap();
        assert_eq!(a.image, b.image, "{p}");
        let (ca, cb) = (a.cache.unwrap(), b.cache.unwrap());
        assert_eq!((ca.stage1, ca.stage2), (cb.stage1, cb.stage2), "{p}");
    }
}

#[test]
fn a_budget_of_zero_is_an_error_and_one_cache_renders() {
    let e = run(&sphere_scene(), &[("placement", "vgc+dgs"), ("caches", "0")], None).unwrap_err().to_string();
    assert!(e.contains("\"caches\" must be at least 1"), "{e}");
    for p in &PLACEMENTS[1..] {
        // VGC's automatic σ_a is raised (with a note) when the budget is too small for it.
        let out = run(&sphere_scene(), &[("placement", p), ("caches", "1")], None).unwrap();
        assert_eq!(out.cache.unwrap().stats.total_caches, 1, "{p}");
        assert!(out.image.pixels.iter().all(|px| px[0].is_finite() && px[0] >= 0.0), "{p}");
    }
}

#[test]
fn more_caches_than_pixels_caches_every_pixel_with_a_note() {
    let scene = top_view(PLANE)
        .replace("xresolution\" 64 \"integer yresolution\" 64", "xresolution\" 8 \"integer yresolution\" 8");
    for p in &PLACEMENTS[1..] {
        let out = run(&scene, &[("placement", p), ("caches", "1000")], None).unwrap();
        let c = out.cache.unwrap();
        assert_eq!(c.stats.total_caches, 64, "{p}");
        assert!(c.stats.notes.iter().any(|n| n.contains("every valid pixel")), "{p}: {:?}", c.stats.notes);
    }
}

#[test]
fn an_all_sky_image_is_black_with_a_note() {
    let scene = top_view("Translate 0 0 -100\nShape \"sphere\" \"float radius\" 0.01")
        .replace("0 0 10  0 0 0  0 1 0", "0 0 10  0 0 20  0 1 0");
    for p in PLACEMENTS {
        let out = run(&scene, &[("placement", p)], None).unwrap();
        assert!(out.image.pixels.iter().all(|px| *px == [0.0; 3]), "{p}");
        let c = out.cache.unwrap();
        assert_eq!(c.stats.valid_pixels, 0);
        assert!(c.stats.notes.iter().any(|n| n.contains("no pixel")), "{p}");
    }
}

#[test]
fn a_tiny_sigma_a_names_itself_and_the_budget() {
    let e = run(&sphere_scene(), &[("placement", "vgc"), ("caches", "20"), ("sigma_a", "0.001")], None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("0.001") && e.contains("20"), "{e}");
}

#[test]
fn coincident_shading_points_from_instances_do_not_break_placement() {
    // The same object instanced twice at the same place: every pixel's shading point appears twice in the
    // scene, and large flat regions give many identical normals.
    let world = format!(
        "ObjectBegin \"p\"\n{PLANE}\nShape \"sphere\" \"float radius\" 1\nObjectEnd\nObjectInstance \"p\"\nObjectInstance \"p\""
    );
    for p in &PLACEMENTS[1..] {
        let out = run(&top_view(&world), &[("placement", p), ("caches", "300")], None).unwrap();
        assert_eq!(out.cache.unwrap().stats.total_caches, 300, "{p}");
        assert!(out.image.pixels.iter().all(|px| px[0].is_finite()), "{p}");
    }
}

#[test]
fn unknown_placements_and_parameters_are_errors_listing_the_valid_ones() {
    let e = run(&sphere_scene(), &[("placement", "vgc+foo")], None).unwrap_err().to_string();
    assert!(e.contains("vgc+foo") && e.contains("vgc+dgs:geom") && e.contains("none"), "{e}");
    let e = run(&sphere_scene(), &[("sdminsiz", "3")], None).unwrap_err().to_string();
    assert!(e.contains("sdminsiz") && e.contains("sdminsize"), "{e}");
}

#[test]
fn nan_normals_from_a_ply_are_dropped_with_a_warning_and_the_image_is_finite() {
    let dir = common::TempDir::new("nan-ply");
    // A square at z = 0 whose second vertex normal is NaN.
    dir.write(
        "bad.ply",
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\nelement face 2\n\
         property list uchar int vertex_indices\nend_header\n\
         -100 -100 0 0 0 1\n100 -100 0 nan 0 1\n100 100 0 0 0 1\n-100 100 0 0 0 1\n3 0 1 2\n3 0 2 3\n",
    );
    let world = "Shape \"plymesh\" \"string filename\" \"bad.ply\"\nTranslate 0.5 -0.3 1.5\nShape \"sphere\" \"float radius\" 1";
    let path = dir.write("s.pbrt", top_view(world));
    let loaded = load(&path, LoadOptions::default()).unwrap();
    assert!(loaded.warnings.iter().any(|w| w.msg.contains("NaN, infinite or zero")), "{:?}", loaded.warnings);
    for p in ["none", "sd+as", "vgc+dgs"] {
        let s = RenderSettings {
            set: vec![("placement".into(), p.into()), ("caches".into(), "300".into())],
            seed: 7,
            ..Default::default()
        };
        let out = render(&loaded.scene, loaded.integrator.as_ref(), &s, &mut Warnings::default()).unwrap();
        assert!(out.image.pixels.iter().all(|px| px.iter().all(|c| c.is_finite() && *c >= 0.0)), "{p}");
        // The same plane as the analytic scene: the sphere's closed form still holds.
        assert!(rmse_to_closed_form(&out.image).0 < 0.03, "{p}");
    }
}

#[test]
fn error_falls_as_caches_grow_on_the_shipped_room() {
    // scenes/room.pbrt at 64×48, against the per-sample reference of the same gather.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/room.pbrt");
    let loaded = load(&path, LoadOptions { resolution: Some([64, 48]), ..Default::default() }).unwrap();
    let go = |p: &str, caches: &str| {
        let s = RenderSettings {
            integrator: Some("cacheao".into()),
            set: vec![("placement".into(), p.into()), ("caches".into(), caches.into())],
            seed: 3,
            ..Default::default()
        };
        render(&loaded.scene, loaded.integrator.as_ref(), &s, &mut Warnings::default()).unwrap().image
    };
    let reference = go("none", "1");
    for p in &PLACEMENTS[1..6] {
        let errs: Vec<f64> =
            ["60", "240", "960"].iter().map(|c| cachert::metrics::rmse(&go(p, c), &reference).unwrap()).collect();
        assert!(errs[1] < errs[0] && errs[2] < errs[1], "{p}: {errs:?}");
    }
}

#[test]
fn the_documented_parameter_tables_are_exactly_what_cacheao_reads() {
    use cachert::application::Application;
    use cachert::application::ambient_occlusion::CacheAo;
    use cachert::integrator::cache::{self, PARAMETERS};
    let e = run(&sphere_scene(), &[("zzz", "1")], None).unwrap_err().to_string();
    let (_, list) = e.split_once("it reads: ").unwrap_or_else(|| panic!("{e}"));
    let mut read: Vec<&str> = list.trim_end_matches(')').split(", ").collect();
    let mut documented: Vec<&str> = PARAMETERS.iter().chain(CacheAo::PARAMETERS).map(|p| p.name).collect();
    read.sort_unstable();
    documented.sort_unstable();
    assert_eq!(read, documented);
    let help = cache::help();
    assert!(documented.iter().all(|n| help.contains(n)) && help.contains("cacheao"), "{help}");
}
