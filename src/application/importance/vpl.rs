//! STAGE 5 (application, importance caching): the virtual point lights (ALGORITHMS.md §6.3) — made by
//! tracing light paths (instant radiosity) and evaluated at a receiver.
//!
//! Every light path starts at a light chosen by power (pbrt-v3's `Sample_Le`,
//! [`Lights::sample_le`](crate::shading::light::Lights::sample_le)); its first vertex is an *emission VPL*
//! (the direct light), every later surface vertex with a non-specular lobe a *surface VPL* (the indirect
//! light). Paths continue by BSDF sampling up to `max_depth` surface vertices with Russian roulette after
//! the second, and paths are traced until the requested number of VPLs exists (the last path is cut
//! there); every power is divided by the number of paths started. The contribution of VPL j to a
//! receiver x with BSDF f_x seen from ω_o is
//!
//! I_j(x) = E_j(−ω) · f_x(ω_o, ω) · |cos θ_x| / max(d², d_c²) · V(x, y_j),
//!
//! where ω is the unit direction from x to the VPL and E_j what the VPL sends toward x: for a surface VPL
//! β·f_j(−ω, ω_in)·|ω_in·n_s| / |ω_in·n_g| · |cos θ_j| with θ_j about the geometric normal, for a point on
//! an area light Le·|cos θ_j|, for a point light its intensity; a distant or infinite light's emission VPL
//! is a direction (no distance, no clamp). The clamp d_c is the same for the estimator and the reference;
//! the light it removes is put back by `compensation` (each VPL records its depth for it).
//!
//! Light paths carry importance: at a vertex with shading normals the throughput takes the adjoint BSDF,
//! f · |ω_in·n_s| · |ω_out·n_g| / (|ω_in·n_g| · pdf), and a VPL's light toward x the same factor (pbrt-v3's
//! `CorrectShadingNormal`); the radiance BSDF made the buddha fractal's one-bounce light 5 % too bright.
//! (Across refraction the throughput keeps the radiance BSDF's (η_i/η_t)² scaling, which the adjoint has
//! not; it cancels through a slab of glass, not where a path starts or ends inside one.) VPLs on Lambertian
//! surfaces (the most common) store their diffuse radiance factor β·R/π, with that factor, and emit like a
//! cosine emitter; other surface VPLs keep their BSDF in a side table, so the list the per-sample reference
//! walks stays small.
//!
//! Depends on `scene`, `shading` and `shading::lighting` (the prepared shading data); never on placement.

use glam::Vec3A;

use crate::sampling::Rng;
use crate::scene::Scene;
use crate::scene::geometry::SurfaceInteraction;
use crate::scene::ray::{Ray, RayCounters, offset_ray_origin};
use crate::shading::bsdf::Bsdf;
use crate::shading::bxdf::{Bxdf, BxdfFlags};
use crate::shading::light::{EmitterPoint, LightSelect, SHADOW_EPSILON, SurfacePoint, spawn_ray_to};
use crate::shading::lighting::{PassThrough, Shading};
use crate::shading::{Spectrum, luminance};

/// How a VPL sends light toward a receiver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Emitter {
    /// Power·|n·w| toward the side of `ng` (both sides when `two_sided`): a point on a diffuse area light,
    /// or a surface VPL on a Lambertian surface.
    Cosine {
        /// Whether both sides emit.
        two_sided: bool,
    },
    /// Power in every direction (a point light).
    Isotropic,
    /// Power × what light `light` emits from the VPL toward w (a spot light).
    Light {
        /// The light's index.
        light: u32,
    },
    /// Power arriving from direction `n` (a distant or infinite light); no distance.
    Directional,
    /// Power × f_j(w, ω_in)·|n·w| with the BSDF and ω_in of entry `index` of [`Vpls::bsdfs`].
    Bsdf {
        /// Index into the side table.
        index: u32,
    },
}

/// One virtual point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vpl {
    /// Position (unused for directional VPLs).
    pub p: Vec3A,
    /// Absolute error bound of `p` (for the shadow ray's offset).
    pub p_error: Vec3A,
    /// Emitting-side geometric normal (zero for point lights); for a directional VPL the unit direction
    /// toward the light.
    pub ng: Vec3A,
    /// Shading normal on the same side (the cosine's axis).
    pub ns: Vec3A,
    /// Power factor (already divided by the number of light paths and the light's selection probability).
    pub power: Spectrum,
    /// How it emits.
    pub emitter: Emitter,
}

/// A surface VPL whose BSDF is not Lambertian: the BSDF and the direction the light came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeneralVpl {
    /// The BSDF at the VPL.
    pub bsdf: Bsdf,
    /// Unit direction toward the previous vertex of the light path.
    pub wi: Vec3A,
}

