//! STAGE 5 (shading): pbrt-v3's `"spatial"` light sample distribution (core/lightdistrib.cpp), the default of
//! its `path` integrator: the scene bounds are cut into a voxel grid (64 voxels along the longest side), and
//! each voxel gets, the first time a path asks for it, a distribution over the lights proportional to the
//! luminance each light delivers to 128 points of the voxel (Halton points, one light sample each, no
//! visibility), with a floor of 0.1 % of the average so that no light has probability 0.
//!
//! The points and light samples are fixed (radical inverses), so a voxel's distribution does not depend on
//! which thread builds it first: images stay identical for any thread count. Depends only on
//! [`super::Lights`] and [`super::distribution`].

use std::sync::OnceLock;

use glam::Vec3A;

use crate::scene::accel::{PrimOrigin, PrimRef};
use crate::scene::geometry::SurfaceInteraction;

use super::Lights;
use super::distribution::Distribution1D;
use crate::shading::luminance;

/// Voxels along the longest side of the scene bounds (pbrt-v3's `maxVoxels`).
const MAX_VOXELS: f32 = 64.0;
/// Points per voxel at which the lights are evaluated (pbrt-v3's `nSamples`).
pub(crate) const SAMPLES: usize = 128;
/// Largest number of voxels kept (a degenerate flat scene gives far fewer; this bounds memory).
const MAX_CELLS: usize = 64 * 64 * 64;

/// Light selection probabilities that depend on where the shading point is.
#[derive(Debug)]
pub struct SpatialSelect {
    lo: Vec3A,
    extent: Vec3A,
    n: [usize; 3],
    /// Per voxel, once built: its distribution's cdf (one more value than lights) followed by each light's
    /// probability, in one allocation so that a lookup touches as few cache lines as it can (the voxels
    /// are visited in no order and most lookups miss the cache).
    cells: Vec<OnceLock<Box<[f32]>>>,
    /// The points' radical inverses (bases 2, 3, 5: the position in the voxel; 7, 11: the light sample),
    /// computed once rather than for every voxel.
    halton: Box<[[f32; 5]]>,
    /// The barycentrics (b0, b1, b2) a triangle light's sample at each point has (`area::triangle_point`
    /// of the light sample): the same for every triangle.
    bary: Box<Soa>,
}

/// A voxel of the grid, as [`SpatialSelect::locate`] finds it.
#[derive(Clone, Copy, Debug)]
pub struct Voxel {
    /// Its cell coordinates.
    v: [usize; 3],
    /// Its slot in [`SpatialSelect::cells`].
    index: usize,
}

/// [`SAMPLES`] points (or triples) as three coordinate arrays, which the per-light loops run over lane by
/// lane.
#[derive(Debug)]
pub(crate) struct Soa {
    /// First coordinates.
    pub x: [f32; SAMPLES],
    /// Second coordinates.
    pub y: [f32; SAMPLES],
    /// Third coordinates.
    pub z: [f32; SAMPLES],
}

impl Soa {
    /// `f(i)` for each point i.
    fn from_fn(mut f: impl FnMut(usize) -> [f32; 3]) -> Box<Soa> {
        let mut s = Box::new(Soa { x: [0.0; SAMPLES], y: [0.0; SAMPLES], z: [0.0; SAMPLES] });
        for i in 0..SAMPLES {
            [s.x[i], s.y[i], s.z[i]] = f(i);
        }
        s
    }
}

