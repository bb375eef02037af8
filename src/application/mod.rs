//! WHAT a cache holds: one module per cache-based application (DESIGN.md §2). An application computes a
//! record at a cache site (value plus per-sample gathering data), compares two records (for the second-stage
//! placement strategies), shades a sample from its selected caches, and gives the brute-force answer the
//! cache approximates. Placement never sees the record type, so every strategy works with every
//! application.
//!
//! Depends on `scene`, `gbuffer` and `sampling`; never on `placement` or the render driver.

pub mod ambient_occlusion;

use crate::gbuffer::ShadingPoint;
use crate::sampling::Rng;
use crate::scene::Scene;
use crate::scene::ray::RayCounters;

/// A cache-based rendering application.
pub trait Application: Sync {
    /// What one cache stores.
    type Record: Send + Sync;

    /// The integrator name users type (`"cacheao"`).
    fn name(&self) -> &'static str;

    /// Evaluates the expensive shading function at a cache site: the value and the per-sample gathering
    /// data that [`Application::diff`] compares.
    fn compute_record(&self, scene: &Scene, at: &ShadingPoint, rng: &mut Rng, rays: &mut RayCounters) -> Self::Record;

    /// Σ_k |g_a[k] − g_b[k]| over corresponding gathering samples (ALGORITHMS.md §4.5.2).
    fn diff(&self, a: &Self::Record, b: &Self::Record) -> f32;

    /// Shades one sample from its selected caches with their interpolation weights (Σ weights > 0).
    fn shade(
        &self,
        scene: &Scene,
        s: &ShadingPoint,
        near: &[(&Self::Record, f32)],
        rng: &mut Rng,
        rays: &mut RayCounters,
    ) -> [f32; 3];

    /// The brute-force answer at one sample: what the caches approximate (references, goldens).
    fn reference(&self, scene: &Scene, s: &ShadingPoint, rng: &mut Rng, rays: &mut RayCounters) -> [f32; 3];

    /// Bytes one record occupies (for the memory report).
    fn record_bytes(&self) -> usize;
}
