//! Known answers for pbrt-v3's `ambientocclusion` integrator: scenes whose AO has a closed form.
//!
//! (a) An unoccluded plane: every cosine-weighted AO ray returns cos θ / pdf = cos θ / (cos θ / π) = π, so
//!     every pixel is π up to rounding, whatever the sample count. With uniform hemisphere sampling a ray
//!     returns 2π cos θ, random, with mean π.
//! (b) A sphere above a plane, seen from straight above by an orthographic camera, checked pixel by pixel
//!     against the closed form (derivation at [`expected_pixel`]).
//! (c) `maxdistance` shorter than every gap between surfaces: nothing occludes, π everywhere.

mod common;

use std::f64::consts::PI;

use cachert::image::Image;
use common::{header, render_text, settings};

#[test]
fn unoccluded_plane_is_pi_everywhere() {
    // A perspective camera looking down at a plane far larger than its view: every pixel sees the plane,
    // nothing is above it.
    let text = format!(
        "LookAt 0 0 5  0.3 0.2 0  0 1 0\nCamera \"perspective\" \"float fov\" [60]\n{}\
         WorldBegin\n\
         Shape \"trianglemesh\" \"point P\" [-1e3 -1e3 0  1e3 -1e3 0  1e3 1e3 0  -1e3 1e3 0] \"integer indices\" [0 1 2 0 2 3]\n\
         WorldEnd\n",
        header(24, 2, 16)
    );
    let (out, _) = render_text(&text, "plane.pbrt", &settings(5));
    let worst = out.image.pixels.iter().flatten().map(|&v| (f64::from(v) - PI).abs()).fold(0.0, f64::max);
    assert!(worst <= 1e-5, "a pixel is {worst} away from π");
}

#[test]
fn unoccluded_plane_with_uniform_sampling_averages_pi() {
    let (res, spp, n) = (24u32, 2u32, 16u32);
    let text = format!(
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"orthographic\"\n{}\
         WorldBegin\n\
         Shape \"trianglemesh\" \"point P\" [-1e3 -1e3 0  1e3 -1e3 0  1e3 1e3 0  -1e3 1e3 0] \"integer indices\" [0 1 2 0 2 3]\n\
         WorldEnd\n",
        header(res, spp, n).replace("[16]", "[16] \"bool cossample\" \"false\"")
    );
    let (out, loaded) = render_text(&text, "plane-uniform.pbrt", &settings(5));
    assert_eq!(loaded.integrator.as_ref().map(|i| i.params.bool_or("cossample", true).ok()), Some(Some(false)));
    // Each ray returns 2π·cos θ with cos θ uniform on [0, 1] under uniform hemisphere sampling: mean π,
    // variance 4π²/12 = π²/3. The image mean averages N = res²·spp·n independent rays.
    let rays = f64::from(res * res * spp * n);
    let sigma = PI / (3.0 * rays).sqrt();
    let mean = common::mean(&out.image);
    assert!((mean - PI).abs() <= 4.0 * sigma, "mean {mean} is {:.1} σ from π", (mean - PI) / sigma);
    // And single pixels really are noisy (the estimator is not the cosine one).
    assert!(out.image.pixels.iter().any(|p| (f64::from(p[0]) - PI).abs() > 0.05));
}

/// Sphere radius, height of its centre above the plane z = 0, half-width of the orthographic view.
const R: f64 = 1.0;
const H: f64 = 1.5;
const HALF: f64 = 3.0;
const RES: usize = 64;
const SPP: u32 = 4;
const NSAMPLES: u32 = 128;

fn sphere_over_plane(extra: &str) -> String {
    format!(
        "LookAt 0 0 10  0 0 0  0 1 0\n\
         Camera \"orthographic\" \"float screenwindow\" [-{HALF} {HALF} -{HALF} {HALF}]\n\
         {}\
         WorldBegin\n\
         Shape \"trianglemesh\" \"point P\" [-100 -100 0  100 -100 0  100 100 0  -100 100 0] \"integer indices\" [0 1 2 0 2 3]\n\
         Translate 0 0 {H}\n\
         Shape \"sphere\" \"float radius\" [{R}]\n\
         WorldEnd\n",
        header(RES as u32, SPP, NSAMPLES).replace(&format!("[{NSAMPLES}]"), &format!("[{NSAMPLES}]{extra}"))
    )
}

