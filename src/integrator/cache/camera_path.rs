//! STAGE 7 (integrator): the camera's path to the surfaces the caches shade (issue 41).
//!
//! A sub-pixel sample's camera ray passes through surfaces without a material, as every integrator's does.
//! Where the application's plan asks for it ([`CachePlan::follow_specular`]), the path also follows perfect
//! specular reflection and transmission as pbrt-v3's `directlighting` does (`SpecularReflect` and
//! `SpecularTransmit` at every vertex, both branches, up to [`SPECULAR_DEPTH`] vertices), and each vertex
//! with a non-specular lobe becomes a [`Vertex`] for the caches to shade, weighted by the specular
//! throughput that reached it. Glass and mirrors seen from the camera then show what they reflect and
//! transmit instead of black. Where the plan asks for it ([`CachePlan::shows_environment`]) a path that
//! leaves the scene takes the infinite lights' radiance, and a purely specular vertex that emits adds its
//! emission (other vertices' emission is the application's to add, as at the camera's own hit).
//!
//! With neither asked for, the one vertex is the camera ray's first hit with a material, exactly as
//! [`crate::gbuffer::shading_point`] finds it, so such an application's images do not change.
//!
//! Depends on `scene`, `gbuffer` (the shading point) and `shading` (BSDFs and lights); never on placement
//! or an application.

use glam::Vec3A;

use crate::application::CachePlan;
use crate::error::{Result, Warnings};
use crate::gbuffer::ShadingPoint;
use crate::scene::Scene;
use crate::scene::ray::{Ray, RayCounters};
use crate::shading::Spectrum;
use crate::shading::bxdf::BxdfFlags;
use crate::shading::lighting::{MAX_PASS_THROUGH, Shading};

/// Most vertices a camera path has, the camera's hit included: pbrt-v3 `directlighting`'s default
/// `maxdepth`, whose specular bounces it follows while `depth + 1 < maxdepth`.
pub const SPECULAR_DEPTH: u32 = 5;

/// A vertex of a camera path that the caches shade.
#[derive(Clone, Copy, Debug)]
pub struct Vertex {
    /// The specular throughput from the camera to here (1 at the camera's own hit).
    pub weight: Spectrum,
    /// The surface, its normals faced toward the previous vertex.
    pub point: ShadingPoint,
    /// Its order among the sample's vertices: vertex 0 shades with the sample's own random stream (so a
    /// path that ends at the camera's hit draws what it drew before paths were followed), the others with
    /// streams of their own.
    pub index: u32,
    /// Specular bounces before it (0: the camera's own hit).
    pub bounces: u32,
}

/// What the camera paths of a render did, for `--stats`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct PathCounts {
    /// Sub-pixel samples traced.
    pub samples: u64,
    /// Specular bounces followed.
    pub specular_bounces: u64,
    /// Vertices shaded that a specular bounce led to (not the camera's own hit).
    pub after_specular: u64,
    /// Of all vertices shaded, those no cache was near enough to: shaded by the application's per-sample
    /// estimator instead.
    pub by_estimator: u64,
    /// Paths that left the scene.
    pub escaped: u64,
}

impl PathCounts {
    /// Adds another count.
    pub fn add(&mut self, o: &PathCounts) {
        self.samples += o.samples;
        self.specular_bounces += o.specular_bounces;
        self.after_specular += o.after_specular;
        self.by_estimator += o.by_estimator;
        self.escaped += o.escaped;
    }
}

/// Traces camera paths in one scene for one application's plan.
pub struct CameraPaths<'a, 's> {
    scene: &'s Scene,
    /// BSDFs and lights, the application's (`borrowed`) or built here; `None` for both when the plan
    /// follows nothing and adds nothing.
    borrowed: Option<&'a Shading<'s>>,
    owned: Option<Shading<'s>>,
    follow_specular: bool,
    environment: bool,
}

impl<'a, 's> CameraPaths<'a, 's> {
    /// The paths `plan` asks for in `scene`, reading BSDFs and lights from `shading` (the application's
    /// own) when given; else they are built here, only when the plan asks for any (their warnings are the
    /// application's to give, so they are dropped here).
    pub fn new(scene: &'s Scene, plan: &CachePlan, shading: Option<&'a Shading<'s>>) -> Result<Self> {
        let (follow_specular, environment) = (plan.follow_specular, plan.shows_environment);
        let wanted = follow_specular || environment;
        let owned = match shading {
            None if wanted => Some(Shading::build(scene, false, &mut Warnings::default())?),
            _ => None,
        };
        let borrowed = shading.filter(|_| wanted);
        Ok(CameraPaths { scene, borrowed, owned, follow_specular, environment })
    }

