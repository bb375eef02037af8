//! STAGE 5 (application): WHAT a cache holds — one module per cache-based application (DESIGN.md §2), and
//! [`registry`], the one list of them by the integrator names users type. An application reads its own
//! parameters, computes a record at a cache site (value plus per-sample gathering data), compares two records
//! (for the second-stage placement strategies), shades a sample from its selected caches, and gives the
//! brute-force answer the cache approximates. Placement never sees the record type, so every strategy works
//! with every application.
//!
//! Adding an application: one file here implementing [`Application`] and one line in [`registry`]; the
//! cache driver (`integrator::cache`), `render --help`, `info` and `experiment` pick it up
//! from there.
//!
//! An application prepares what it reads from the scene once per render ([`Application::prepare`]: for
//! irradiance caching the lights, materials and textures) and every other call reads that, so the cache
//! driver never needs to know what an application shades with.
//!
//! The trait is what the cache driver needs, plus one value for the studies:
//! - *identity and parameters*: `NAME`, `ABOUT`, `PARAMETERS` (each declared once as a
//!   `parse::integrator::ParamDef`, read with its typed getters), and `PAPER_CACHES`, which stays on the trait
//!   because the driver's default budget `caches` scales it;
//! - *the records*: `from_params` (which resolves the defaults that scale with the scene from its length
//!   scale L, `gbuffer::scale::SceneScale`), `prepare`, `compute_record`, `diff`, `finish_record`, `shade`,
//!   `reference`, `record_bytes`, `record_bytes_bound`, and the `--stats` report (`settings`,
//!   `prepared_report`, `scale_derived`);
//! - [`Application::plan`]: a [`CachePlan`], what these settings ask of the driver beyond caches. It holds the
//!   three hooks that each served one application, now generic fields named for what the driver does:
//!   `DGS_GEOMETRY` became `dgs_geometry` (importance caching: off), `without_caches` became
//!   `shade_by_reference` (importance caching's `sampling uniform|power`), `per_pixel_term` became
//!   `added_per_pixel` (irradiance caching's `output full`). They depend on the settings (or may), so they are
//!   one value made from the resolved application rather than three trait items.
//! - [`Application::STUDY`]: a [`Study`], what the studies (goldens, experiments, stability tests) know of the
//!   application and the driver never reads: `QUICK` became `Study::quick`, `PER_SAMPLE` became
//!   `Study::per_sample`, and `baselines()` became `Study::baselines`, a function of the resolved application.
//!   The registry copies the data into its [`registry::Entry`], so the studies read it by name.
//!
//! Depends on `scene`, `gbuffer`, `sampling`, `shading` (its estimators in `shading::lighting`) and the
//! parameter reader `parse::integrator`; never on `placement` or the cache driver.

pub mod ambient_occlusion;
pub mod importance;
pub mod irradiance;
pub mod registry;

use glam::Vec3A;

use crate::error::{Result, Warnings};
use crate::gbuffer::ShadingPoint;
use crate::gbuffer::scale::SceneScale;
use crate::parse::integrator::{IntegratorParams, Parameter};
use crate::sampling::{Rng, Stratum};
use crate::scene::Scene;
use crate::scene::ray::RayCounters;
use crate::shading::lighting::Shading;

/// One cache selected for a shading point (ALGORITHMS.md §5): its record, where it is, and its
/// interpolation weight.
#[derive(Clone, Copy, Debug)]
pub struct Neighbour<'a, R> {
    /// The cache's record.
    pub record: &'a R,
    /// The cache's position.
    pub p: Vec3A,
    /// The cache's unit shading normal (faced toward the camera).
    pub n: Vec3A,
    /// The interpolation weight 1 / Dist (Eq. 5); Σ over the selection > 0.
    pub weight: f32,
}

