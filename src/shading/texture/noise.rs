//! STAGE 5 (shading): Perlin's gradient noise as pbrt-v3 computes it (`Noise`), for the `dots` texture.
//!
//! The permutation is Ken Perlin's reference table (the one pbrt-v3 uses), so dot placement matches
//! pbrt-v3's. Depends on nothing; never allocates.

/// Ken Perlin's permutation of 0..=255.
const PERM: [u8; 256] = [
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69, 142, 8, 99, 37, 240,
    21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219, 203, 117, 35, 11, 32, 57, 177, 33, 88,
    237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175, 74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83,
    111, 229, 122, 60, 211, 133, 230, 220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161, 1, 216,
    80, 73, 209, 76, 132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100, 109, 198, 173, 186,
    3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206, 59, 227, 47, 16, 58, 17,
    182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163, 70, 221, 153, 101, 155, 167, 43, 172, 9, 129,
    22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232, 178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238,
    210, 144, 12, 191, 179, 162, 241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31, 181, 199, 106, 157, 184,
    84, 204, 176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141, 128, 195,
    78, 66, 215, 61, 156, 180,
];

#[inline]
fn perm(i: i32) -> i32 {
    i32::from(PERM[(i & 255) as usize])
}

/// Dot product of the pseudo-random gradient at lattice point (x, y, z) with the offset (dx, dy, dz).
#[inline]
fn grad(x: i32, y: i32, z: i32, dx: f32, dy: f32, dz: f32) -> f32 {
    let h = perm(perm(perm(x) + y) + z) & 15;
    let u = if h < 8 || h == 12 || h == 13 { dx } else { dy };
    let v = if h < 4 || h == 12 || h == 13 { dy } else { dz };
    (if h & 1 != 0 { -u } else { u }) + (if h & 2 != 0 { -v } else { v })
}

/// The quintic fade 6t⁵ − 15t⁴ + 10t³.
#[inline]
fn fade(t: f32) -> f32 {
    let t3 = t * t * t;
    let t4 = t3 * t;
    6.0 * t4 * t - 15.0 * t4 + 10.0 * t3
}

#[inline]
fn lerp(t: f32, a: f32, b: f32) -> f32 {
    (1.0 - t) * a + t * b
}

/// pbrt-v3's `Noise(x, y, z)`: gradient noise in about [−1, 1], 0 at every lattice point.
pub fn noise(x: f32, y: f32, z: f32) -> f32 {
    let (fx, fy, fz) = (x.floor(), y.floor(), z.floor());
    let (dx, dy, dz) = (x - fx, y - fy, z - fz);
    // Lattice coordinates modulo 256 (a float beyond the i32 range saturates; any value is fine there).
    let (ix, iy, iz) = ((fx as i64 & 255) as i32, (fy as i64 & 255) as i32, (fz as i64 & 255) as i32);
    let w000 = grad(ix, iy, iz, dx, dy, dz);
    let w100 = grad(ix + 1, iy, iz, dx - 1.0, dy, dz);
    let w010 = grad(ix, iy + 1, iz, dx, dy - 1.0, dz);
    let w110 = grad(ix + 1, iy + 1, iz, dx - 1.0, dy - 1.0, dz);
    let w001 = grad(ix, iy, iz + 1, dx, dy, dz - 1.0);
    let w101 = grad(ix + 1, iy, iz + 1, dx - 1.0, dy, dz - 1.0);
    let w011 = grad(ix, iy + 1, iz + 1, dx, dy - 1.0, dz - 1.0);
    let w111 = grad(ix + 1, iy + 1, iz + 1, dx - 1.0, dy - 1.0, dz - 1.0);
    let (wx, wy, wz) = (fade(dx), fade(dy), fade(dz));
    let x00 = lerp(wx, w000, w100);
    let x10 = lerp(wx, w010, w110);
    let x01 = lerp(wx, w001, w101);
    let x11 = lerp(wx, w011, w111);
    let y0 = lerp(wy, x00, x10);
    let y1 = lerp(wy, x01, x11);
    let n = lerp(wz, y0, y1);
    if n.is_finite() { n } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_is_a_permutation() {
        let mut seen = [false; 256];
        PERM.iter().for_each(|&p| seen[p as usize] = true);
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn noise_is_zero_on_the_lattice_and_bounded() {
        assert_eq!(noise(3.0, -7.0, 0.0), 0.0);
        let mut max = 0.0f32;
        for i in 0..2000 {
            let f = i as f32;
            let n = noise(f * 0.137 - 50.0, f * 0.071 + 0.5, 0.5);
            max = max.max(n.abs());
        }
        assert!(max > 0.2 && max <= 1.5, "{max}");
        assert!(noise(f32::NAN, 1e30, f32::INFINITY).is_finite());
    }

    #[test]
    fn noise_matches_a_hand_evaluation() {
        // At (0.5, 0.5, 0.5) every corner's fade weight is ½: the mean of the eight gradient dot products.
        let mut sum = 0.0;
        for (cx, cy, cz) in [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1), (1, 1, 1)] {
            sum += grad(cx, cy, cz, 0.5 - cx as f32, 0.5 - cy as f32, 0.5 - cz as f32);
        }
        assert!((noise(0.5, 0.5, 0.5) - sum / 8.0).abs() < 1e-6);
    }
}