/// |`w`·`ns`| / |`w`·`ng`| (0 where `w` lies in the geometric plane): the shading-normal correction of
/// importance transport for light arriving from `w` (pbrt-v3's `CorrectShadingNormal`, its other factor
/// being the outgoing direction's geometric cosine).
fn adjoint_factor(w: Vec3A, ns: Vec3A, ng: Vec3A) -> f32 {
    let g = w.dot(ng).abs();
    if g > 0.0 { w.dot(ns).abs() / g } else { 0.0 }
}

/// The VPL set of a render.
#[derive(Clone, Debug)]
pub struct Vpls {
    /// The VPLs.
    pub list: Vec<Vpl>,
    /// BSDFs of the non-Lambertian surface VPLs.
    pub bsdfs: Vec<GeneralVpl>,
    /// Light paths started.
    pub paths: u64,
    /// d_c² (the distance clamp, squared).
    pub clamp2: f32,
    /// Each VPL's flux luminance (for power sampling).
    pub flux: Vec<f32>,
    /// Each VPL's surface vertices on its light path before it (0: an emission VPL; a surface VPL at the
    /// k-th surface vertex: k), for estimates that add vertices of their own (the clamp's compensation).
    pub depth: Vec<u8>,
    /// Per VPL, the end of a shadow ray to it from either side of its surface: its position offset along
    /// its normal (index 0) and against it (index 1), as `spawn_ray_to` would offset it; made once with
    /// the set so that the shadow rays of a cache's thousands of VPLs only choose one
    /// ([`Vpls::shadow_ray`]). Empty for a set built by hand (the rays are then offset per call).
    ends: Vec<[Vec3A; 2]>,
}

/// A receiver: a surface point with its BSDF and the direction it is seen from.
#[derive(Clone, Copy, Debug)]
pub struct Receiver {
    /// The surface point.
    pub si: SurfaceInteraction,
    /// Its BSDF.
    pub bsdf: Bsdf,
    /// Unit direction toward the viewer.
    pub wo: Vec3A,
    /// When every non-specular lobe is Lambertian reflection (then f needs no lobe walk): R/π (0 when
    /// `wo` lies in the shading frame's plane), and ω_o · n_g, whose sign f's direction must share.
    lambert: Option<(Spectrum, f32)>,
    /// The origin of a shadow ray leaving the surface on the side of its geometric normal (index 0) and on
    /// the other (index 1), as `spawn_ray_to` would offset it.
    origins: [Vec3A; 2],
}

impl Receiver {
    /// The receiver at `si` with BSDF `bsdf`, seen from `wo`.
    pub fn new(si: SurfaceInteraction, bsdf: Bsdf, wo: Vec3A) -> Self {
        let origins = [si.ng, -si.ng].map(|w| offset_ray_origin(si.p, si.p_error, si.ng, w));
        let lambert = lambertian(&bsdf).map(|r| {
            let r = if bsdf.to_local(wo).z != 0.0 { r } else { Spectrum::ZERO };
            (r, wo.dot(bsdf.geometric_normal()))
        });
        Receiver { si, bsdf, wo, lambert, origins }
    }

    /// f(ω_o, `wi`) over the non-specular lobes (specular ones are 0 for any given direction).
    #[inline]
    fn f(&self, wi: Vec3A) -> Spectrum {
        match self.lambert {
            Some((r, a)) => {
                if a * wi.dot(self.bsdf.geometric_normal()) > 0.0 {
                    r
                } else {
                    Spectrum::ZERO
                }
            }
            None => self.bsdf.f(self.wo, wi, BxdfFlags::ALL),
        }
    }
}

/// R/π summed over the Lambertian lobes when every non-specular lobe of `bsdf` is Lambertian reflection.
fn lambertian(bsdf: &Bsdf) -> Option<Spectrum> {
    let mut r = Spectrum::ZERO;
    for (b, scale) in bsdf.lobes() {
        match b {
            Bxdf::Lambertian(l) => r += scale * l.r,
            _ if b.flags().contains(BxdfFlags::SPECULAR) => {}
            _ => return None,
        }
    }
    Some(r * std::f32::consts::FRAC_1_PI)
}

/// What a VPL sends to a receiver before visibility: the RGB contribution and the shadow ray that decides
/// visibility.
#[derive(Clone, Copy, Debug)]
pub struct Unoccluded {
    /// I_j(x) with V = 1.
    pub value: Spectrum,
    /// From the receiver to the VPL (or along the VPL's direction, unbounded).
    pub shadow: Ray,
}