/// What shading at a cache's site makes of its neighbours against the cache alone ([`Application::predict`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeaveOneOut {
    /// The value shading gives there from the neighbours; its expectation where shading draws.
    pub from_others: [f32; 3],
    /// The value shading gives there from the cache alone.
    pub alone: [f32; 3],
    /// The variance of a pixel's value there (the mean of its sub-pixel samples) from the neighbours about
    /// `from_others`, the colour channels' mean (0 where shading draws nothing).
    pub variance: f32,
    /// The same from the cache alone: the noise a pixel there keeps however many caches are added.
    pub own_variance: f32,
    /// The part of the expected squared difference of the two values (the colour channels' mean) that the
    /// records' own estimation noise makes (their gathering), not their placement: 0 where records are exact
    /// or their noise is not measured.
    pub records_noise: f32,
    /// The noise a pixel's error against the per-sample reference keeps there whatever the placement, beyond
    /// shading's own draws (the variances above): the records' noise its blend carries and the reference's
    /// own noise (the mean of its sub-pixel samples about its expectation), the colour channels' mean; 0
    /// where both are exact or not measured.
    pub kept_noise: f32,
}

impl LeaveOneOut {
    /// A prediction of an application whose shading draws nothing: the two values, no variance.
    pub fn values(from_others: [f32; 3], alone: [f32; 3]) -> Self {
        LeaveOneOut { from_others, alone, variance: 0.0, own_variance: 0.0, records_noise: 0.0, kept_noise: 0.0 }
    }
}

/// The per-pixel integrator an application's images can be compared with (`experiment --ao-samples`): its
/// name, the parameters that make it compute the same quantity, the parameter that takes the ray count,
/// and the factor that brings its values to the application's scale.
#[derive(Clone, Debug, PartialEq)]
pub struct Baseline {
    /// Short label of its rows in experiment results (`ao` gives rows `ao:N`).
    pub label: &'static str,
    /// Per-pixel integrator name (`ambientocclusion`).
    pub integrator: &'static str,
    /// Parameters matching the application's settings (e.g. the ray length).
    pub set: Vec<(String, String)>,
    /// The parameter that sets the rays per pixel sample (`nsamples`).
    pub samples: &'static str,
    /// Multiplies the per-pixel image to the application's units.
    pub scale: f32,
}

/// How to render the application's own estimator per pixel, with fewer samples than its reference: the
/// placement `none` (every sub-pixel sample shaded by [`Application::reference`]) with these settings and
/// `count` set to the sample count. The images estimate exactly the quantity of the reference and of the
/// cache images, so an experiment can put this per-pixel integrator on the same error-versus-time axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PerSample {
    /// The parameter that sets the samples of one pixel sample (`gather`: gather² directions; `draws`).
    pub count: &'static str,
    /// Settings beside it that make the render per-pixel (e.g. a sampling mode without caches).
    pub set: &'static [(&'static str, &'static str)],
}

/// A per-pixel integrator whose image is added to the cached one ([`CachePlan::added_per_pixel`]). It
/// renders with the scene's Sampler and PixelFilter, as it would on its own.
#[derive(Clone, Debug, PartialEq)]
pub struct PerPixelTerm {
    /// The per-pixel integrator's name (`directlighting`).
    pub integrator: &'static str,
    /// Its parameters.
    pub set: Vec<(String, String)>,
}