/// Fraction of cosine-weighted directions from a plane point at distance `rho` from the foot of the sphere
/// centre that hit the sphere: p = (r/d)² · cos θ = r² h / d³ (see [`expected_pixel`]).
fn occluded_fraction(rho: f64) -> f64 {
    let d2 = rho * rho + H * H;
    R * R * H / (d2 * d2.sqrt())
}

/// Expected value and standard deviation of pixel (i, j) of the rendered sphere-over-plane image.
///
/// **Closed form.** At a plane point with normal n = +z, let d be the distance to the sphere centre c and θ the
/// angle between n and c − p. The sphere subtends a cone of half-angle β with sin β = r/d. pbrt-v3's AO
/// draws directions with pdf cos θ'/π and scores cos θ'/pdf = π for each unoccluded ray, so its expected value
/// is π (1 − P) with P = (1/π) ∫_cone cos θ' dω, the cone's projected solid angle over π. For a cone wholly
/// above the horizon that integral is π sin²β cos θ (the projected area of a disk seen at angle θ: Nusselt's
/// analogue), so P = (r/d)² cos θ and AO = π (1 − (r/d)² cos θ). Here the sphere lies in z > h − r > 0, so it is
/// above every plane point's horizon and the form holds over the whole plane; with d² = ρ² + h² and
/// cos θ = h/d, P(ρ) = r² h / d³.
///
/// **Pixel mean.** The random sampler puts camera samples uniformly in the pixel and the box filter (radius ½)
/// gives each sample to its own pixel with weight 1, so the expected pixel value is the average of
/// π (1 − P) over the pixel's square on the plane (orthographic: screen (x, y) is the plane point up to the
/// signs of x and y, which P does not see). The average is taken with an 8×8 midpoint rule.
///
/// **Noise.** Each AO ray is a Bernoulli trial scoring π with probability 1 − P(x) at the sample position x. One
/// camera sample averages n rays: conditional mean π(1 − P(x)), conditional variance π² P(1 − P)/n. Over
/// the pixel, by the law of total variance, one camera sample has variance π² (Var_x P + E_x[P(1 − P)]/n),
/// and the pixel averages `spp` independent camera samples: σ² = π² (Var_x P + E_x[P(1 − P)]/n) / spp.
/// The per-pixel check is |value − mean| ≤ 6σ (+ rounding): with N = spp·n = 512 rays and P ≥ 0.04 in the
/// checked region (N·P ≥ 20) the binomial tail beyond 6σ is about 1e-6 per pixel, so over ~2,500 pixels
/// a correct renderer fails with probability well under 1 %; the seed is fixed, so the outcome is too. A wrong
/// camera mapping, normal or ray offset moves many pixels by far more than that; the aggregate checks below
/// (mean z-score and RMS z-score ≈ 1) catch small biases the per-pixel band would let through.
fn expected_pixel(i: usize, j: usize) -> (f64, f64) {
    const Q: usize = 8;
    let px = 2.0 * HALF / RES as f64;
    let (mut sum_p, mut sum_p2, mut sum_bern) = (0.0, 0.0, 0.0);
    for a in 0..Q {
        for b in 0..Q {
            let x = -HALF + (i as f64 + (a as f64 + 0.5) / Q as f64) * px;
            let y = HALF - (j as f64 + (b as f64 + 0.5) / Q as f64) * px;
            let p = occluded_fraction((x * x + y * y).sqrt());
            sum_p += p;
            sum_p2 += p * p;
            sum_bern += p * (1.0 - p);
        }
    }
    let q2 = (Q * Q) as f64;
    let (mean_p, var_p) = (sum_p / q2, (sum_p2 / q2 - (sum_p / q2).powi(2)).max(0.0));
    let var = PI * PI * (var_p + sum_bern / q2 / f64::from(NSAMPLES)) / f64::from(SPP);
    (PI * (1.0 - mean_p), var.sqrt())
}