impl SpatialSelect {
    /// The grid over the world bounds `(lo, hi)` (`None`: an empty world, one voxel).
    pub fn new(bounds: Option<(Vec3A, Vec3A)>) -> SpatialSelect {
        let (lo, hi) = bounds.unwrap_or((Vec3A::ZERO, Vec3A::ZERO));
        let extent = (hi - lo).max(Vec3A::ZERO);
        let longest = extent.max_element();
        let mut n = [1usize; 3];
        if longest > 0.0 && longest.is_finite() {
            for (k, nk) in n.iter_mut().enumerate() {
                *nk = ((extent[k] / longest * MAX_VOXELS).round() as usize).max(1);
            }
        }
        let count = (n[0] * n[1] * n[2]).min(MAX_CELLS);
        let halton: Box<[[f32; 5]]> =
            (0..SAMPLES as u32).map(|i| [2, 3, 5, 7, 11].map(|b| radical_inverse(b, i))).collect();
        let bary = Soa::from_fn(|i| {
            // `area::triangle_point`'s barycentrics, operation for operation.
            let [_, _, _, u0, u1] = halton[i];
            let su0 = u0.sqrt();
            let (b0, b1) = (1.0 - su0, u1 * su0);
            [b0, b1, 1.0 - b0 - b1]
        });
        SpatialSelect { lo, extent, n, cells: (0..count).map(|_| OnceLock::new()).collect(), halton, bary }
    }

    /// The voxel holding `p` (clamped into the grid).
    fn cell(&self, p: Vec3A) -> [usize; 3] {
        let mut v = [0usize; 3];
        for k in 0..3 {
            let t = if self.extent[k] > 0.0 { (p[k] - self.lo[k]) / self.extent[k] } else { 0.0 };
            let i = (t * self.n[k] as f32) as i64; // NaN → 0
            v[k] = i.clamp(0, self.n[k] as i64 - 1) as usize;
        }
        v
    }

    /// The slot in [`SpatialSelect::cells`] of voxel `v`.
    fn index(&self, v: [usize; 3]) -> usize {
        ((v[2] * self.n[1] + v[1]) * self.n[0] + v[0]).min(self.cells.len() - 1)
    }

    /// The voxel holding `p`, its table asked for in advance: the CPU is told to bring the table into its
    /// cache if it is built. A path calls this as soon as it knows its next vertex and picks the light with
    /// [`SpatialSelect::sample_in`] after shading it, so the table's cache misses overlap the shading work
    /// instead of stalling the light choice.
    #[inline]
    pub fn locate(&self, p: Vec3A) -> Voxel {
        let v = self.cell(p);
        let voxel = Voxel { v, index: self.index(v) };
        #[cfg(target_arch = "x86_64")]
        if let Some(t) = self.cells[voxel.index].get() {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            for line in t.chunks(16) {
                // SAFETY: prefetching is a hint; the address is that of live data.
                unsafe { _mm_prefetch::<_MM_HINT_T0>(line.as_ptr().cast()) };
            }
        }
        voxel
    }

    /// Voxel `v`'s sample points (point i's light sample is the last two radical inverses of
    /// [`SpatialSelect::halton`]`[i]`, the same in every voxel).
    fn voxel_points(&self, v: [usize; 3]) -> Box<Soa> {
        let size = Vec3A::new(
            self.extent.x / self.n[0] as f32,
            self.extent.y / self.n[1] as f32,
            self.extent.z / self.n[2] as f32,
        );
        let p0 = self.lo + Vec3A::new(v[0] as f32, v[1] as f32, v[2] as f32) * size;
        Soa::from_fn(|i| {
            let [x, y, z, ..] = self.halton[i];
            (p0 + Vec3A::new(x, y, z) * size).to_array()
        })
    }

    /// The table of `voxel` (see [`SpatialSelect::cells`]), built on first use.
    fn table(&self, lights: &Lights<'_>, voxel: Voxel) -> &[f32] {
        self.cells[voxel.index].get_or_init(|| table_of(&self.compute(lights, voxel.v)))
    }

    /// pbrt-v3's `SpatialLightDistribution::ComputeDistribution` for voxel `v`.
    fn compute(&self, lights: &Lights<'_>, v: [usize; 3]) -> Distribution1D {
        let points = self.voxel_points(v);
        let mut contrib = vec![0.0f32; lights.len()];
        for (j, c) in contrib.iter_mut().enumerate() {
            // Triangle lights (most scenes' only kind) by the dedicated loop; the sums are the same, term by
            // term and in the same order, as the general loop's.
            *c = match lights.triangle_unoccluded_sum(j, &points, &self.bary) {
                Some(sum) => sum,
                None => self.unoccluded_sum(lights, j, &points),
            };
        }
        let sum: f32 = contrib.iter().sum();
        let avg = sum / (SAMPLES as f32 * contrib.len().max(1) as f32);
        let floor = if avg > 0.0 { 0.001 * avg } else { 1.0 };
        contrib.iter_mut().for_each(|c| *c = c.max(floor));
        Distribution1D::new(&contrib)
    }