/// What a cache-based render with an application's settings asks of the cache driver beyond placing caches
/// and shading from them ([`Application::plan`]). Every field is generic — any application may ask for it —
/// and the default asks for nothing.
#[derive(Clone, Debug, PartialEq)]
pub struct CachePlan {
    /// Whether the `vgc+dgs` placement's discontinuity map has the geometry term G′ (Eq. 3) beside the
    /// record differences (the ablations `vgc+dgs:diff` and `vgc+dgs:geom` fix their terms whatever this
    /// says). Importance caching turns it off: the paper found it does better without.
    pub dgs_geometry: bool,
    /// Whether the `refine` placement's map has the leave-one-out term (where a cache's neighbours predict it
    /// badly, [`Application::predict`]); refine's error estimate, for a target error, asks
    /// [`Application::predict`] whatever this says. Importance caching turns it off: measured, the term
    /// moved none of its stability-map cells beyond their seeds' spread and made its placement stages
    /// 1.19–1.29× as long (experiments/notes/refine.md).
    pub refine_misses: bool,
    /// `Some(why)` when these settings are a per-sample estimator that reads no caches: the driver places
    /// none, shades every sample with [`Application::reference`] whatever the placement, and notes `why`
    /// (importance caching's many-light baselines, `sampling uniform` or `power`).
    pub shade_by_reference: Option<String>,
    /// A per-pixel integrator whose image the driver adds to the cached one and to the per-sample reference
    /// (irradiance caching's `output full`: the emitted and direct light that its caches, holding indirect
    /// light only, leave out).
    pub added_per_pixel: Option<PerPixelTerm>,
    /// Whether camera paths follow perfect specular reflection and transmission (as pbrt-v3's
    /// `directlighting` does) and the caches shade the first non-specular vertices, weighted by the
    /// specular throughput: the light the application computes is seen in mirrors and through glass.
    pub follow_specular: bool,
    /// Whether a camera path that leaves the scene takes the infinite lights' radiance (and an emitter at a
    /// purely specular vertex its emission): the application's image is everything the camera sees, not
    /// only what reaches surfaces. Off where an added per-pixel term already shows it.
    pub shows_environment: bool,
    /// Whether each record takes a lesson from its neighbours once placement is over
    /// ([`Application::lesson`]).
    pub learns: bool,
}

impl Default for CachePlan {
    fn default() -> Self {
        CachePlan {
            dgs_geometry: true,
            refine_misses: true,
            shade_by_reference: None,
            added_per_pixel: None,
            follow_specular: false,
            shows_environment: false,
            learns: false,
        }
    }
}

/// What the studies know of an application and the cache driver never reads ([`Application::STUDY`]): the
/// golden matrix and the stability tests render with `quick`; experiments chart `per_sample` and the
/// `baselines` beside the cache methods.
#[derive(Debug)]
pub struct Study<A> {
    /// Parameter settings (`--set` pairs) that make a small render (64×48, the default budget) take about
    /// a second on two cores with the same estimator — fewer gather directions or light samples, never a
    /// different method.
    pub quick: &'static [(&'static str, &'static str)],
    /// The per-pixel form of the application's own estimator at a given sample count, if it has one.
    pub per_sample: Option<PerSample>,
    /// The per-pixel integrators computing the same image as the resolved application (none, one, or
    /// several compared side by side); the first is the one an experiment renders converged.
    pub baselines: fn(&A) -> Vec<Baseline>,
}

impl<A> Study<A> {
    /// No quick settings, no per-sample form, no baselines.
    pub const NONE: Self = Study { quick: &[], per_sample: None, baselines: no_baselines::<A> };
}

fn no_baselines<A>(_: &A) -> Vec<Baseline> {
    Vec::new()
}

/// A cache-based rendering application.
///
/// The driver calls, in order: [`Application::from_params`], [`Application::prepare`], then
/// [`Application::compute_record`] at every cache site (and [`Application::diff`] between records while
/// placing), [`Application::finish_record`] once placement is over, and [`Application::shade`] at every
/// sub-pixel sample — or [`Application::reference`] at every sub-pixel sample for the per-sample reference.
pub trait Application: Sync + Sized {
    /// The integrator name users type (in the scene's `Integrator` line or `--integrator`).
    const NAME: &'static str;
    /// One line saying what the integrator renders (for `--help`, `info` and error messages).
    const ABOUT: &'static str;
    /// The application's own parameters (beside the cache driver's generic ones); its page in docs/integrators/ has the same
    /// table under the application's name.
    const PARAMETERS: &'static [Parameter];

    /// The parameter whose value is pbrt-v3 `path`'s `maxdepth` − 1 (the surface vertices of a light path
    /// beyond the receiver), if the application carries light along paths: a render that replaces a
    /// scene's `path`, `volpath` or `bdpt` takes it from that integrator's `maxdepth`, so the image has the
    /// light paths of the scene's own (the default: none).
    const PATH_DEPTH: Option<&'static str> = None;

