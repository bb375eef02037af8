//! Light sources (src/shading/light): irradiance from sphere, disk and quad lights against closed forms;
//! the other shapes, scaled shapes and environment maps against an independent estimate (cosine-sampled
//! rays through the geometry, counting what `emitted`/`le_escaped` return); sample/pdf consistency; the
//! environment map's pdf over the sphere; light selection; bad input; and three pbrt-v3 renders
//! (tests/data/pbrt-v3/lights): an environment map seen directly, emitters seen directly (which side
//! emits), and point/spot/distant lights on a matte floor with a shadowing sphere.

mod common;

use std::f32::consts::PI;
use std::path::{Path, PathBuf};

use cachert::Warnings;
use cachert::image::Image;
use cachert::sampling::warp::cosine_hemisphere;
use cachert::sampling::{Frame, Rng};
use cachert::scene::geometry::SurfaceInteraction;
use cachert::scene::ray::Ray;
use cachert::scene::{LoadOptions, LoadedScene, Scene, load_str};
use cachert::shading::Spectrum;
use cachert::shading::light::{LightSelect, Lights};
use glam::Vec3A;

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pbrt-v3/lights")
}

/// Loads scene text as if it were a file in the test data folder (so relative map names resolve there).
fn load(text: &str) -> LoadedScene {
    load_str(text, &data_dir().join("inline.pbrt"), LoadOptions::default()).unwrap_or_else(|e| panic!("load: {e}"))
}

fn build_lights(scene: &Scene) -> Lights<'_> {
    let mut w = Warnings::default();
    Lights::build(scene, &mut w).unwrap_or_else(|e| panic!("lights: {e}"))
}

/// A floor quad at z = 0 facing +z, 20 wide.
const FLOOR: &str =
    "Shape \"trianglemesh\" \"point P\" [-10 -10 0  10 -10 0  10 10 0  -10 10 0] \"integer indices\" [0 1 2 0 2 3]\n";

/// The surface interaction on the floor at (x, y), found by a ray from below (so no emitter is in the way).
fn floor_point(scene: &Scene, x: f32, y: f32) -> SurfaceInteraction {
    let si = scene.geometry.intersect(&Ray::new(Vec3A::new(x, y, -1.0), Vec3A::Z)).expect("the floor is there");
    assert!(si.p.z.abs() < 1e-5 && si.ng.z > 0.99);
    si
}

/// Mean and standard error of `f` over an n×n stratified grid with a seeded jitter.
fn mc(n: usize, seed: u64, mut f: impl FnMut([f32; 2]) -> Vec3A) -> (Vec3A, Vec3A) {
    let mut rng = Rng::new(seed);
    let (mut sum, mut sum2) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
    for j in 0..n {
        for i in 0..n {
            let [a, b] = rng.uniform2();
            let u = [((i as f32 + a) / n as f32).min(0.999_999), ((j as f32 + b) / n as f32).min(0.999_999)];
            let v = f(u).as_dvec3();
            sum += v;
            sum2 += v * v;
        }
    }
    let m = (n * n) as f64;
    let mean = sum / m;
    let var = (sum2 / m - mean * mean).max(glam::DVec3::ZERO);
    (mean.as_vec3a(), (var / m).as_vec3a().powf(0.5))
}

/// Irradiance at `si` by light sampling of every light (shadow rays traced), with its standard error.
/// `convex`: the emitter cannot hide parts of itself from `si`. Also checks, for each sample, that pdf_li and pdf_li_hit give the sample's pdf back (to 0.2 %; at most
/// 1 % of the samples may miss that: a direction rounded into the neighbouring cell of an environment
/// map, or a grazing hit whose normal the intersection's rounding moves).
fn irradiance_by_light_sampling(
    scene: &Scene,
    l: &Lights,
    si: &SurfaceInteraction,
    n: usize,
    convex: bool,
) -> (Vec3A, Vec3A) {
    let mut total = (Vec3A::ZERO, Vec3A::ZERO);
    for light in 0..l.len() {
        let (mut blocked, mut off, mut far_off, mut checked) = (0, 0, 0, 0);
        let (e, err) = mc(n, 7 + light as u64, |u| {
            let Some(s) = l.sample_li(light, si, u) else { return Vec3A::ZERO };
            if scene.geometry.occluded_from(&s.shadow, si.origin) {
                blocked += 1;
                return Vec3A::ZERO;
            }
            if !s.is_delta {
                checked += 1;
                let p = l.pdf_li(light, si, s.wi);
                let mut worst = (p - s.pdf).abs() / s.pdf;
                if let Some(hit) = scene.geometry.intersect(&si.spawn_ray(s.wi)) {
                    assert_eq!(l.light_of_hit(&hit), Some(light), "the sampled direction hits the light");
                    worst = worst.max((l.pdf_li_hit(light, si, &hit) - s.pdf).abs() / s.pdf);
                }
                let ok = worst <= 2e-3;
                if worst > 0.05 {
                    far_off += 1;
                }
                if !ok {
                    off += 1;
                }
            }
            s.li * s.wi.dot(si.ng).max(0.0) / s.pdf
        });
        // A convex or flat emitter never hides its own samples; a cylinder's far side is hidden by its near side.
        assert!(!convex || blocked == 0, "light {light}: {blocked} shadow rays toward an unblocked light were blocked");
        assert!(
            off * 20 <= checked && far_off * 100 <= checked,
            "light {light}: of {checked} samples, {off} have \
             another pdf_li (> 0.2 %), {far_off} by more than 5 %"
        );
        total.0 += e;
        total.1 += err * err;
    }
    (total.0, total.1.powf(0.5))
}