    /// Σ over the points `at` of luminance(Li) / pdf of light `j`'s sample at point i, without visibility,
    /// skipping samples that carry nothing or give a non-finite term (any kind of light).
    fn unoccluded_sum(&self, lights: &Lights<'_>, j: usize, at: &Soa) -> f32 {
        let mut sum = 0.0;
        for (i, h) in self.halton.iter().enumerate() {
            let at = Vec3A::new(at.x[i], at.y[i], at.z[i]);
            if let Some(ls) = lights.sample_li_with::<false>(j, &point_interaction(at), [h[3], h[4]])
                && ls.pdf > 0.0
            {
                let y = luminance(ls.li) / ls.pdf;
                if y.is_finite() {
                    sum += y;
                }
            }
        }
        sum
    }

    /// Picks a light for a point in `voxel` (from [`SpatialSelect::locate`]) with `u` ∈ [0, 1): its index and
    /// probability.
    #[inline]
    pub fn sample_in(&self, lights: &Lights<'_>, voxel: Voxel, u: f32) -> Option<(usize, f32)> {
        if lights.is_empty() {
            return None;
        }
        let (i, pmf) = pick(self.table(lights, voxel), u);
        (pmf > 0.0).then_some((i, pmf))
    }
}

/// The table a voxel keeps for distribution `d` (see [`SpatialSelect::cells`]).
fn table_of(d: &Distribution1D) -> Box<[f32]> {
    d.cdf().iter().copied().chain((0..d.count()).map(|i| d.discrete_pdf(i))).collect()
}

/// `Distribution1D::sample_discrete(u)` of the distribution whose table is `t`.
#[inline]
fn pick(t: &[f32], u: f32) -> (usize, f32) {
    let n = t.len() / 2;
    let (cdf, pmfs) = t.split_at(n + 1);
    let i = cdf.partition_point(|&c| c <= u).saturating_sub(1).min(n - 1);
    (i, pmfs[i])
}

/// A bare point (no surface: zero normals), as pbrt-v3's `Interaction` at a voxel sample point.
fn point_interaction(p: Vec3A) -> SurfaceInteraction {
    SurfaceInteraction {
        p,
        p_error: Vec3A::ZERO,
        t: 0.0,
        ng: Vec3A::ZERO,
        ns: Vec3A::ZERO,
        dpdu: Vec3A::X,
        uv: [0.0; 2],
        material: 0,
        area_light: None,
        origin: PrimOrigin { prim: PrimRef::Quadric(u32::MAX), instance: None },
    }
}