    /// The paper's cache budget for this application at 1920×1080 (ALGORITHMS.md §7): experiments give
    /// their densities as multiples of it.
    const PAPER_CACHES: usize = 120_000;

    /// The default budget `caches` at 1920×1080, scaled to the image's pixels: the paper's
    /// ([`Application::PAPER_CACHES`]) unless the application measured a better one for its defaults.
    const DEFAULT_CACHES: usize = Self::PAPER_CACHES;

    /// What the studies know of the application (the cache driver never reads it).
    const STUDY: Study<Self> = Study::NONE;

    /// What one cache stores.
    type Record: Send + Sync;

    /// The scene as the application reads it while rendering: a reference to it and whatever is prepared
    /// from it once (lights, materials, textures). Made by [`Application::prepare`].
    type Prepared<'s>: Sync;

    /// Reads exactly the parameters of [`Application::PARAMETERS`] with the typed getters of
    /// `IntegratorParams` (a bad value is an error naming it); a default that scales with the scene is a
    /// multiple of `scale.length`, the scene's length scale L (never of the raw bounding-box diagonal).
    fn from_params(p: &IntegratorParams<'_>, scale: &SceneScale) -> Result<Self>;

    /// The values these settings derived from the scene's length scale L (cache AO's default
    /// `maxdistance`, importance caching's d_c), for the `--stats` report; a value the user set is not
    /// derived (the default: none).
    fn scale_derived(&self) -> Vec<(&'static str, f32)> {
        Vec::new()
    }

    /// Prepares what the application reads from `scene` while rendering; problems that do not stop it (a
    /// scene without lights) are warnings.
    fn prepare<'s>(&self, scene: &'s Scene, warnings: &mut Warnings) -> Result<Self::Prepared<'s>>;

    /// The resolved parameters (defaults filled in), for the `--stats` report.
    fn settings(&self) -> Vec<(&'static str, serde_json::Value)>;

    /// What [`Application::prepare`] made of the scene, for the `--stats` report: what the settings asked
    /// for may differ from what the scene gave (importance caching: the VPLs generated, which can be fewer
    /// than `vpls`, and the light paths traced for them; irradiance caching: the lights).
    fn prepared_report(&self, cx: &Self::Prepared<'_>) -> Vec<(&'static str, serde_json::Value)> {
        let _ = cx;
        Vec::new()
    }

    /// The shading data [`Application::prepare`] built, if any: the driver's camera paths read their BSDFs
    /// and lights from it rather than reading the scene's textures and lights a second time (the default:
    /// none, and the driver builds its own where the plan needs one).
    fn shading<'a, 's>(&self, cx: &'a Self::Prepared<'s>) -> Option<&'a Shading<'s>> {
        let _ = cx;
        None
    }

    /// What these settings ask of the driver beyond caches (the default: nothing; see [`CachePlan`]).
    fn plan(&self) -> CachePlan {
        CachePlan::default()
    }

    /// Evaluates the expensive shading function at a cache site: the value and the per-sample gathering
    /// data that [`Application::diff`] compares.
    fn compute_record(
        &self,
        cx: &Self::Prepared<'_>,
        at: &ShadingPoint,
        rng: &mut Rng,
        rays: &mut RayCounters,
    ) -> Self::Record;

    /// `Σ_k |g_a[k] − g_b[k]|` over corresponding gathering samples (ALGORITHMS.md §4.5.2).
    fn diff(&self, a: &Self::Record, b: &Self::Record) -> f32;

    /// Called once per record when placement is over and before any shading: keeps what shading needs and
    /// may drop the per-sample data that only [`Application::diff`] reads (so memory stays flat while the
    /// image renders), or derive what depends on the final cache set. `region` is the distance from the
    /// cache to the M-th nearest other cache (ALGORITHMS.md §5's M; infinite when there are fewer): the
    /// radius of the region the cache serves.
    fn finish_record(&self, cx: &Self::Prepared<'_>, record: &mut Self::Record, region: f32) {
        let _ = (cx, record, region);
    }

    /// A copy of these settings whose shading draws about `keep` (0 < `keep` < 1) of its samples, for a
    /// target error the caches already beat where the error is the shading's noise
    /// ([`crate::placement::CacheOracle::thin`]); `None` (the default) where it is not (an interpolation's
    /// bias), or where no fewer draws are possible. It must not change what a record holds.
    fn thinned(&self, keep: f32) -> Option<Self> {
        let _ = keep;
        None
    }

    /// Called once per record after every [`Application::finish_record`], where the plan asks for it
    /// ([`CachePlan::learns`]), with the caches that shading at the record's own site would blend besides it
    /// (the §5 selection there with the cache itself left out; weights 1 / Dist): a small number that
    /// [`Application::keep_lesson`] stores in the record, of how shading near the cache should use its
    /// neighbours (importance caching: how many of its draws go to F). It must depend on the records alone,
    /// so that images stay deterministic.
    fn lesson(&self, cx: &Self::Prepared<'_>, own: &Self::Record, near: &[Neighbour<'_, Self::Record>]) -> u8 {
        let _ = (cx, own, near);
        0
    }

