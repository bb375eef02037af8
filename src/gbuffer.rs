//! STAGE 3: the G-buffer — one shading point per pixel centre (ALGORITHMS.md §2), the input of every
//! cache-placement strategy. A pixel whose camera ray leaves the scene is not valid.
//!
//! Depends on `scene` (camera rays, intersections); placement code reads only these plain types, so tests
//! can build synthetic G-buffers with [`GBuffer::from_fn`].

pub mod scale;

use glam::Vec3A;
use rayon::prelude::*;

use crate::scene::Scene;
use crate::scene::accel::PrimOrigin;
use crate::scene::geometry::SurfaceInteraction;

/// Index of a pixel in a G-buffer: `y * width + x`.
pub type PixelId = u32;

/// The surface seen through one pixel centre (or one sub-pixel sample): what placement reads (p, n, depth)
/// and what shading needs — the shading frame (n with ∂p/∂u), the material and (u, v) its textures are
/// evaluated at, and the area light of an emitter seen directly. Plain `Copy` data.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingPoint {
    /// World position.
    pub p: Vec3A,
    /// Absolute error bound of `p` (for spawning rays).
    pub p_error: Vec3A,
    /// Unit shading normal, faced toward the camera.
    pub n: Vec3A,
    /// Unit geometric normal, faced toward the camera.
    pub ng: Vec3A,
    /// Unit direction from `p` toward the camera.
    pub wo: Vec3A,
    /// Distance from the camera position to `p`.
    pub depth: f32,
    /// ∂p/∂u, not normalised: with `n` it gives the shading frame (tangent = the part of ∂p/∂u orthogonal
    /// to `n`), as pbrt-v3's BSDF builds it.
    pub dpdu: Vec3A,
    /// Surface (u, v).
    pub uv: [f32; 2],
    /// Material id.
    pub material: u32,
    /// Area light id when the surface seen emits (its radiance toward `wo` is added by integrators that
    /// show emitters).
    pub area_light: Option<u32>,
    /// The primitive seen (shadow rays from here skip it; see `scene::accel::PrimOrigin`).
    pub origin: Option<PrimOrigin>,
    /// Whether `n` and `ng` (in that order) were flipped to face the camera: the surface's own normals are
    /// the negated ones. [`ShadingPoint::interaction`] restores them, because pbrt-v3's BSDFs are not all
    /// symmetric in the normal's side (plastic's Fresnel term reflects as from inside the dielectric when
    /// the viewer is on the side of the shading normal) and one-sided emitters emit on one side only.
    pub flipped: [bool; 2],
}

impl ShadingPoint {
    /// The shading point of the hit `si`, seen from unit direction `wo` after a path of length `depth`
    /// from the camera: its normals faced toward `wo`, with which ones were flipped recorded.
    pub fn at_hit(si: &SurfaceInteraction, wo: Vec3A, depth: f32) -> ShadingPoint {
        let face = |n: Vec3A| if n.dot(wo) < 0.0 { -n } else { n };
        ShadingPoint {
            p: si.p,
            p_error: si.p_error,
            n: face(si.ns),
            ng: face(si.ng),
            flipped: [si.ns.dot(wo) < 0.0, si.ng.dot(wo) < 0.0],
            wo,
            depth,
            dpdu: si.dpdu,
            uv: si.uv,
            material: si.material,
            area_light: si.area_light,
            origin: Some(si.origin),
        }
    }

    /// The surface interaction at this point with the surface's own normals (as the camera ray's hit had
    /// them, before `n` and `ng` were faced toward the camera), so that a BSDF or emitter built from it is
    /// the one a per-pixel integrator sees; `None` for a point not made by a camera ray (no primitive).
    pub fn interaction(&self) -> Option<SurfaceInteraction> {
        let own = |n: Vec3A, flipped: bool| if flipped { -n } else { n };
        Some(SurfaceInteraction {
            p: self.p,
            p_error: self.p_error,
            t: self.depth,
            ng: own(self.ng, self.flipped[1]),
            ns: own(self.n, self.flipped[0]),
            dpdu: self.dpdu,
            uv: self.uv,
            material: self.material,
            area_light: self.area_light,
            origin: self.origin?,
        })
    }
}