impl Vpls {
    /// No VPLs (a scene without lights, or the start of [`Vpls::generate`]), with the distance clamp `clamp`.
    pub fn none(clamp: f32) -> Vpls {
        Vpls {
            list: Vec::new(),
            bsdfs: Vec::new(),
            paths: 0,
            clamp2: clamp * clamp,
            flux: Vec::new(),
            depth: Vec::new(),
            ends: Vec::new(),
        }
    }

    /// Traces light paths in `scene` until `count` VPLs exist (or `64·count` paths brought none), with
    /// light paths of at most `max_depth` surface vertices, lights chosen by `select`, all randomness from
    /// `rng`, and the distance clamp `clamp`.
    pub fn generate(
        scene: &Scene,
        sh: &Shading<'_>,
        select: &LightSelect,
        count: usize,
        max_depth: u32,
        clamp: f32,
        rng: &mut Rng,
    ) -> Vpls {
        let mut v = Vpls::none(clamp);
        v.list.reserve(count);
        let mut rho_u = [[0.0f32; 2]; 16];
        for (i, u) in rho_u.iter_mut().enumerate() {
            *u = [((i % 4) as f32 + 0.5) / 4.0, ((i / 4) as f32 + 0.5) / 4.0];
        }
        let give_up = 64 * count as u64 + 64;
        while v.list.len() < count && v.paths < give_up {
            v.paths += 1;
            let Some((light, pmf)) = select.sample(rng.uniform()) else { break };
            let (u_pos, u_dir) = (rng.uniform2(), rng.uniform2());
            let Some(start) = sh.lights.sample_le(light, u_pos, u_dir) else { continue };
            v.push_emission(sh, light, &start.at, start.inv_pdf_at / pmf);
            let mut beta = start.beta / pmf;
            let beta0 = beta.max_element();
            let mut ray = start.ray;
            let (mut depth, mut pass) = (0u32, PassThrough::default());
            while v.list.len() < count && depth < max_depth {
                let Some(si) = scene.geometry.intersect(&ray) else { break };
                let Some(bsdf) = sh.bsdf(&si) else {
                    let Some(next) = pass.past(&si, &ray) else { break };
                    ray = next;
                    continue;
                };
                depth += 1;
                let wi = -ray.d.normalize();
                if bsdf.num_components(BxdfFlags::NON_SPECULAR) > 0 {
                    v.push_surface(&si, &bsdf, wi, beta, depth, &rho_u);
                }
                let Some(bs) = bsdf.sample_f(wi, rng.uniform2(), BxdfFlags::ALL) else { break };
                if bs.f == Spectrum::ZERO || bs.pdf <= 0.0 {
                    break;
                }
                // Importance transport (the adjoint BSDF): f · |ω_in·n_s| · |ω_out·n_g| / (|ω_in·n_g| · pdf), as
                // pbrt-v3's light paths weigh it; with the radiance BSDF's |ω_out·n_s| instead, a mesh with
                // shading normals sent too much light (the buddha fractal: +5 % against `path` one bounce).
                beta *= bs.f * (adjoint_factor(wi, bsdf.shading_normal(), si.ng) * bs.wi.dot(si.ng).abs() / bs.pdf);
                if depth >= 2 {
                    let rr = beta.max_element() / beta0;
                    if rr < 1.0 {
                        let q = (1.0 - rr).max(0.05);
                        if rng.uniform() < q {
                            break;
                        }
                        beta /= 1.0 - q;
                    }
                }
                if !beta.is_finite() {
                    break;
                }
                ray = si.spawn_ray(bs.wi);
            }
        }
        let inv = 1.0 / v.paths.max(1) as f32;
        for (vpl, flux) in v.list.iter_mut().zip(v.flux.iter_mut()) {
            vpl.power *= inv;
            *flux *= inv;
        }
        v.sort_spatially();
        v.ends = v.list.iter().map(|l| [l.ng, -l.ng].map(|w| offset_ray_origin(l.p, l.p_error, l.ng, w))).collect();
        v
    }

