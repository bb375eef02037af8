//! STAGE 5 (shading): light leaving the lights — where light paths start (pbrt-v3's `Light::Sample_Le`) and
//! what an emitting point or direction sends toward a receiver. The virtual point lights of importance
//! caching are made from these: the first vertex of every light path is an emission VPL.
//!
//! Point lights emit uniformly over the sphere, spot lights uniformly over their cone, area lights
//! cosine-weighted from a point chosen by area (both sides for a two-sided emitter, one picked with equal
//! probability, which pbrt-v3 leaves out), and distant and infinite lights from a disk the size of the
//! world's bounding sphere facing their direction, as pbrt-v3 does. Depends on the light types of this
//! module's parent and on `sampling`; never on the renderer.

use glam::Vec3A;

use super::area::{SurfacePoint, sample_triangle};
use super::{Kind, Lights};
use crate::sampling::Frame;
use crate::sampling::warp::{concentric_disk, cosine_hemisphere, uniform_cone, uniform_sphere};
use crate::scene::ray::{Ray, offset_ray_origin};
use crate::shading::Spectrum;

/// Where light leaves a light source: the emission vertex of a light path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EmitterPoint {
    /// The position of a point or spot light.
    Point(Vec3A),
    /// A point on an area light, with its emitting-side normal.
    Surface(SurfacePoint),
    /// The unit direction toward a distant or infinite light.
    Direction(Vec3A),
}

/// The start of a light path drawn from one light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightPathStart {
    /// The emission vertex.
    pub at: EmitterPoint,
    /// 1 / the density with which `at` was drawn: area density for a surface point, solid-angle density for
    /// an infinite light's direction, 1 for point, spot and distant lights (their vertex is fixed).
    pub inv_pdf_at: f32,
    /// The path's first ray.
    pub ray: Ray,
    /// Le·|cos θ| / (pdf_pos·pdf_dir): the throughput the first ray carries (before the choice of light).
    pub beta: Spectrum,
}