    /// Stores what [`Application::lesson`] gave for `record`.
    fn keep_lesson(&self, record: &mut Self::Record, lesson: u8) {
        let _ = (record, lesson);
    }

    /// Shades one sample from its selected caches (at least one; Σ weights > 0). `stratum` says where the
    /// sample sits among its pixel's sub-pixel samples, for draws stratified across them (an application
    /// that draws nothing per sample ignores it; `rng` is the sample's own stream).
    fn shade(
        &self,
        cx: &Self::Prepared<'_>,
        s: &ShadingPoint,
        near: &[Neighbour<'_, Self::Record>],
        rng: &mut Rng,
        stratum: Stratum,
        rays: &mut RayCounters,
    ) -> [f32; 3];

    /// The leave-one-out question of refine's error estimate: what shading a pixel's `samples` sub-pixel
    /// samples at a cache's own site `at` makes of the caches `near` (the cache itself not among them)
    /// against what it makes of `own` alone, or `None` when the application cannot say (the default). Asked
    /// while placing, before [`Application::finish_record`].
    fn predict(
        &self,
        cx: &Self::Prepared<'_>,
        at: &ShadingPoint,
        own: &Self::Record,
        near: &[Neighbour<'_, Self::Record>],
        samples: u32,
    ) -> Option<LeaveOneOut> {
        let _ = (cx, at, own, near, samples);
        None
    }

    /// The brute-force answer at one sample: what the caches approximate (references, goldens); a
    /// per-sample estimator's when [`CachePlan::shade_by_reference`] says so (`stratum` as for
    /// [`Application::shade`]).
    fn reference(
        &self,
        cx: &Self::Prepared<'_>,
        s: &ShadingPoint,
        rng: &mut Rng,
        stratum: Stratum,
        rays: &mut RayCounters,
    ) -> [f32; 3];

    /// The application's per-sample estimate where no cache is near enough to a sample (a point seen in a
    /// mirror or through glass, far from every cache): by default [`Application::reference`]; an
    /// application whose reference is too costly per sample gives a cheaper unbiased estimator.
    fn estimate(
        &self,
        cx: &Self::Prepared<'_>,
        s: &ShadingPoint,
        rng: &mut Rng,
        stratum: Stratum,
        rays: &mut RayCounters,
    ) -> [f32; 3] {
        self.reference(cx, s, rng, stratum, rays)
    }

    /// Bytes `record` occupies, heap included (for the memory report; asked before and after
    /// [`Application::finish_record`]).
    fn record_bytes(&self, record: &Self::Record) -> usize;

    /// The most bytes one record can occupy at any time, heap included: the driver refuses a budget whose
    /// records would not fit in the memory available, before it places anything.
    fn record_bytes_bound(&self) -> usize;
}