/// Irradiance at `si` from cosine-sampled rays: π × mean of what the rays see (emitters or the
/// environment). Independent of the light samplers.
fn irradiance_by_rays(scene: &Scene, l: &Lights, si: &SurfaceInteraction, n: usize) -> (Vec3A, Vec3A) {
    let frame = Frame::from_normal(si.ng);
    let (m, e) = mc(n, 99, |u| {
        let ray = si.spawn_ray(frame.to_world(cosine_hemisphere(u)));
        match scene.geometry.intersect(&ray) {
            Some(hit) => l.emitted(&hit, -ray.d),
            None => l.le_escaped(&ray),
        }
    });
    (m * PI, e * PI)
}

fn assert_close(what: &str, got: (Vec3A, Vec3A), want: Vec3A, want_err: Vec3A) {
    let tol = 4.0 * (got.1 * got.1 + want_err * want_err).powf(0.5) + want.abs() * 2e-4 + Vec3A::splat(1e-6);
    println!("{what}: got {:?} ± {:?}, want {want:?} ± {want_err:?}", got.0, got.1);
    assert!(((got.0 - want).abs() - tol).max_element() <= 0.0, "{what}: {:?} vs {want:?} (tolerance {tol:?})", got.0);
}

#[test]
fn disk_sphere_and_quad_irradiance_match_closed_forms() {
    let (r, d) = (0.7f32, 2.0f32);
    let l = Vec3A::new(2.0, 1.0, 0.5);
    let disk = format!(
        "WorldBegin\n{FLOOR}AttributeBegin\nTranslate 0 0 {d}\nReverseOrientation\n\
         AreaLightSource \"diffuse\" \"rgb L\" [2 1 0.5]\nShape \"disk\" \"float radius\" [{r}]\nAttributeEnd\nWorldEnd\n"
    );
    let loaded = load(&disk);
    let lights = build_lights(&loaded.scene);
    assert_eq!(lights.len(), 1);
    let si = floor_point(&loaded.scene, 0.0, 0.0);
    let want = PI * l * r * r / (r * r + d * d);
    assert_close(
        "disk on axis",
        irradiance_by_light_sampling(&loaded.scene, &lights, &si, 64, true),
        want,
        Vec3A::ZERO,
    );

    // A one-sided sphere of radius R at height h: E = πL (R/h)² while it is wholly above the horizon.
    let (rs, h) = (1.0f32, 3.0f32);
    let sphere = format!(
        "WorldBegin\n{FLOOR}AttributeBegin\nTranslate 0.5 0 {h}\n\
         AreaLightSource \"diffuse\" \"rgb L\" [2 1 0.5]\nShape \"sphere\" \"float radius\" [{rs}]\nAttributeEnd\nWorldEnd\n"
    );
    let loaded = load(&sphere);
    let lights = build_lights(&loaded.scene);
    let si = floor_point(&loaded.scene, 0.5, 0.0);
    let want = PI * l * (rs / h) * (rs / h);
    assert_close(
        "sphere (cone sampling)",
        irradiance_by_light_sampling(&loaded.scene, &lights, &si, 64, true),
        want,
        Vec3A::ZERO,
    );

    // A square of half side s at height c facing down, two triangle lights: four corner rectangles of the
    // configuration factor F = 1/2π [A/√(1+A²) atan(B/√(1+A²)) + B/√(1+B²) atan(A/√(1+B²))], A = B = s/c.
    let (s, c) = (0.8f32, 1.5f32);
    let quad = format!(
        "WorldBegin\n{FLOOR}AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [2 1 0.5]\n\
         Shape \"trianglemesh\" \"point P\" [-{s} -{s} {c}  {s} -{s} {c}  {s} {s} {c}  -{s} {s} {c}] \
         \"integer indices\" [0 2 1 0 3 2]\nAttributeEnd\nWorldEnd\n"
    );
    let loaded = load(&quad);
    let lights = build_lights(&loaded.scene);
    assert_eq!(lights.len(), 2, "one light per triangle");
    let si = floor_point(&loaded.scene, 0.0, 0.0);
    let a = (s / c) as f64;
    let q = (1.0 + a * a).sqrt();
    let f = 2.0 * (a / q * (a / q).atan()) / (2.0 * std::f64::consts::PI);
    let want = PI * l * 4.0 * f as f32;
    assert_close(
        "square of two triangles",
        irradiance_by_light_sampling(&loaded.scene, &lights, &si, 64, true),
        want,
        Vec3A::ZERO,
    );
}