    /// Puts the VPLs in Morton (Z-curve) order of their positions, directional ones last, so that
    /// consecutive VPLs are near each other: a cache's shadow rays to consecutive VPLs then often meet the
    /// blocker the previous one met (tested first) and walk the same part of the BVH, and a cache's
    /// distributions have runs of zeros where a region is hidden. The order of a set is a relabelling: no
    /// estimate's expectation depends on it. Stable, so equal keys keep the order they were made in.
    fn sort_spatially(&mut self) {
        let positional = |v: &Vpl| !matches!(v.emitter, Emitter::Directional);
        let (lo, hi) = self
            .list
            .iter()
            .filter(|v| positional(v))
            .fold((Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)), |(lo, hi), v| {
                (lo.min(v.p), hi.max(v.p))
            });
        let scale = Vec3A::splat(1023.0) / (hi - lo).max(Vec3A::splat(f32::MIN_POSITIVE));
        let key = |v: &Vpl| -> u64 {
            if !positional(v) {
                return u64::MAX;
            }
            let q = ((v.p - lo) * scale).clamp(Vec3A::ZERO, Vec3A::splat(1023.0));
            let spread = |x: f32| {
                // The 10 bits of x, two zero bits between each.
                let mut b = x as u64 & 0x3ff;
                b = (b | b << 16) & 0x0300_00ff;
                b = (b | b << 8) & 0x0300_f00f;
                b = (b | b << 4) & 0x030c_30c3;
                (b | b << 2) & 0x0924_9249
            };
            spread(q.x) << 2 | spread(q.y) << 1 | spread(q.z)
        };
        let mut order: Vec<usize> = (0..self.list.len()).collect();
        order.sort_by_key(|&i| key(&self.list[i]));
        self.list = order.iter().map(|&i| self.list[i]).collect();
        self.flux = order.iter().map(|&i| self.flux[i]).collect();
        self.depth = order.iter().map(|&i| self.depth[i]).collect();
    }

    fn push(&mut self, vpl: Vpl, flux: f32, depth: u32) {
        let ok = vpl.power.is_finite() && vpl.p.is_finite() && flux.is_finite();
        if ok {
            self.list.push(vpl);
            self.flux.push(flux.max(0.0));
            self.depth.push(depth.min(u8::MAX as u32) as u8);
        }
    }

    /// The emission vertex of a light path from light `light`, weighted by `weight` (1 / its density and
    /// the light's selection probability).
    fn push_emission(&mut self, sh: &Shading<'_>, light: usize, at: &EmitterPoint, weight: f32) {
        use std::f32::consts::PI;
        let lights = &sh.lights;
        let vpl = match *at {
            EmitterPoint::Surface(sp) => {
                // A diffuse area light emits the same radiance toward every lit direction.
                let two_sided = lights.is_two_sided(light);
                let le = lights.emission(light, at, sp.n);
                let power = le * weight;
                let sides = if two_sided { 2.0 } else { 1.0 };
                let v = Vpl {
                    p: sp.p,
                    p_error: sp.p_error,
                    ng: sp.n,
                    ns: sp.n,
                    power,
                    emitter: Emitter::Cosine { two_sided },
                };
                return self.push(v, luminance(power) * PI * sides, 0);
            }
            EmitterPoint::Point(p) => {
                let base = Vpl {
                    p,
                    p_error: Vec3A::ZERO,
                    ng: Vec3A::ZERO,
                    ns: Vec3A::ZERO,
                    power: Spectrum::ZERO,
                    emitter: Emitter::Isotropic,
                };
                if lights.is_point(light) {
                    let i = lights.emission(light, at, Vec3A::Z);
                    Vpl { power: i * weight, ..base }
                } else {
                    Vpl { power: Spectrum::splat(weight), emitter: Emitter::Light { light: light as u32 }, ..base }
                }
            }
            EmitterPoint::Direction(w) => Vpl {
                p: Vec3A::ZERO,
                p_error: Vec3A::ZERO,
                ng: w,
                ns: w,
                power: lights.emission(light, at, w) * weight,
                emitter: Emitter::Directional,
            },
        };
        let flux = match vpl.emitter {
            Emitter::Isotropic => 4.0 * PI * luminance(vpl.power),
            Emitter::Light { .. } => luminance(lights.power(light)) * weight,
            _ => luminance(vpl.power) * PI * lights.world_radius() * lights.world_radius(),
        };
        self.push(vpl, flux, 0);
    }

    /// A surface VPL at `si` with BSDF `bsdf`, light arriving from `wi` with throughput `beta`.
    fn push_surface(
        &mut self,
        si: &SurfaceInteraction,
        bsdf: &Bsdf,
        wi: Vec3A,
        beta: Spectrum,
        depth: u32,
        rho_u: &[[f32; 2]],
    ) {
        // The emitting side is the side the light arrived on. Light carried from a light is importance
        // transport: with shading normals, what the VPL sends toward x is f · |ω_in·n_s| · |ω_x·n_g| / |ω_in·n_g|
        // (pbrt-v3's CorrectShadingNormal at a light subpath's vertex), so the VPL's cosine is about the
        // geometric normal and the constant |ω_in·n_s| / |ω_in·n_g| is in its power.
        let side = if wi.dot(si.ng) >= 0.0 { 1.0 } else { -1.0 };
        let ng = si.ng * side;
        let ns = ng;
        let beta = beta * adjoint_factor(wi, bsdf.shading_normal(), si.ng);
        let lambert =
            bsdf.lobes().all(|(b, _)| matches!(b, Bxdf::Lambertian(_)) || b.flags().contains(BxdfFlags::SPECULAR));
        let rho = bsdf.rho_hd(wi, rho_u);
        let flux = luminance(beta * rho);
        if lambert {
            let r: Spectrum =
                bsdf.lobes().filter_map(|(b, s)| if let Bxdf::Lambertian(l) = b { Some(s * l.r) } else { None }).sum();
            let power = beta * r * std::f32::consts::FRAC_1_PI;
            let v = Vpl { p: si.p, p_error: si.p_error, ng, ns, power, emitter: Emitter::Cosine { two_sided: false } };
            self.push(v, flux, depth);
        } else {
            let index = self.bsdfs.len() as u32;
            self.bsdfs.push(GeneralVpl { bsdf: *bsdf, wi });
            let v = Vpl { p: si.p, p_error: si.p_error, ng, ns, power: beta, emitter: Emitter::Bsdf { index } };
            self.push(v, flux, depth);
        }
    }

    /// Number of VPLs.
    pub fn len(&self) -> usize {
        self.list.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// What VPL `j` sends toward unit direction `w` (leaving it), with light `sh`: see [`Emitter`].
    #[inline]
    fn emitted(&self, sh: &Shading<'_>, vpl: &Vpl, w: Vec3A) -> Spectrum {
        match vpl.emitter {
            Emitter::Cosine { two_sided } => {
                let c = vpl.ng.dot(w);
                if two_sided || c > 0.0 { vpl.power * vpl.ns.dot(w).abs() } else { Spectrum::ZERO }
            }
            Emitter::Isotropic | Emitter::Directional => vpl.power,
            Emitter::Light { light } => vpl.power * sh.lights.emission(light as usize, &EmitterPoint::Point(vpl.p), w),
            Emitter::Bsdf { index } => {
                let g = &self.bsdfs[index as usize];
                vpl.power * g.bsdf.f(w, g.wi, BxdfFlags::ALL) * vpl.ns.dot(w).abs()
            }
        }
    }

    /// I_j(x) of VPL `j` at receiver `x` without visibility, and its shadow ray; `None` when it is 0.
    #[inline]
    pub fn unoccluded(&self, sh: &Shading<'_>, j: usize, x: &Receiver) -> Option<Unoccluded> {
        let value = self.unoccluded_value(sh, j, x)?;
        Some(Unoccluded { value, shadow: self.shadow_ray(j, x) })
    }

    /// I_j(x) of VPL `j` at receiver `x` without visibility; `None` when it is 0.
    #[inline]
    pub fn unoccluded_value(&self, sh: &Shading<'_>, j: usize, x: &Receiver) -> Option<Spectrum> {
        let vpl = &self.list[j];
        if let Emitter::Directional = vpl.emitter {
            let w = vpl.ng;
            let value = vpl.power * x.f(w) * w.dot(x.bsdf.shading_normal()).abs();
            return (value.max_element() > 0.0).then_some(value);
        }
        let d = vpl.p - x.si.p;
        let d2 = d.length_squared();
        if d2.is_nan() || d2 <= 0.0 {
            return None;
        }
        let w = d / d2.sqrt();
        let f = x.f(w);
        if f.max_element() <= 0.0 {
            return None;
        }
        let e = self.emitted(sh, vpl, -w);
        let value = e * f * (w.dot(x.bsdf.shading_normal()).abs() / d2.max(self.clamp2));
        if value.max_element().is_nan() || value.max_element() <= 0.0 {
            return None;
        }
        Some(value)
    }

    /// The shadow ray from receiver `x` to VPL `j` (along a directional VPL's direction, unbounded).
    #[inline]
    pub fn shadow_ray(&self, j: usize, x: &Receiver) -> Ray {
        let vpl = &self.list[j];
        if let Emitter::Directional = vpl.emitter {
            return x.si.spawn_ray(vpl.ng);
        }
        let Some(ends) = self.ends.get(j) else {
            return spawn_ray_to(&x.si, &SurfacePoint { p: vpl.p, p_error: vpl.p_error, n: vpl.ng });
        };
        // `spawn_ray_to` with both offsets chosen from the precomputed pairs: offset_ray_origin flips its
        // offset exactly when the direction's dot product with the normal is negative.
        let origin = x.origins[((vpl.p - x.si.p).dot(x.si.ng) < 0.0) as usize];
        let target = ends[((origin - vpl.p).dot(vpl.ng) < 0.0) as usize];
        Ray { o: origin, d: target - origin, t_max: 1.0 - SHADOW_EPSILON }
    }

    /// I_j(x) with visibility (one shadow ray when the unoccluded value is not 0).
    #[inline]
    pub fn contribution(
        &self,
        scene: &Scene,
        sh: &Shading<'_>,
        j: usize,
        x: &Receiver,
        rays: &mut RayCounters,
    ) -> Spectrum {
        match self.unoccluded(sh, j, x) {
            Some(u) => {
                rays.shadow += 1;
                if scene.geometry.occluded(&u.shadow) { Spectrum::ZERO } else { u.value }
            }
            None => Spectrum::ZERO,
        }
    }

    /// Luminance of an upper bound of VPL `j`'s unoccluded contribution anywhere within distance `radius`
    /// of the receiver `x` (the B distribution, ALGORITHMS.md §6.3 after \[BZ\] `evalBoundedGeometricFactor`):
    /// the distance shortened by `radius` (then clamped by d_c), the VPL's cosine widened by the angle the
    /// region subtends, the receiver's cosine bounded by 1, the receiver's BSDF at the actual direction, a
    /// glossy VPL's BSDF at the direction of the region nearest its lobe's axis (`glossy_bound`; a choice
    /// beyond \[BZ\], whose VPLs are Lambertian).
    pub fn bound(&self, sh: &Shading<'_>, j: usize, x: &Receiver, radius: f32) -> f32 {
        let vpl = &self.list[j];
        if let Emitter::Directional = vpl.emitter {
            return luminance(vpl.power * x.f(vpl.ng));
        }
        let d = vpl.p - x.si.p;
        let dist = d.length();
        if dist.is_nan() || dist <= 0.0 {
            return 0.0;
        }
        let w = d / dist;
        let f = x.f(w);
        if f.max_element() <= 0.0 {
            return 0.0;
        }
        let near = (dist - radius).max(0.0);
        // cos(max(0, θ − δ)) with θ the VPL-side angle (cos θ = `cos`) and δ = asin(min(1, R/d)) the angle the
        // region subtends, without trigonometric calls: cos(θ − δ) = cos θ cos δ + sin θ sin δ when θ > δ.
        let sin_d = (radius / dist).min(1.0);
        let cos_d = (1.0 - sin_d * sin_d).max(0.0).sqrt();
        let widened = |cos: f32| {
            let cos = cos.clamp(-1.0, 1.0);
            if cos >= cos_d { 1.0 } else { (cos * cos_d + (1.0 - cos * cos).max(0.0).sqrt() * sin_d).max(0.0) }
        };
        let e = match vpl.emitter {
            Emitter::Cosine { two_sided } => {
                let c = vpl.ns.dot(-w);
                vpl.power * widened(if two_sided { c.abs() } else { c })
            }
            Emitter::Bsdf { index } => {
                let g = &self.bsdfs[index as usize];
                vpl.power * glossy_bound(g, -w, sin_d, cos_d) * widened(vpl.ns.dot(-w).abs())
            }
            _ => self.emitted(sh, vpl, -w),
        };
        let b = luminance(e * f) / (near * near).max(self.clamp2);
        if b.is_finite() { b.max(0.0) } else { 0.0 }
    }

    /// Bytes the VPL set occupies.
    pub fn bytes(&self) -> usize {
        self.list.len() * (std::mem::size_of::<Vpl>() + 4) + self.bsdfs.len() * std::mem::size_of::<GeneralVpl>()
    }

    /// Bytes a set of `count` VPLs may occupy (every one with its own BSDF).
    pub fn bytes_for(count: usize) -> usize {
        count * (std::mem::size_of::<Vpl>() + 4 + std::mem::size_of::<GeneralVpl>())
    }
}