/// The radical inverse of `i` in prime `base` (the Halton sequence's dimension for that base).
fn radical_inverse(base: u32, mut i: u32) -> f32 {
    let inv = 1.0 / base as f64;
    let (mut digits, mut scale) = (0.0f64, inv);
    while i > 0 {
        digits += (i % base) as f64 * scale;
        i /= base;
        scale *= inv;
    }
    (digits as f32).min(1.0 - f32::EPSILON / 2.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radical_inverses_are_the_halton_points() {
        assert_eq!(radical_inverse(2, 1), 0.5);
        assert_eq!(radical_inverse(2, 3), 0.75);
        assert!((radical_inverse(3, 1) - 1.0 / 3.0).abs() < 1e-7);
        assert!((radical_inverse(5, 7) - (2.0 / 5.0 + 1.0 / 25.0)).abs() < 1e-7);
    }

    #[test]
    fn a_voxel_table_picks_what_its_distribution_picks() {
        let mut rng = crate::sampling::Rng::keyed(3, 1, 0);
        for f in [vec![1.0], vec![0.0, 2.0, 0.0, 5.0, 1e-6], vec![0.0; 4], (0..21).map(|i| (i % 5) as f32).collect()] {
            let d = Distribution1D::new(&f);
            let t = table_of(&d);
            let us = (0..2000).map(|_| rng.uniform()).chain([0.0, 0.5, 1.0 - f32::EPSILON / 2.0]);
            for u in us {
                assert_eq!(pick(&t, u), d.sample_discrete(u), "f {f:?} u {u}");
            }
        }
    }

    #[test]
    fn the_triangle_loop_sums_what_the_general_loop_sums_bit_for_bit() {
        // Emitting triangles of every flavour `area::triangle_point` distinguishes: shading normals whose
        // interpolation changes side across the triangle, a reversed mesh without normals, a two-sided quad,
        // and a light in the plane of some voxel points; plus a disk, which only the general loop handles.
        let text = r#"WorldBegin
AttributeBegin
AreaLightSource "diffuse" "rgb L" [1 2 3]
Shape "trianglemesh" "point P" [0 0 0  2 0 0  0 2 0.5] "integer indices" [0 1 2] "normal N" [0 0 1  0 0 -1  0.3 0 1]
AttributeEnd
AttributeBegin
ReverseOrientation
AreaLightSource "diffuse" "rgb L" [2 2 2]
Shape "trianglemesh" "point P" [0 0 2  0 2 2  2 0 2.5] "integer indices" [0 1 2]
AttributeEnd
AttributeBegin
AreaLightSource "diffuse" "rgb L" [0.5 1 1] "bool twosided" "true"
Shape "trianglemesh" "point P" [-1 -1 1  3 -1 1  3 3 1  -1 3 1] "integer indices" [0 1 2 0 2 3]
AttributeEnd
AttributeBegin
Translate 1 1 3
AreaLightSource "diffuse" "rgb L" [1 1 1]
Shape "disk" "float radius" 0.5
AttributeEnd
Shape "trianglemesh" "point P" [-2 -2 -1  4 -2 -1  4 4 -1  -2 4 -1] "integer indices" [0 1 2 0 2 3]
WorldEnd
"#;
        let loaded = crate::scene::load_str(text, std::path::Path::new("inline.pbrt"), Default::default()).unwrap();
        let mut warnings = crate::error::Warnings::default();
        let lights = Lights::build(&loaded.scene, &mut warnings).unwrap();
        let s = SpatialSelect::new(loaded.scene.bounds());
        let (mut compared, mut general) = (0, 0);
        for v in (0..s.n[0]).step_by(3).flat_map(|x| (0..s.n[1]).step_by(3).map(move |y| (x, y))) {
            for z in (0..s.n[2]).step_by(2) {
                let points = s.voxel_points([v.0, v.1, z]);
                for j in 0..lights.len() {
                    let slow = s.unoccluded_sum(&lights, j, &points);
                    match lights.triangle_unoccluded_sum(j, &points, &s.bary) {
                        Some(fast) => {
                            assert_eq!(fast.to_bits(), slow.to_bits(), "light {j} voxel {v:?},{z}: {fast} vs {slow}");
                            compared += usize::from(slow > 0.0);
                        }
                        None => general += 1,
                    }
                }
            }
        }
        assert!(compared > 500 && general > 100, "compared {compared}, general {general}");
    }

    #[test]
    fn the_grid_follows_the_bounds_aspect_and_clamps_points() {
        let s = SpatialSelect::new(Some((Vec3A::ZERO, Vec3A::new(2.0, 1.0, 0.0))));
        assert_eq!(s.n, [64, 32, 1]);
        assert_eq!(s.cell(Vec3A::new(-5.0, 0.5, 3.0)), [0, 16, 0]);
        assert_eq!(s.cell(Vec3A::new(9.0, f32::NAN, 0.0)), [63, 0, 0]);
        assert_eq!(SpatialSelect::new(None).cells.len(), 1);
    }
}