#[test]
fn every_emitting_shape_agrees_with_cosine_sampled_rays() {
    // Shapes without a simple closed form, partial and non-uniformly scaled shapes: light sampling against
    // the independent ray estimate, both with their standard errors.
    let shapes = [
        (
            "cylinder",
            "Translate 0.3 0 2\nRotate 70 1 0 0\nShape \"cylinder\" \"float radius\" [0.5] \"float zmin\" [-0.6] \"float zmax\" [0.4] \"float phimax\" [300]",
        ),
        ("cone", "Translate 0 0.2 2.5\nRotate 180 1 0 0\nShape \"cone\" \"float radius\" [0.7] \"float height\" [0.9]"),
        (
            "paraboloid",
            "Translate 0 0 1.5\nRotate 20 1 0 0\nShape \"paraboloid\" \"float radius\" [0.8] \"float zmin\" [0.1] \"float zmax\" [0.9]",
        ),
        (
            "partial sphere",
            "Translate 0 0 2\nShape \"sphere\" \"float radius\" [0.8] \"float zmin\" [-0.5] \"float zmax\" [0.6] \"float phimax\" [250]",
        ),
        ("stretched sphere", "Translate 0.4 0 2.2\nScale 2 0.5 1\nShape \"sphere\" \"float radius\" [0.7]"),
        (
            "annulus",
            "Translate 0 0 1.5\nRotate 160 1 0 0\nShape \"disk\" \"float radius\" [0.9] \"float innerradius\" [0.3] \"float phimax\" [200]",
        ),
        (
            "sheared disk",
            "Translate 0 0 1.5\nConcatTransform [1 0 0 0  0.5 1 0 0  0 0 -1 0  0 0 0 1]\nShape \"disk\" \"float radius\" [0.8]",
        ),
    ];
    for (name, shape) in shapes {
        for two in ["false", "true"] {
            let text = format!(
                "WorldBegin\n{FLOOR}AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 2 3] \"bool twosided\" \"{two}\"\n\
                 {shape}\nAttributeEnd\nWorldEnd\n"
            );
            let loaded = load(&text);
            let lights = build_lights(&loaded.scene);
            assert_eq!(lights.len(), 1, "{name}");
            let si = floor_point(&loaded.scene, 0.1, -0.2);
            let by_rays = irradiance_by_rays(&loaded.scene, &lights, &si, 256);
            // (One-sided, some face away: the sheared disk's mirror flips it up, as in pbrt-v3.)
            assert!(two == "false" || by_rays.0.max_element() > 0.05, "{name}: the shape lights the point");
            let by_light = irradiance_by_light_sampling(&loaded.scene, &lights, &si, 64, false);
            assert_close(&format!("{name} twosided={two}"), by_light, by_rays.0, by_rays.1);
        }
    }
}

/// A 2×1 texel environment map file (left half red-ish, right half blue-ish) for the map tests.
fn write_map(dir: &common::TempDir) -> PathBuf {
    let im = Image::from_pixels(
        4,
        2,
        vec![
            [3.0, 0.5, 0.2],
            [0.2, 0.4, 2.0],
            [1.0, 1.0, 1.0],
            [0.1, 0.1, 0.1],
            [0.5, 2.0, 0.5],
            [0.3, 0.3, 0.3],
            [4.0, 4.0, 1.0],
            [0.2, 0.1, 0.0],
        ],
    )
    .unwrap();
    let p = dir.path("map.pfm");
    cachert::image::write(&im, &p).unwrap();
    p
}

#[test]
fn environment_map_pdf_integrates_to_one_and_sampling_matches_the_rays() {
    let dir = common::TempDir::new("envlight");
    let map = write_map(&dir);
    for (name, map) in [("data map (24×12)", data_dir().join("envmap.pfm")), ("small map (4×2)", map)] {
        let text = format!(
            "WorldBegin\n{FLOOR}AttributeBegin\nRotate 40 1 1 0\nLightSource \"infinite\" \"string mapname\" \"{}\" \
             \"rgb L\" [1 0.5 2]\nAttributeEnd\nWorldEnd\n",
            map.display()
        );
        let loaded = load(&text);
        assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
        let lights = build_lights(&loaded.scene);
        assert_eq!(lights.len(), 1);
        let si = floor_point(&loaded.scene, 0.0, 0.0);
        // ∫ pdf dω over the sphere (midpoint rule in θ, φ; the pdf is constant on a finer grid than this).
        let (nt, np) = (512, 1024);
        let mut int = 0.0f64;
        for j in 0..nt {
            let th = (j as f32 + 0.5) / nt as f32 * PI;
            for i in 0..np {
                let ph = (i as f32 + 0.5) / np as f32 * 2.0 * PI;
                let w = Vec3A::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
                int += (lights.pdf_li(0, &si, w) * th.sin()) as f64;
            }
        }
        int *= (PI / nt as f32 * 2.0 * PI / np as f32) as f64;
        println!("{name}: ∫ pdf dω = {int}");
        assert!((int - 1.0).abs() < 2e-3, "{name}: ∫ pdf dω = {int}");
        let by_rays = irradiance_by_rays(&loaded.scene, &lights, &si, 256);
        let by_light = irradiance_by_light_sampling(&loaded.scene, &lights, &si, 64, true);
        assert_close(name, by_light, by_rays.0, by_rays.1);
    }
}