/// The shading point seen through film position `p_film` (raster coordinates of the full image), passing
/// through surfaces without a material as the integrators do; `None` when the ray leaves the scene.
pub fn shading_point(scene: &Scene, p_film: [f32; 2]) -> Option<ShadingPoint> {
    let cam = scene.camera.position();
    let mut ray = scene.camera.generate_ray(p_film, [0.5, 0.5]);
    for _ in 0..1024 {
        let si = scene.geometry.intersect(&ray)?;
        if scene.is_null_material(si.material) {
            ray = si.spawn_ray(ray.d);
            continue;
        }
        return Some(ShadingPoint::at_hit(&si, -ray.d.normalize(), (si.p - cam).length()));
    }
    None
}

/// One shading point per pixel of the (cropped) image.
#[derive(Clone, Debug, PartialEq)]
pub struct GBuffer {
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// `Some` where the pixel centre sees a surface; row-major, top row first.
    pub points: Vec<Option<ShadingPoint>>,
    /// Number of valid pixels (ALGORITHMS.md's P).
    pub valid_count: usize,
    /// Smallest and largest depth over valid pixels ((0, 0) when none is valid).
    pub depth_range: (f32, f32),
    /// The scene's length scale L ([`scale::SceneScale::length`]; ALGORITHMS.md's L), which the placement
    /// strategies' scale-dependent defaults are multiples of.
    pub scale: f32,
}

impl GBuffer {
    /// Builds a G-buffer from a function of (x, y) — for tests and synthetic inputs.
    pub fn from_fn(width: usize, height: usize, scale: f32, f: impl Fn(usize, usize) -> Option<ShadingPoint>) -> Self {
        let points = (0..width * height).map(|i| f(i % width, i / width)).collect();
        Self::finish(width, height, points, scale)
    }

    /// Traces one primary ray through every pixel centre of `scene`'s cropped film (passing through
    /// surfaces without a material, as the integrators do); `scale` is the scene's length scale L
    /// ([`scale::SceneScale::of`]).
    pub fn from_scene(scene: &Scene, scale: f32) -> Self {
        let b = scene.film.cropped_bounds();
        let [w, h] = b.size();
        let points = (0..w * h)
            .into_par_iter()
            .map(|i| {
                let p_film = [(b.min[0] + (i % w) as i32) as f32 + 0.5, (b.min[1] + (i / w) as i32) as f32 + 0.5];
                shading_point(scene, p_film)
            })
            .collect();
        Self::finish(w, h, points, scale)
    }

    fn finish(width: usize, height: usize, points: Vec<Option<ShadingPoint>>, scale: f32) -> Self {
        let valid_count = points.iter().filter(|p| p.is_some()).count();
        let depth_range = points.iter().flatten().fold(None, |r: Option<(f32, f32)>, p| {
            Some(r.map_or((p.depth, p.depth), |(lo, hi)| (lo.min(p.depth), hi.max(p.depth))))
        });
        GBuffer { width, height, points, valid_count, depth_range: depth_range.unwrap_or((0.0, 0.0)), scale }
    }

    /// The pixel id of (x, y).
    #[inline]
    pub fn id(&self, x: usize, y: usize) -> PixelId {
        (y * self.width + x) as PixelId
    }

    /// The (x, y) of a pixel id.
    #[inline]
    pub fn xy(&self, id: PixelId) -> (usize, usize) {
        (id as usize % self.width, id as usize / self.width)
    }

    /// The shading point of pixel `id`, if valid.
    #[inline]
    pub fn get(&self, id: PixelId) -> Option<&ShadingPoint> {
        self.points.get(id as usize).and_then(|p| p.as_ref())
    }

    /// The ids of all valid pixels, in order.
    pub fn valid_ids(&self) -> Vec<PixelId> {
        self.points.iter().enumerate().filter(|(_, p)| p.is_some()).map(|(i, _)| i as PixelId).collect()
    }
}