/// A bound of what a surface VPL `g` reflects toward the directions within angle δ (sin δ = `sin_d`,
/// cos δ = `cos_d`) of unit `out`: the larger of f toward `out` and toward the direction of that cone
/// nearest the mirror direction of the light's arrival (the axis of a glossy lobe; the axis itself when the
/// cone holds it). For B: a cache's region seen from a glossy VPL spans such a cone, and the VPL's beam may
/// light part of the region while missing the cache itself (a bathroom blind 0.19 from a tile's VPL whose
/// 24° beam held the shading point, not its one cache 0.11 away: F = U = B = 0 there, a draw by C alone
/// worth 2343 against a pixel of 0.48).
fn glossy_bound(g: &GeneralVpl, out: Vec3A, sin_d: f32, cos_d: f32) -> Spectrum {
    let f = g.bsdf.f(out, g.wi, BxdfFlags::ALL);
    if sin_d <= 0.0 {
        return f;
    }
    let n = g.bsdf.shading_normal();
    let axis = 2.0 * g.wi.dot(n) * n - g.wi;
    let c = out.dot(axis);
    let toward = if c >= cos_d {
        axis
    } else {
        // The cone's direction nearest the axis: `out` turned by δ toward it.
        let e = (axis - c * out).normalize_or_zero();
        if e == Vec3A::ZERO {
            return f;
        }
        cos_d * out + sin_d * e
    };
    f.max(g.bsdf.f(toward, g.wi, BxdfFlags::ALL))
}