#[test]
fn delta_lights_give_their_closed_form_irradiance() {
    let text = format!(
        "WorldBegin\n{FLOOR}\
         LightSource \"point\" \"rgb I\" [2 4 6] \"rgb scale\" [0.5 0.5 0.5] \"point from\" [1 0 2]\n\
         AttributeBegin\nTranslate 0 0 3\nLightSource \"spot\" \"rgb I\" [5 5 5] \"point from\" [0 0 0] \"point to\" [0 0 -1] \
         \"float coneangle\" [30] \"float conedeltaangle\" [10]\nAttributeEnd\n\
         LightSource \"distant\" \"rgb L\" [1 2 3] \"point from\" [0 1 1] \"point to\" [0 0 0]\nWorldEnd\n"
    );
    let loaded = load(&text);
    let lights = build_lights(&loaded.scene);
    assert_eq!(lights.len(), 3);
    assert!((0..3).all(|i| lights.is_delta(i)));
    let si = floor_point(&loaded.scene, 0.0, 0.0);
    // Point: I·scale·cos/d² with d² = 5, cos = 2/√5.
    let s = lights.sample_li(0, &si, [0.5, 0.5]).unwrap();
    let want = Vec3A::new(1.0, 2.0, 3.0) * (2.0 / 5f32.sqrt()) / 5.0;
    assert!((s.li * s.wi.dot(si.ng) - want).length() < 1e-5 && s.pdf == 1.0);
    assert!((lights.power(0) - 4.0 * PI * Vec3A::new(1.0, 2.0, 3.0)).length() < 1e-4);
    // Spot at height 3 pointing down: on axis I/9; at 25° off axis (inside the 20°–30° ramp) the quartic
    // of (cos25° − cos30°)/(cos20° − cos30°); at 35° nothing.
    let s = lights.sample_li(1, &si, [0.5, 0.5]).unwrap();
    assert!((s.li - Vec3A::splat(5.0 / 9.0)).length() < 1e-5);
    for (deg, want) in [
        (25.0f32, {
            let d = (25f32.to_radians().cos() - 30f32.to_radians().cos())
                / (20f32.to_radians().cos() - 30f32.to_radians().cos());
            d.powi(4)
        }),
        (35.0, 0.0),
    ] {
        let x = 3.0 * deg.to_radians().tan();
        let si = floor_point(&loaded.scene, x, 0.0);
        let got = lights.sample_li(1, &si, [0.5, 0.5]).map_or(Vec3A::ZERO, |s| s.li);
        let d2 = 9.0 + x * x;
        assert!((got - Vec3A::splat(5.0 * want / d2)).length() < 1e-5, "{deg}°: {got:?}");
    }
    // Distant: L·cos with cos = 1/√2, along an unbounded shadow ray.
    let s = lights.sample_li(2, &si, [0.5, 0.5]).unwrap();
    assert!((s.li * s.wi.dot(si.ng) - Vec3A::new(1.0, 2.0, 3.0) / 2f32.sqrt()).length() < 1e-5);
    assert!(s.shadow.t_max.is_infinite());
    // Delta lights have no density toward any direction.
    assert_eq!(lights.pdf_li(0, &si, s.wi), 0.0);
}

#[test]
fn light_selection_by_power_and_uniformly() {
    let loaded = load(
        "WorldBegin\nLightSource \"point\" \"rgb I\" [1 1 1]\nLightSource \"point\" \"rgb I\" [3 3 3]\nWorldEnd\n",
    );
    let l = build_lights(&loaded.scene);
    let p = LightSelect::new(&l, "power").unwrap();
    assert!((p.pmf(0) - 0.25).abs() < 1e-6 && (p.pmf(1) - 0.75).abs() < 1e-6);
    assert_eq!(p.sample(0.2).unwrap().0, 0);
    assert_eq!(p.sample(0.3).unwrap().0, 1);
    let u = LightSelect::new(&l, "uniform").unwrap();
    assert!((u.pmf(0) - 0.5).abs() < 1e-6 && u.note().is_none());
    let s = LightSelect::new(&l, "spatial").unwrap();
    assert!(s.note().is_some() && (s.pmf(1) - 0.75).abs() < 1e-6);
    assert!(LightSelect::new(&l, "bogus").is_err());
    // No lights: nothing to pick, not a panic.
    let empty = load("WorldBegin\nWorldEnd\n");
    let l = build_lights(&empty.scene);
    assert_eq!(l.len(), 0);
    assert!(LightSelect::new(&l, "power").unwrap().sample(0.5).is_none());
    assert_eq!(l.le_escaped(&Ray::new(Vec3A::ZERO, Vec3A::Z)), Spectrum::ZERO);
}

fn build_warnings(text: &str) -> (cachert::Result<usize>, Vec<String>) {
    let loaded = load(text);
    let mut w = Warnings::default();
    let r = Lights::build(&loaded.scene, &mut w).map(|l| l.len());
    (r, w.iter().map(|w| w.to_string()).collect())
}