    /// The shading data the paths read, if the plan needs any.
    fn shading(&self) -> Option<&Shading<'s>> {
        self.borrowed.or(self.owned.as_ref())
    }

    /// Traces the camera ray `ray` (from the camera at `eye`): writes the vertices to shade into `out`
    /// (cleared first) and returns the radiance the path gathered on its own (escaped rays, emitters at
    /// purely specular vertices).
    pub fn trace(
        &self,
        ray: Ray,
        eye: Vec3A,
        out: &mut Vec<Vertex>,
        counts: &mut PathCounts,
        rays: &mut RayCounters,
    ) -> Spectrum {
        out.clear();
        counts.samples += 1;
        rays.camera += 1;
        self.walk(ray, eye, 0.0, Spectrum::ONE, 0, out, counts, rays)
    }

    /// The path from `ray` on, `depth` vertices already behind it, `travelled` from the camera to `from`,
    /// carrying `weight`.
    #[allow(clippy::too_many_arguments)]
    fn walk(
        &self,
        mut ray: Ray,
        from: Vec3A,
        travelled: f32,
        weight: Spectrum,
        depth: u32,
        out: &mut Vec<Vertex>,
        counts: &mut PathCounts,
        rays: &mut RayCounters,
    ) -> Spectrum {
        for _ in 0..MAX_PASS_THROUGH {
            let Some(si) = self.scene.geometry.intersect(&ray) else {
                counts.escaped += 1;
                return match self.shading() {
                    Some(sh) if self.environment => weight * sh.lights.le_escaped(&ray),
                    _ => Spectrum::ZERO,
                };
            };
            if self.scene.is_null_material(si.material) {
                ray = si.spawn_ray(ray.d);
                continue;
            }
            let wo = -ray.d.normalize();
            let point = ShadingPoint::at_hit(&si, wo, travelled + (si.p - from).length());
            let index = out.len() as u32;
            // A material that cannot be specular needs no BSDF here: the vertex is the caches' to shade.
            let follows = |sh: &&Shading<'_>| self.follow_specular && sh.materials.may_be_specular(si.material);
            let Some(sh) = self.shading().filter(follows) else {
                counts.after_specular += u64::from(depth > 0);
                out.push(Vertex { weight, point, index, bounces: depth });
                return Spectrum::ZERO;
            };
            // Smooth glass as two lobes, reflection and transmission, as `directlighting` has it, whatever
            // the application's own shading uses.
            let bsdf = sh.materials.bsdf_with(si.material, &si, &sh.textures, false);
            let specular = bsdf.is_some_and(|b| b.lobes().any(|(l, _)| l.flags().contains(BxdfFlags::SPECULAR)));
            let mut l = Spectrum::ZERO;
            if !specular || bsdf.is_some_and(|b| b.num_components(BxdfFlags::NON_SPECULAR) > 0) {
                counts.after_specular += u64::from(depth > 0);
                out.push(Vertex { weight, point, index, bounces: depth });
            } else if self.environment {
                l += weight * sh.lights.emitted(&si, wo);
            }
            let Some(bsdf) = bsdf.filter(|_| specular && depth + 1 < SPECULAR_DEPTH) else { return l };
            for lobe in [BxdfFlags::REFLECTION, BxdfFlags::TRANSMISSION] {
                let Some(bs) = bsdf.sample_f(wo, [0.5, 0.5], lobe | BxdfFlags::SPECULAR) else { continue };
                let cos = bs.wi.dot(bsdf.shading_normal()).abs();
                if bs.pdf <= 0.0 || bs.f == Spectrum::ZERO || cos == 0.0 {
                    continue;
                }
                counts.specular_bounces += 1;
                rays.camera += 1;
                let next = weight * bs.f * (cos / bs.pdf);
                l += self.walk(si.spawn_ray(bs.wi), si.p, point.depth, next, depth + 1, out, counts, rays);
            }
            return l;
        }
        Spectrum::ZERO
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{LoadOptions, load_str};

    fn scene(world: &str) -> Scene {
        let text = format!(
            "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [30]\nFilm \"image\" \"integer xresolution\" [8] \"integer yresolution\" [8]\nWorldBegin\n{world}\nWorldEnd\n"
        );
        load_str(&text, std::path::Path::new("t.pbrt"), LoadOptions::default()).expect("loads").scene
    }

    fn plan(follow_specular: bool, shows_environment: bool) -> CachePlan {
        CachePlan { follow_specular, shows_environment, ..CachePlan::default() }
    }

    fn trace(s: &Scene, p: &CachePlan) -> (Spectrum, Vec<Vertex>, PathCounts) {
        let paths = CameraPaths::new(s, p, None).unwrap();
        let ray = s.camera.generate_ray([4.0, 4.0], [0.5, 0.5]);
        let (mut out, mut counts, mut rays) = (Vec::new(), PathCounts::default(), RayCounters::default());
        let l = paths.trace(ray, s.camera.position(), &mut out, &mut counts, &mut rays);
        (l, out, counts)
    }

    const BACKDROP: &str = "Material \"matte\"\nShape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-50 -50 -10  50 -50 -10  50 50 -10  -50 50 -10]";

    #[test]
    fn a_mirror_hands_the_caches_what_it_reflects_and_glass_both_branches() {
        let sky = "LightSource \"infinite\" \"rgb L\" [0.5 0.5 0.5]";
        // A mirror facing the camera reflects the camera's side, where nothing is: the path escapes.
        let mirror = "Material \"mirror\"\nShape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-5 -5 0  5 -5 0  5 5 0  -5 5 0]";
        let s = scene(&format!("{sky}\n{mirror}"));
        let (l, out, counts) = trace(&s, &plan(true, true));
        assert!(out.is_empty(), "a mirror has no non-specular lobe");
        assert_eq!(counts.specular_bounces, 1);
        assert_eq!(counts.escaped, 1);
        assert!((l.max_element() - 0.45).abs() < 0.06, "the sky seen in a mirror of reflectance 0.9: {l:?}");
        // Without following, the mirror itself is the vertex and nothing is gathered.
        let (l, out, _) = trace(&s, &plan(false, false));
        assert_eq!((l, out.len()), (Spectrum::ZERO, 1));
        // Glass in front of a matte backdrop: the transmitted branch reaches the backdrop (weighted by the
        // glass's transmittance), the reflected one escapes.
        let glass = "Material \"glass\"\nShape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-5 -5 0  5 -5 0  5 5 0  -5 5 0]";
        let s = scene(&format!("{sky}\n{glass}\n{BACKDROP}"));
        let (_, out, counts) = trace(&s, &plan(true, true));
        assert_eq!(counts.specular_bounces, 2);
        assert_eq!(out.len(), 1, "the backdrop, through the glass");
        assert!(out[0].point.p.z < -9.9 && out[0].bounces == 1 && counts.after_specular == 1);
        // Entering glass of η 1.5 head-on transmits 1 − F = 0.96 of the radiance, scaled by (1 / 1.5)² as
        // pbrt-v3 scales radiance across an interface: 0.427.
        let t = out[0].weight.max_element();
        assert!((t - 0.96 / 2.25).abs() < 0.01, "{t}");
    }

    #[test]
    fn an_escaped_path_shows_the_environment_only_when_asked() {
        let s = scene("LightSource \"infinite\" \"rgb L\" [0.25 0.5 1]");
        let (l, out, counts) = trace(&s, &plan(true, true));
        assert!(out.is_empty() && counts.escaped == 1);
        assert_eq!(l, Spectrum::new(0.25, 0.5, 1.0));
        let (l, _, _) = trace(&s, &plan(true, false));
        assert_eq!(l, Spectrum::ZERO);
    }

    #[test]
    fn a_diffuse_hit_is_the_gbuffer_point() {
        let s = scene(BACKDROP);
        for p in [plan(false, false), plan(true, true)] {
            let (_, out, _) = trace(&s, &p);
            let g = crate::gbuffer::shading_point(&s, [4.0, 4.0]).unwrap();
            assert_eq!(out.len(), 1);
            assert_eq!(out[0].point, g);
            assert_eq!(out[0].weight, Spectrum::ONE);
        }
    }
}