/// Pixel (i, j)'s centre distance from the axis through the sphere centre, on the plane.
fn rho(i: usize, j: usize) -> f64 {
    let px = 2.0 * HALF / RES as f64;
    let x = -HALF + (i as f64 + 0.5) * px;
    let y = HALF - (j as f64 + 0.5) * px;
    (x * x + y * y).sqrt()
}

fn value(im: &Image, i: usize, j: usize) -> f64 {
    let p = im.get(i, j);
    assert!(p[0] == p[1] && p[1] == p[2], "AO is grey");
    f64::from(p[0])
}

#[test]
fn sphere_over_plane_matches_the_closed_form() {
    let (out, _) = render_text(&sphere_over_plane(""), "sphere-over-plane.pbrt", &settings(2024));
    let im = &out.image;
    assert_eq!((im.width, im.height), (RES, RES));
    let diag = 2.0 * HALF / RES as f64 * std::f64::consts::SQRT_2;
    let (mut n, mut sum_z2, mut sum_d, mut sum_var, mut worst) = (0usize, 0.0, 0.0, 0.0, 0.0f64);
    for j in 0..RES {
        for i in 0..RES {
            let r = rho(i, j);
            // Away from the sphere's outline (camera rays there may hit the sphere) and inside ρ ≤ 3.
            if r < R + diag || r > HALF {
                continue;
            }
            let (mean, sigma) = expected_pixel(i, j);
            let v = value(im, i, j);
            let z = (v - mean) / sigma;
            assert!(
                (v - mean).abs() <= 6.0 * sigma + 1e-5,
                "pixel ({i}, {j}) at ρ = {r:.3}: {v:.5}, expected {mean:.5} ± {sigma:.5} (z = {z:.2})"
            );
            n += 1;
            sum_z2 += z * z;
            sum_d += v - mean;
            sum_var += sigma * sigma;
            worst = worst.max(z.abs());
        }
    }
    let rms_z = (sum_z2 / n as f64).sqrt();
    let mean_z = sum_d / sum_var.sqrt();
    eprintln!("{n} pixels: RMS z {rms_z:.3}, z of the summed difference {mean_z:.2}, max |z| {worst:.2}");
    assert!(n > 2000, "only {n} pixels checked");
    // Σ z² over n pixels has mean n and sd √(2n): RMS z within 1 ± 0.1 is a > 5σ band for n ≈ 2,500.
    assert!((0.9..=1.1).contains(&rms_z), "RMS z-score {rms_z}: the noise is not what the model says");
    assert!(mean_z.abs() <= 4.0, "the image is biased: summed difference is {mean_z:.2} σ");
    // Pixels that see the sphere's top are there too (the camera looks straight down at it).
    let centre = value(im, RES / 2, RES / 2);
    assert!(centre > 2.5, "the top of the sphere is almost unoccluded, got {centre}");
}

#[test]
fn maxdistance_shorter_than_the_gap_gives_pi() {
    // The gap between the plane and the sphere is h − r = 0.5; rays of length 0.4 reach nothing.
    let (out, _) = render_text(&sphere_over_plane(" \"float maxdistance\" [0.4]"), "bounded.pbrt", &settings(9));
    let worst = out.image.pixels.iter().flatten().map(|&v| (f64::from(v) - PI).abs()).fold(0.0, f64::max);
    assert!(worst <= 1e-5, "a pixel is {worst} away from π");
    // Longer rays do reach the sphere from the plane next to it: at ρ ≈ 1.17 the sphere is 0.9 away and
    // unbounded AO is π(1 − 0.22) ≈ 2.45; rays of length 2 see most of that occlusion.
    let (out, _) = render_text(&sphere_over_plane(" \"float maxdistance\" [2]"), "bounded.pbrt", &settings(9));
    let near = value(&out.image, RES / 2 + 12, RES / 2);
    assert!(near < 0.9 * PI, "ρ ≈ 1.17 with rays of length 2 should be occluded often, got {near}");
}