#[test]
fn bad_light_input_is_an_error_or_a_warning_at_the_directive() {
    // Negative radiance or scale: an error naming file:line.
    let (r, _) = build_warnings(&format!(
        "WorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 -1 1]\n{FLOOR}AttributeEnd\nWorldEnd\n"
    ));
    let e = r.unwrap_err().to_string();
    assert!(e.contains("inline.pbrt:3:") && e.contains("negative"), "{e}");
    let (r, _) = build_warnings("WorldBegin\nLightSource \"point\" \"rgb scale\" [-1 1 1]\nWorldEnd\n");
    assert!(r.unwrap_err().to_string().contains("inline.pbrt:2:"));
    let (r, _) =
        build_warnings("WorldBegin\nLightSource \"spot\" \"point from\" [1 1 1] \"point to\" [1 1 1]\nWorldEnd\n");
    assert!(r.unwrap_err().to_string().contains("same point"));
    // Zero power: skipped with a warning (also a spot with a zero cone).
    let (r, w) = build_warnings(
        "WorldBegin\nLightSource \"point\" \"rgb I\" [0 0 0]\nLightSource \"spot\" \"float coneangle\" [0] \"float conedeltaangle\" [0]\nWorldEnd\n",
    );
    assert_eq!(r.unwrap(), 0);
    assert!(w.iter().any(|m| m.contains("inline.pbrt:2:") && m.contains("zero power")), "{w:?}");
    assert!(w.iter().any(|m| m.contains("inline.pbrt:3:")), "{w:?}");
    let (r, w) = build_warnings(&format!(
        "WorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [0 0 0]\n{FLOOR}AttributeEnd\nWorldEnd\n"
    ));
    assert_eq!(r.unwrap(), 0);
    assert!(w.iter().any(|m| m.contains("inline.pbrt:3:") && m.contains("emits nothing")), "{w:?}");
    // Goniometric and projection lights: refused with a warning, skipped.
    let (r, w) = build_warnings("WorldBegin\nLightSource \"goniometric\"\nLightSource \"projection\"\nWorldEnd\n");
    assert_eq!(r.unwrap(), 0);
    assert!(w.iter().any(|m| m.contains("inline.pbrt:2:") && m.contains("goniometric")), "{w:?}");
    assert!(w.iter().any(|m| m.contains("inline.pbrt:3:") && m.contains("projection")), "{w:?}");
    // A missing, empty or non-image map: a warning and pbrt-v3's constant L.
    let dir = common::TempDir::new("badmap");
    let empty = dir.write("empty.pfm", "PF\n0 0\n-1\n");
    let text = dir.write("text.exr", "this is not an EXR file");
    for map in [dir.path("missing.exr"), empty, text] {
        let (r, w) = build_warnings(&format!(
            "WorldBegin\nLightSource \"infinite\" \"string mapname\" \"{}\" \"rgb L\" [0.5 1 2]\nWorldEnd\n",
            map.display()
        ));
        assert_eq!(r.unwrap(), 1, "{}", map.display());
        assert!(w.iter().any(|m| m.contains("inline.pbrt:2:") && m.contains("constant L")), "{w:?}");
        let loaded = load(&format!(
            "WorldBegin\nLightSource \"infinite\" \"string mapname\" \"{}\" \"rgb L\" [0.5 1 2]\nWorldEnd\n",
            map.display()
        ));
        let l = build_lights(&loaded.scene);
        assert_eq!(l.le_escaped(&Ray::new(Vec3A::ZERO, Vec3A::new(0.3, -0.2, 0.9))), Vec3A::new(0.5, 1.0, 2.0));
    }
}

/// Renders a pbrt-v3 reference scene's camera the way its non-jittered 4×4 stratified sampler and box
/// filter do: the mean of `f` over the 16 film points (x + (i + ½)/4, y + (j + ½)/4) of each pixel.
fn render_like_pbrt(scene: &Scene, mut f: impl FnMut(&Ray) -> Vec3A) -> Image {
    let [w, h] = scene.film.resolution.map(|v| v as usize);
    let mut im = Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let mut sum = Vec3A::ZERO;
            for j in 0..4 {
                for i in 0..4 {
                    let p = [x as f32 + (i as f32 + 0.5) / 4.0, y as f32 + (j as f32 + 0.5) / 4.0];
                    sum += f(&scene.camera.generate_ray(p, [0.5, 0.5]));
                }
            }
            im.set(x, y, (sum / 16.0).to_array());
        }
    }
    im
}

