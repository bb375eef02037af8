//! STAGE 5 (shading): the procedural patterns' choice between two inputs — pbrt-v3's 2-D and 3-D
//! checkerboards and its polka dots.
//!
//! The 2-D checkerboard is point-sampled. pbrt-v3's default `aamode "closedform"` box-filters the checks
//! over the ray's footprint, which needs ray differentials cachert does not trace; with a zero footprint
//! pbrt-v3's closed form is itself a point sample, and at pbrt-v3's own footprint (⅛ pixel at 64 or more
//! samples per pixel) the two differ only in a sliver along check edges, well inside Monte Carlo noise.
//!
//! Depends only on [`super::noise`].

use super::noise::noise;

/// Whether (s, t) falls in a `tex1` check (pbrt-v3: ⌊s⌋ + ⌊t⌋ even) of the 2-D checkerboard.
#[inline]
pub fn checker_2d_first(st: [f32; 2]) -> bool {
    (st[0].floor() as i64).wrapping_add(st[1].floor() as i64).rem_euclid(2) == 0
}

/// Whether texture-space point `p` falls in a `tex1` cell (⌊x⌋ + ⌊y⌋ + ⌊z⌋ even) of the 3-D checkerboard.
#[inline]
pub fn checker_3d_first(p: [f32; 3]) -> bool {
    let cells = p.map(|x| x.floor() as i64);
    cells[0].wrapping_add(cells[1]).wrapping_add(cells[2]).rem_euclid(2) == 0
}

/// pbrt-v3's `DotsTexture` test: whether (s, t) is inside the dot of its cell. Cells are centred on
/// integer (s, t); a cell has a dot where the noise at its centre is positive, of radius 0.35 and shifted
/// by up to 0.15 by two more noise values.
#[inline]
pub fn in_dot(st: [f32; 2]) -> bool {
    let s_cell = (st[0] + 0.5).floor();
    let t_cell = (st[1] + 0.5).floor();
    if noise(s_cell + 0.5, t_cell + 0.5, 0.5) > 0.0 {
        const RADIUS: f32 = 0.35;
        const MAX_SHIFT: f32 = 0.5 - RADIUS;
        let s_center = s_cell + MAX_SHIFT * noise(s_cell + 1.5, t_cell + 2.8, 0.5);
        let t_center = t_cell + MAX_SHIFT * noise(s_cell + 4.5, t_cell + 9.8, 0.5);
        let (ds, dt) = (st[0] - s_center, st[1] - t_center);
        return ds * ds + dt * dt < RADIUS * RADIUS;
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checks_alternate_in_2d_and_3d() {
        assert!(checker_2d_first([0.5, 0.5]));
        assert!(!checker_2d_first([1.5, 0.5]));
        assert!(!checker_2d_first([-0.5, 0.5]));
        assert!(checker_2d_first([-0.5, -0.5]));
        assert!(checker_2d_first([2.0, 0.0]));
        assert!(!checker_2d_first([2.0, -1e-3]));
        assert!(checker_3d_first([0.5, 0.5, 0.5]));
        assert!(!checker_3d_first([0.5, 0.5, -0.5]));
        assert!(checker_3d_first([-0.5, 1.5, 0.5]));
        // Far away and non-finite coordinates give an answer, not a panic.
        let _ = checker_2d_first([1e30, f32::NAN]);
        let _ = checker_3d_first([f32::INFINITY, -1e38, 3.0]);
    }

    #[test]
    fn dots_cover_a_plausible_fraction() {
        // Half the cells have a dot (noise sign) of area π·0.35² ≈ 0.385: about 19 % of the plane.
        let n = 400;
        let mut inside = 0;
        for i in 0..n {
            for j in 0..n {
                inside += in_dot([i as f32 * 0.05 + 0.01, j as f32 * 0.05 + 0.02]) as u32;
            }
        }
        let f = f64::from(inside) / f64::from(n * n);
        assert!((0.08..0.32).contains(&f), "{f}");
        // Non-finite coordinates give an answer, not a panic.
        let _ = in_dot([f32::NAN, f32::INFINITY]);
    }
}
