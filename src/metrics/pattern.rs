//! A synthetic HDR test image for the metrics' tests and benchmarks: smooth gradients, bright spots and
//! seeded noise, the same for the same arguments on every machine.
//!
//! Depends on `image` only.

use crate::image::Image;

/// A deterministic pseudo-random value in [0, 1) from two integers.
fn hash01(a: u64, b: u64) -> f32 {
    let mut h = a.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ b.wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
    h ^= h >> 31;
    h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h ^= h >> 29;
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// A `width`×`height` pattern: gradients from 0.05 to 0.65, spots of +6 on a grid, and per-channel noise of
/// amplitude `noise` keyed by `seed` (0 gives the clean pattern whatever the seed).
pub fn pattern(width: usize, height: usize, seed: u64, noise: f32) -> Image {
    let mut im = Image::new(width, height);
    for y in 0..height {
        for x in 0..width {
            let (u, v) = (x as f32 / width as f32, y as f32 / height as f32);
            let base = 0.05 + 0.6 * u * v + if (x / 37 + y / 23) % 7 == 0 { 6.0 } else { 0.0 };
            let i = (y * width + x) as u64;
            let n = |c: u64| noise * (hash01(seed * 3 + c, i) - 0.5);
            im.set(x, y, [(base + n(0)).max(0.0), (0.8 * base + n(1)).max(0.0), (0.5 * base * u + n(2)).max(0.0)]);
        }
    }
    im
}