/// Compares with a pbrt-v3 reference: returns (max |diff| / (|ref| + 0.01) over the pixels, the share of
/// pixels beyond `tol` of that measure, RMSE / mean of the reference); prints them.
fn compare(name: &str, ours: &Image, reference: &Image, tol: f32) -> (f32, f32, f64) {
    assert_eq!((ours.width, ours.height), (reference.width, reference.height));
    if let Ok(dir) = std::env::var("CACHERT_DUMP_DIR") {
        let _ = cachert::image::write(ours, &Path::new(&dir).join(format!("{name}-ours.pfm")));
    }
    let (mut worst, mut over, mut se) = (0.0f32, 0usize, 0.0f64);
    for (a, b) in ours.pixels.iter().zip(&reference.pixels) {
        let mut px = 0.0f32;
        for c in 0..3 {
            let d = (a[c] - b[c]).abs();
            se += (d as f64).powi(2);
            px = px.max(d / (b[c].abs() + 0.01));
        }
        worst = worst.max(px);
        if px > tol {
            over += 1;
        }
    }
    let n = ours.pixels.len();
    let rmse = (se / (3 * n) as f64).sqrt() / common::mean(reference);
    let share = over as f32 / n as f32;
    println!("{name}: worst pixel {worst:.2e}, {over} of {n} pixels beyond {tol}, RMSE/mean {rmse:.2e}");
    (worst, share, rmse)
}

fn reference(name: &str) -> (LoadedScene, Image) {
    let dir = data_dir();
    let loaded = cachert::scene::load(&dir.join(format!("{name}.pbrt")), LoadOptions::default()).unwrap();
    let im = cachert::image::read(&dir.join(format!("{name}-ref.pfm"))).unwrap();
    (loaded, im)
}

#[test]
fn environment_map_seen_directly_matches_pbrt_v3() {
    let (loaded, pbrt) = reference("envmap");
    let lights = build_lights(&loaded.scene);
    let ours = render_like_pbrt(&loaded.scene, |ray| lights.le_escaped(ray));
    let (worst, _, rmse) = compare("envmap", &ours, &pbrt, 1e-3);
    assert!(worst < 2e-3 && rmse < 2e-4, "orientation, resampling or scale differ from pbrt-v3");
}

#[test]
fn emitters_seen_directly_match_pbrt_v3() {
    let (loaded, pbrt) = reference("emitters");
    let scene = &loaded.scene;
    let lights = build_lights(scene);
    let ours = render_like_pbrt(scene, |ray| {
        scene.geometry.intersect(ray).map_or(Vec3A::ZERO, |hit| lights.emitted(&hit, -ray.d))
    });
    let (_, share, rmse) = compare("emitters", &ours, &pbrt, 1e-3);
    // Silhouette pixels may differ where a film point grazes an edge; nothing else may.
    assert!(share < 0.01 && rmse < 0.02, "emission sides differ from pbrt-v3");
}

#[test]
fn point_spot_and_distant_lights_on_a_floor_match_pbrt_v3() {
    let (loaded, pbrt) = reference("delta");
    let scene = &loaded.scene;
    let lights = build_lights(scene);
    assert_eq!(lights.len(), 3);
    let kd = 0.5 / PI;
    let ours = render_like_pbrt(scene, |ray| {
        let Some(si) = scene.geometry.intersect(ray) else { return Vec3A::ZERO };
        let wo = -ray.d;
        let mut sum = Vec3A::ZERO;
        for l in 0..lights.len() {
            let Some(s) = lights.sample_li(l, &si, [0.5, 0.5]) else { continue };
            // pbrt-v3's BSDF::f reflects only when wi and wo are on the same side of the geometric normal.
            if s.wi.dot(si.ng) * wo.dot(si.ng) <= 0.0 || scene.geometry.occluded_from(&s.shadow, si.origin) {
                continue;
            }
            sum += s.li * kd * s.wi.dot(si.ns).abs() / s.pdf;
        }
        sum
    });
    let (_, share, rmse) = compare("delta", &ours, &pbrt, 2e-3);
    assert!(share < 0.01 && rmse < 0.01, "delta-light irradiance differs from pbrt-v3");
}

/// The shared scenes must be here: fails, with the reason, where they are absent (outside CI the tests that
/// need them print a `skipped` line and pass; under CI they fail too).
#[test]
fn shared_scenes_present() {
    common::assert_shared_scenes_present();
}

#[test]
fn the_shared_scenes_lights_build() {
    let Some(dir) = common::shared_scenes() else { return };
    let mut files: Vec<PathBuf> = [
        "bitterli-cornell-box-v3/scene.pbrt",
        "bitterli-bathroom/scene-v3.pbrt",
        "bitterli-staircase2/scene-v3.pbrt",
        "pbrtv3scenes-veach-mis/mis.pbrt",
        "pbrtv3scenes-buddha-fractal/buddha-fractal.pbrt",
    ]
    .iter()
    .filter_map(|f| common::shared_file(&dir, f))
    .collect();
    if let Some(lights) = common::shared_file(&dir, "hackmad-pbrt-v3-rs-tests/lights") {
        let mut extra: Vec<PathBuf> = std::fs::read_dir(&lights)
            .unwrap_or_else(|e| panic!("{}: {e}", lights.display()))
            .map(|e| e.expect("a readable folder entry").path())
            .filter(|p| p.extension().is_some_and(|e| e == "pbrt"))
            .collect();
        extra.sort();
        assert!(!extra.is_empty(), "no .pbrt file in {}", lights.display());
        files.extend(extra);
    }
    for f in files {
        // Every one of these loads today; one that stops loading (its assets gone from the shared copy, or a
        // loader regression) is a failure under CI and a printed skip elsewhere.
        let loaded = match cachert::scene::load(&f, LoadOptions::default()) {
            Ok(l) => l,
            Err(e) => {
                common::unavailable(&format!("{} does not load: {e}", f.display()));
                continue;
            }
        };
        let mut w = Warnings::default();
        let l = Lights::build(&loaded.scene, &mut w).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        println!("{}: {:?}", f.display(), l.type_counts());
        for m in w.iter() {
            println!("  {m}");
        }
        let name = f.file_name().unwrap().to_string_lossy();
        if name.contains("goniometric") || name.contains("projection") {
            // Refused, with a warning at the LightSource.
            assert!(l.is_empty() && w.iter().any(|m| m.msg.contains("not supported")), "{}", f.display());
            continue;
        }
        assert!(!l.is_empty(), "{}: no lights", f.display());
        let sel = LightSelect::new(&l, "power").unwrap();
        let total: f32 = (0..l.len()).map(|i| sel.pmf(i)).sum();
        assert!((total - 1.0).abs() < 1e-3, "{}: pmf sums to {total}", f.display());
    }
}