/// Test set-up of the importance-caching unit tests: the scene of pbrt text `text`, its shading and the
/// flux-proportional light selection that VPL generation reads, handed to `f` (they borrow the loaded scene).
#[cfg(test)]
pub(crate) fn with_lit_scene<T>(text: &str, f: impl FnOnce(&Scene, &Shading<'_>, &LightSelect) -> T) -> T {
    let options = crate::scene::LoadOptions::default();
    let loaded = crate::scene::load_str(text, std::path::Path::new("test.pbrt"), options).unwrap();
    let sh = Shading::build(&loaded.scene, true, &mut crate::error::Warnings::default()).unwrap();
    let select = LightSelect::new(&sh.lights, "power").unwrap();
    f(&loaded.scene, &sh, &select)
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::scene::{LoadOptions, load_str};

    /// A floor, a wall facing it and a lamp: VPLs on all three.
    const ROOM: &str = "LookAt 0 3 -4 0 0 0 0 1 0\nCamera \"perspective\"\nWorldBegin\n\
        Material \"matte\" \"rgb Kd\" [0.7 0.6 0.5]\n\
        Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-2 0 -2  2 0 -2  2 0 2  -2 0 2]\n\
        Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-2 0 2  2 0 2  2 3 2  -2 3 2]\n\
        AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [5 5 5]\n\
        Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-0.5 2.5 -0.5  0.5 2.5 -0.5  0.5 2.5 0.5  -0.5 2.5 0.5]\n\
        AttributeEnd\nLightSource \"point\" \"point from\" [1 1 -1] \"rgb I\" [2 2 2]\nWorldEnd\n";

    #[test]
    fn the_glossy_bound_reaches_the_lobe_a_region_holds() {
        // Light arriving 30° from the normal: the lobe's axis is the mirror direction, 30° the other way.
        let n = Vec3A::Z;
        let wi = Vec3A::new(0.5, 0.0, 0.75f32.sqrt());
        let g = GeneralVpl { bsdf: crate::application::importance::split::glossy(0.1, n), wi };
        let axis = Vec3A::new(-0.5, 0.0, 0.75f32.sqrt());
        let f = |w: Vec3A| luminance(g.bsdf.f(w, wi, BxdfFlags::ALL));
        // Toward a cache 25° from the axis, with a region seen 15° wide, or none.
        let out = Vec3A::new((-5f32).to_radians().sin(), 0.0, (-5f32).to_radians().cos());
        let (sin_d, cos_d) = (15f32.to_radians().sin(), 15f32.to_radians().cos());
        assert_eq!(luminance(glossy_bound(&g, out, 0.0, 1.0)), f(out), "no region: f itself");
        let b = luminance(glossy_bound(&g, out, sin_d, cos_d));
        assert!(b > 5.0 * f(out), "the region reaches 10° from the axis: {b} vs {}", f(out));
        // It bounds f over the region's directions, up to the lobe's asymmetry about its axis.
        let mut rng = Rng::new(4);
        let mut most = 0.0f32;
        for _ in 0..20_000 {
            let w = crate::sampling::warp::uniform_sphere(rng.uniform2());
            if w.dot(out) >= cos_d {
                most = most.max(f(w));
            }
        }
        assert!(most > 0.0 && most <= 1.05 * b, "sampled {most}, bound {b}");
        // A region that holds the axis: the peak.
        let wide = (30f32.to_radians().sin(), 30f32.to_radians().cos());
        assert_eq!(luminance(glossy_bound(&g, out, wide.0, wide.1)), f(axis).max(f(out)));
    }

    #[test]
    fn the_lambertian_shortcut_equals_the_bsdf() {
        use crate::shading::bxdf::lambert::LambertianReflection;
        let n = Vec3A::new(0.1, 0.2, 1.0).normalize();
        let mut bsdf = Bsdf::new(n, n, Vec3A::X, 1.0);
        bsdf.add(Bxdf::Lambertian(LambertianReflection { r: Spectrum::splat(0.6) }));
        let si = SurfaceInteraction { ng: n, ns: n, ..dummy_interaction() };
        let x = Receiver::new(si, bsdf, Vec3A::new(0.3, -0.1, 0.9).normalize());
        assert!(x.lambert.is_some());
        let mut rng = Rng::new(2);
        for _ in 0..1000 {
            let [a, b] = rng.uniform2();
            let w = crate::sampling::warp::uniform_sphere([a, b]);
            let (a, b) = (x.f(w), bsdf.f(x.wo, w, BxdfFlags::ALL));
            assert!((a - b).abs().max_element() <= 1e-6 * b.max_element(), "{w:?}: {a:?} vs {b:?}");
        }
    }

    #[test]
    fn shadow_rays_from_the_precomputed_ends_are_spawn_ray_to_s() {
        with_lit_scene(ROOM, |scene, sh, select| {
            let v = Vpls::generate(scene, sh, select, 1000, 5, 0.05, &mut Rng::new(7));
            assert_eq!(v.ends.len(), v.len());
            let mut rng = Rng::new(8);
            for k in 0..40 {
                // Receivers on the floor and on the wall; VPLs on both sides of each (the point light's have no
                // normal).
                let [a, b] = rng.uniform2();
                let ray = if k % 2 == 0 {
                    Ray::new(Vec3A::new(3.8 * a - 1.9, 1.0, 3.8 * b - 1.9), -Vec3A::Y)
                } else {
                    Ray::new(Vec3A::new(3.8 * a - 1.9, 2.9 * b + 0.05, 0.0), Vec3A::Z)
                };
                let si = scene.geometry.intersect(&ray).unwrap();
                let x = Receiver::new(si, sh.bsdf(&si).unwrap(), crate::sampling::warp::uniform_sphere(rng.uniform2()));
                for (j, vpl) in v.list.iter().enumerate() {
                    if let Emitter::Directional = vpl.emitter {
                        continue;
                    }
                    let (fast, plain) = (
                        v.shadow_ray(j, &x),
                        spawn_ray_to(&x.si, &SurfacePoint { p: vpl.p, p_error: vpl.p_error, n: vpl.ng }),
                    );
                    let bits = |r: &Ray| [r.o.to_array(), r.d.to_array()].map(|v| v.map(f32::to_bits));
                    assert_eq!(bits(&fast), bits(&plain), "receiver {k}, VPL {j}");
                    assert_eq!(fast.t_max, plain.t_max);
                }
            }
        });
    }

    fn dummy_interaction() -> SurfaceInteraction {
        let loaded = load_str(ROOM, Path::new("room.pbrt"), LoadOptions::default()).unwrap();
        loaded.scene.geometry.intersect(&Ray::new(Vec3A::new(0.1, 1.0, 0.2), -Vec3A::Y)).unwrap()
    }

    #[test]
    fn the_bound_holds_over_the_region_and_generation_is_deterministic() {
        with_lit_scene(ROOM, |scene, sh, select| {
            let make = |seed| Vpls::generate(scene, sh, select, 500, 5, 0.05, &mut Rng::new(seed));
            let v = make(3);
            assert_eq!(v.len(), 500);
            assert_eq!(v.list, make(3).list, "same seed, same VPLs");
            assert_ne!(v.list, make(4).list);
            assert!(v.list.iter().any(|p| matches!(p.emitter, Emitter::Isotropic)));
            assert!(v.list.iter().any(|p| matches!(p.emitter, Emitter::Cosine { .. }) && p.p.y < 2.4));
            // Receivers on the floor: a centre x and points within `radius` of it. For Lambertian receivers and
            // cosine or isotropic VPLs the bound at x is an upper bound of the unoccluded contribution there.
            let floor = |px: f32, pz: f32| {
                let si = scene.geometry.intersect(&Ray::new(Vec3A::new(px, 1.0, pz), -Vec3A::Y)).unwrap();
                Receiver::new(si, sh.bsdf(&si).unwrap(), Vec3A::new(0.0, 1.0, -1.0).normalize())
            };
            let mut rng = Rng::new(9);
            for (cx, cz, radius) in [(0.013, 0.021, 0.3), (-1.0, 1.2, 0.6), (1.5, -1.37, 0.1)] {
                let x = floor(cx, cz);
                for _ in 0..20 {
                    let [a, b] = rng.uniform2();
                    let (r, phi) = (radius * a.sqrt(), std::f32::consts::TAU * b);
                    let y = floor(cx + r * phi.cos(), cz + r * phi.sin());
                    for j in 0..v.len() {
                        let at_y = v.unoccluded(sh, j, &y).map_or(0.0, |u| luminance(u.value));
                        let bound = v.bound(sh, j, &x, radius);
                        assert!(
                            at_y <= bound * (1.0 + 1e-4) + 1e-9,
                            "VPL {j} ({:?}): {at_y} > {bound}",
                            v.list[j].emitter
                        );
                    }
                }
            }
        });
    }
}