impl Lights<'_> {
    /// Draws the start of a light path from light `light` with samples `u_pos` (the emission vertex) and
    /// `u_dir` (the direction); `None` when the sample carries nothing.
    pub fn sample_le(&self, light: usize, u_pos: [f32; 2], u_dir: [f32; 2]) -> Option<LightPathStart> {
        use std::f32::consts::PI;
        let start = match self.entries[light].kind {
            Kind::Point(l) => {
                let w = uniform_sphere(u_dir);
                let beta = l.i * (4.0 * PI);
                LightPathStart { at: EmitterPoint::Point(l.p), inv_pdf_at: 1.0, ray: Ray::new(l.p, w), beta }
            }
            Kind::Spot(l) => {
                let local = Frame::from_normal(l.axis).to_world(uniform_cone(u_dir, l.cos_total));
                let w = (l.light_from_world.inverse() * local).normalize_or_zero();
                let pdf = 1.0 / (2.0 * PI * (1.0 - l.cos_total));
                let beta = l.i * (l.falloff(w) / pdf);
                LightPathStart { at: EmitterPoint::Point(l.p), inv_pdf_at: 1.0, ray: Ray::new(l.p, w), beta }
            }
            Kind::Distant(l) => {
                let ray = self.disk_ray(l.w, u_pos)?;
                let beta = l.l * (PI * self.world_radius * self.world_radius);
                LightPathStart { at: EmitterPoint::Direction(l.w), inv_pdf_at: 1.0, ray, beta }
            }
            Kind::Infinite(i) => {
                let (le, w, pdf) = self.infinite[i as usize].sample(u_dir)?;
                let ray = self.disk_ray(w, u_pos)?;
                let beta = le * (PI * self.world_radius * self.world_radius / pdf);
                LightPathStart { at: EmitterPoint::Direction(w), inv_pdf_at: 1.0 / pdf, ray, beta }
            }
            Kind::Triangle { area, mesh, tri, tri_area, n_face } => {
                let sp = sample_triangle(&self.geometry.meshes[mesh as usize], tri as usize, n_face, u_pos);
                self.surface_start(area, sp, tri_area, u_dir)?
            }
            Kind::Shape { area, quadric, sampler } => {
                let (sp, pdf) = sampler.sample_area(&self.geometry.accel.quadrics[quadric as usize], u_pos)?;
                self.surface_start(area, sp, 1.0 / pdf, u_dir)?
            }
        };
        let ok = start.beta.max_element() > 0.0
            && start.beta.is_finite()
            && start.inv_pdf_at.is_finite()
            && start.ray.d != Vec3A::ZERO;
        ok.then_some(start)
    }

    /// What light `light` sends from `at` toward unit direction `w` (leaving the emitter): radiance for an
    /// area light, intensity for a point or spot light; for a direction, the radiance arriving along it
    /// (`w` is then ignored).
    pub fn emission(&self, light: usize, at: &EmitterPoint, w: Vec3A) -> Spectrum {
        match (self.entries[light].kind, at) {
            (Kind::Point(l), _) => l.i,
            (Kind::Spot(l), _) => l.i * l.falloff(w),
            (Kind::Distant(l), _) => l.l,
            (Kind::Infinite(i), EmitterPoint::Direction(d)) => self.infinite[i as usize].le(*d),
            (Kind::Triangle { area, .. } | Kind::Shape { area, .. }, EmitterPoint::Surface(sp)) => {
                self.emission[area as usize].l(sp.n, w)
            }
            _ => Spectrum::ZERO,
        }
    }

    /// Whether light `light` is a point light (it emits the same intensity in every direction).
    pub fn is_point(&self, light: usize) -> bool {
        matches!(self.entries[light].kind, Kind::Point(_))
    }

    /// Whether light `light` is an area light that emits from both sides.
    pub fn is_two_sided(&self, light: usize) -> bool {
        match self.entries[light].kind {
            Kind::Triangle { area, .. } | Kind::Shape { area, .. } => self.emission[area as usize].two_sided,
            _ => false,
        }
    }

    /// Radius of the world's bounding sphere (distant and infinite lights' disks).
    pub fn world_radius(&self) -> f32 {
        self.world_radius
    }

    /// A ray along −`w` from a uniformly chosen point of the world-sized disk facing `w`, outside the world.
    fn disk_ray(&self, w: Vec3A, u: [f32; 2]) -> Option<Ray> {
        let r = self.world_radius;
        if !(r > 0.0 && r.is_finite()) {
            return None;
        }
        let f = Frame::from_normal(w);
        let [dx, dy] = concentric_disk(u);
        let o = self.world_center + r * (w + dx * f.s + dy * f.t);
        Some(Ray::new(o, -w))
    }

    /// A cosine-weighted direction leaving area light `area` at `sp` (chosen with area density
    /// 1/`inv_pdf_pos`); a two-sided emitter picks its side with `u[0]`.
    fn surface_start(&self, area: u32, sp: SurfacePoint, inv_pdf_pos: f32, u: [f32; 2]) -> Option<LightPathStart> {
        let em = &self.emission[area as usize];
        let (n, u, sides) = if em.two_sided {
            if u[0] < 0.5 { (sp.n, [u[0] * 2.0, u[1]], 2.0) } else { (-sp.n, [(u[0] - 0.5) * 2.0, u[1]], 2.0) }
        } else {
            (sp.n, u, 1.0)
        };
        let w = Frame::from_normal(n).to_world(cosine_hemisphere([u[0].min(1.0 - f32::EPSILON / 2.0), u[1]]));
        // Le·cos / (pdf_pos · cos/(π·sides)) = Le·π·sides / pdf_pos.
        let beta = em.l(sp.n, w) * (std::f32::consts::PI * sides * inv_pdf_pos);
        let ray = Ray::new(offset_ray_origin(sp.p, sp.p_error, sp.n, w), w);
        let ok = w.dot(n) > 0.0;
        ok.then_some(LightPathStart { at: EmitterPoint::Surface(sp), inv_pdf_at: inv_pdf_pos, ray, beta })
    }
}