#[test]
fn area_lights_on_a_matte_scene_match_pbrt_v3_within_noise() {
    // pbrt-v3 directlighting (MIS of light and BSDF samples) against light sampling only: the same
    // expectation by different estimators, so this checks L, scale, sides, shapes' pdfs and shadow rays.
    let dir = data_dir();
    let loaded = cachert::scene::load(&dir.join("area.pbrt"), LoadOptions::default()).unwrap();
    let scene = &loaded.scene;
    let lights = build_lights(scene);
    assert_eq!(lights.len(), 5);
    let disk = (0..lights.len()).find(|&l| lights.samples(l) == 4).expect("the disk's nsamples");
    assert!((lights.power(disk) - Vec3A::new(3.0, 2.0, 1.0) * PI * PI * 0.25).length() < 1e-3);
    let kd = 0.5 / PI;
    let [w, h] = scene.film.resolution.map(|v| v as usize);
    let mut ours = Image::new(w, h);
    let mut rng = Rng::new(5);
    let (g, k) = (8usize, 2usize);
    for y in 0..h {
        for x in 0..w {
            let mut sum = Vec3A::ZERO;
            for j in 0..g {
                for i in 0..g {
                    // Jittered film points: a fixed grid would bias the pixels that an emitter's edge crosses.
                    let [ja, jb] = rng.uniform2();
                    let p = [x as f32 + (i as f32 + ja) / g as f32, y as f32 + (j as f32 + jb) / g as f32];
                    let ray = scene.camera.generate_ray(p, [0.5, 0.5]);
                    let Some(si) = scene.geometry.intersect(&ray) else { continue };
                    let wo = -ray.d;
                    sum += lights.emitted(&si, wo);
                    for l in 0..lights.len() {
                        for s in 0..k * k {
                            let [a, b] = rng.uniform2();
                            let u = [((s % k) as f32 + a) / k as f32, ((s / k) as f32 + b) / k as f32];
                            let Some(ls) = lights.sample_li(l, &si, u) else { continue };
                            if ls.wi.dot(si.ng) * wo.dot(si.ng) <= 0.0
                                || scene.geometry.occluded_from(&ls.shadow, si.origin)
                            {
                                continue;
                            }
                            sum += ls.li * kd * ls.wi.dot(si.ns).abs() / ls.pdf / (k * k) as f32;
                        }
                    }
                }
            }
            ours.set(x, y, (sum / (g * g) as f32).to_array());
        }
    }
    assert!(ours.first_non_finite().is_none());
    common::assert_matches_pbrt_pair("area", &ours, &dir.join("area-a.pfm"), &dir.join("area-b.pfm"));
}

#[test]
fn light_paths_carry_each_lights_emitted_flux() {
    // pbrt-v3's Sample_Le: the throughput of a light path's first ray, averaged over its samples, is the
    // light's emitted flux. Exact values (not pbrt-v3's `Power()`, which approximates the spot's and the
    // environment's): a one-sided quad πAL, two-sided 2πAL, a sphere π·4πr²·L, a point light 4πI, a spot
    // with a hard edge 2π(1 − cos θ)·I, a distant light L·πR² and a constant environment 4πL·πR² through
    // the world's bounding disk (R: its radius; the floor makes it √200 here).
    let quad =
        "Shape \"trianglemesh\" \"point P\" [-1 -1 3  1 -1 3  1 1 3  -1 1 3] \"integer indices\" [0 2 1 0 3 2]\n";
    let world_r = (20.0f32 * 20.0 + 20.0 * 20.0).sqrt() / 2.0;
    let cases: Vec<(&str, String, f32)> = vec![
        ("one-sided quad", format!("AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [2 2 2]\n{quad}AttributeEnd\n"), PI * 4.0 * 2.0),
        (
            "two-sided quad",
            format!("AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [2 2 2] \"bool twosided\" true\n{quad}AttributeEnd\n"),
            2.0 * PI * 4.0 * 2.0,
        ),
        (
            "sphere",
            "AttributeBegin\nTranslate 0 0 3\nAreaLightSource \"diffuse\" \"rgb L\" [2 2 2]\nShape \"sphere\" \"float radius\" 0.5\nAttributeEnd\n".into(),
            PI * 4.0 * PI * 0.25 * 2.0,
        ),
        ("point", "LightSource \"point\" \"point from\" [0 0 3] \"rgb I\" [3 3 3]\n".into(), 4.0 * PI * 3.0),
        (
            "spot",
            "LightSource \"spot\" \"point from\" [0 0 3] \"point to\" [0 0 0] \"float coneangle\" 40 \"float conedeltaangle\" 0 \"rgb I\" [3 3 3]\n".into(),
            2.0 * PI * (1.0 - 40f32.to_radians().cos()) * 3.0,
        ),
        ("distant", "LightSource \"distant\" \"point from\" [1 1 3] \"point to\" [0 0 0] \"rgb L\" [2 2 2]\n".into(), 2.0 * PI * world_r * world_r),
        ("infinite", "LightSource \"infinite\" \"rgb L\" [0.5 0.5 0.5]\n".into(), 4.0 * PI * 0.5 * PI * world_r * world_r),
    ];
    for (name, light, flux) in cases {
        let text = format!(
            "LookAt 0 0 10 0 0 0 0 1 0\nCamera \"perspective\"\nWorldBegin\n{light}Material \"matte\"\n{FLOOR}WorldEnd\n"
        );
        let loaded = load(&text);
        let lights = build_lights(&loaded.scene);
        assert_eq!(lights.len(), if name.ends_with("quad") { 2 } else { 1 }, "{name}");
        let mut rng = Rng::new(21);
        let n = 200_000;
        let mut sum = 0.0f64;
        for i in 0..n {
            let light = i % lights.len();
            if let Some(s) = lights.sample_le(light, rng.uniform2(), rng.uniform2()) {
                assert!(s.beta.is_finite() && s.ray.d.is_finite(), "{name}");
                sum += s.beta.to_array()[0] as f64 * lights.len() as f64;
            }
        }
        let mean = sum / n as f64;
        eprintln!("{name}: mean throughput {mean:.4}, flux {flux:.4}");
        assert!((mean / flux as f64 - 1.0).abs() < 0.01, "{name}: {mean} vs {flux}");
    }
}

/// `Lights::behind` lets `EstimateDirect` skip lights wholly behind a reflecting surface: it must never
/// call a light behind when a sample of it lies on the plane's front side, and must say so for lights that
/// are plainly behind (a triangle, a disk, a sphere and a point light under a floor, seen from above and
/// from tilted planes).
#[test]
fn lights_called_behind_a_plane_have_every_sample_behind_it() {
    let text = format!(
        "WorldBegin\n{FLOOR}\
         AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n\
         Shape \"trianglemesh\" \"point P\" [-1 -1 -2  1 -1 -2  0 1 -3] \"integer indices\" [0 1 2]\nAttributeEnd\n\
         AttributeBegin\nTranslate 3 0 -1\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" \"true\"\n\
         Shape \"disk\" \"float radius\" [0.5]\nAttributeEnd\n\
         AttributeBegin\nTranslate -3 2 -2\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n\
         Shape \"sphere\" \"float radius\" [0.5]\nAttributeEnd\n\
         LightSource \"point\" \"point from\" [0 -3 -0.5] \"rgb I\" [1 1 1]\n\
         LightSource \"distant\" \"point from\" [0 0 -1] \"point to\" [0 0 0]\nWorldEnd\n"
    );
    let loaded = load(&text);
    let lights = build_lights(&loaded.scene);
    assert_eq!(lights.len(), 5);
    let mut rng = Rng::new(7);
    let (mut behind, mut front) = (0, 0);
    for k in 0..200 {
        let [x, y] = rng.uniform2();
        let si = floor_point(&loaded.scene, 8.0 * x - 4.0, 8.0 * y - 4.0);
        // The floor's own normal, its opposite, and tilted planes through the same point.
        let tilt = Vec3A::new(rng.uniform() - 0.5, rng.uniform() - 0.5, 0.0) * (k % 4) as f32;
        for n in [Vec3A::Z, -Vec3A::Z, (Vec3A::Z + tilt).normalize(), (-Vec3A::Z + tilt).normalize()] {
            for j in 0..lights.len() {
                if !lights.behind(j, si.p, n) {
                    continue;
                }
                behind += 1;
                for _ in 0..64 {
                    if let Some(ls) = lights.sample_li(j, &si, rng.uniform2()) {
                        front += usize::from(ls.wi.dot(n) >= 0.0);
                    }
                }
            }
        }
    }
    assert_eq!(front, 0, "a light called behind had samples in front");
    // Every area light and the point light are below the floor: behind for n = +z at every point.
    assert!(behind >= 200 * 4, "behind only {behind} times");
    let si = floor_point(&loaded.scene, 0.0, 0.0);
    let count = |n: Vec3A| (0..lights.len()).filter(|&j| lights.behind(j, si.p, n)).count();
    // Four lights under the floor (the distant light never is behind); none of them behind the other side.
    assert_eq!((count(Vec3A::Z), count(-Vec3A::Z)), (4, 0));
}
