//! STAGE 7 (integrator): what a cache-based render reports — the stage times of the paper's Table 4, cache
//! counts, the placement search results, rays and memory — as plain data that serialises to JSON.

use serde::Serialize;

use super::camera_path::PathCounts;
use crate::gbuffer::scale::{ScaleSource, SceneScale, VIEW_FACTOR};
use crate::placement::{PlacementInfo, RoundEstimate};
use crate::scene::ray::RayCounters;

/// Wall seconds of each step (paper Table 4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct StageTimes {
    /// Preparing what the application reads from the scene (`Application::prepare`: lights, materials,
    /// textures; importance caching's VPLs).
    pub prepare: f64,
    /// Tracing the G-buffer (one shading point per pixel centre).
    pub shading_points: f64,
    /// First-stage placement.
    pub initial_generation: f64,
    /// Evaluating the first-stage caches.
    pub initial_computation: f64,
    /// Second-stage placement (excluding evaluation).
    pub adaptive_generation: f64,
    /// Evaluating the second-stage caches.
    pub adaptive_computation: f64,
    /// Building the kd-tree.
    pub kd_tree: f64,
    /// Finishing the records once placement is over (`Application::finish_record`).
    pub finish_records: f64,
    /// Shading every sub-pixel sample.
    pub render: f64,
    /// Rendering the per-pixel term added to the cached image (`CachePlan::added_per_pixel`).
    pub per_pixel_term: f64,
    /// Everything.
    pub total: f64,
}

impl StageTimes {
    /// The steps in pipeline order with their summary labels (total excluded): the one list behind the
    /// end-of-run summary and the experiment CSV's columns.
    pub fn steps(&self) -> [(&'static str, f64); 10] {
        [
            ("prepare", self.prepare),
            ("shading points", self.shading_points),
            ("initial gen", self.initial_generation),
            ("initial comp", self.initial_computation),
            ("adaptive gen", self.adaptive_generation),
            ("adaptive comp", self.adaptive_computation),
            ("kd-tree", self.kd_tree),
            ("finish records", self.finish_records),
            ("render", self.render),
            ("per-pixel term", self.per_pixel_term),
        ]
    }
}

/// The report of a cache-based render.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct CacheStats {
    /// Stage times.
    pub times: StageTimes,
    /// Pixels whose centre sees the scene.
    pub valid_pixels: usize,
    /// First-stage caches.
    pub stage1_caches: usize,
    /// Second-stage caches.
    pub stage2_caches: usize,
    /// All caches.
    pub total_caches: usize,
    /// Second-stage rounds.
    pub adaptive_rounds: u32,
    /// refine with a target error: its estimated relative RMSE after the first stage and after each round.
    #[serde(serialize_with = "ser_estimates")]
    pub error_estimates: Vec<RoundEstimate>,
    /// First-stage search results (σ_s, iterations, …).
    #[serde(serialize_with = "ser_info")]
    pub placement: PlacementInfo,
    /// Rays traced evaluating caches.
    #[serde(serialize_with = "ser_rays")]
    pub cache_rays: RayCounters,
    /// Rays traced while shading samples (camera rays; reference occlusion rays).
    #[serde(serialize_with = "ser_rays")]
    pub render_rays: RayCounters,
    /// Bytes of the cache records while placing (with their per-sample gathering data).
    pub record_bytes: usize,
    /// Bytes of the cache records while shading (after `Application::finish_record`).
    pub record_bytes_kept: usize,
    /// Peak resident memory of the process (bytes), where the OS reports it.
    pub peak_memory_bytes: Option<u64>,
    /// The scene's length scale L, where it came from, and the defaults derived from it.
    pub scale: Option<ScaleReport>,
    /// What the application prepared from the scene (`Application::prepared_report`: e.g. the VPLs
    /// generated).
    pub prepared: serde_json::Map<String, serde_json::Value>,
    /// What the camera paths did: specular bounces followed, vertices shaded after them, those shaded by
    /// the per-sample estimator, paths that left the scene.
    pub camera_paths: PathCounts,
    /// Remarks (budget above the valid pixels, …).
    pub notes: Vec<String>,
}

/// The length scale L of a render (`gbuffer::scale`) and the defaults derived from it, as `--stats` writes
/// them: `length`, `source` (`scene_diagonal` or `camera_view`), `scene_diagonal`, `view_extent`, the rays
/// that measured it, and `derived` (λ unless set; the application's, such as cache AO's `maxdistance` or
/// importance caching's `clamp_distance` d_c).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ScaleReport {
    /// L and what it was made from.
    #[serde(flatten)]
    pub scale: SceneScale,
    /// Each default derived from L, by parameter name.
    pub derived: serde_json::Map<String, serde_json::Value>,
}

impl ScaleReport {
    /// One summary line: L, its source, and what was derived from it.
    pub fn summary(&self) -> String {
        let s = &self.scale;
        let from = match (s.source, s.view_extent) {
            (ScaleSource::CameraView, Some(v)) => {
                format!("{VIEW_FACTOR} x camera view extent {v:.4}; scene diagonal {:.4}", s.scene_diagonal)
            }
            (_, Some(v)) => format!("scene diagonal; camera view extent {v:.4}"),
            (_, None) => "scene diagonal; the camera sees nothing".to_string(),
        };
        let derived: Vec<String> = self.derived.iter().map(|(k, v)| format!("{k} {v}")).collect();
        let derived = if derived.is_empty() { String::new() } else { format!(": {}", derived.join(", ")) };
        format!("scale: L {:.4} ({from}){derived}", s.length)
    }
}

fn ser_rays<S: serde::Serializer>(r: &RayCounters, s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeStruct;
    let mut st = s.serialize_struct("rays", 3)?;
    st.serialize_field("camera", &r.camera)?;
    st.serialize_field("occlusion", &r.shadow)?;
    st.serialize_field("total", &r.total())?;
    st.end()
}

fn ser_estimates<S: serde::Serializer>(e: &[RoundEstimate], s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::{SerializeSeq, SerializeStruct};
    let mut seq = s.serialize_seq(Some(e.len()))?;
    for r in e {
        struct Row<'a>(&'a RoundEstimate);
        impl serde::Serialize for Row<'_> {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                let mut st = s.serialize_struct("estimate", 2)?;
                st.serialize_field("caches", &self.0.caches)?;
                st.serialize_field("relative_rmse", &self.0.relative_rmse)?;
                st.end()
            }
        }
        seq.serialize_element(&Row(r))?;
    }
    seq.end()
}

fn ser_info<S: serde::Serializer>(i: &PlacementInfo, s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeStruct;
    let mut st = s.serialize_struct("placement", 6)?;
    st.serialize_field("sigma_s", &i.sigma_s)?;
    st.serialize_field("sigma_a_deg", &i.sigma_a_deg)?;
    st.serialize_field("sd_threshold", &i.sd_threshold)?;
    st.serialize_field("search_iterations", &i.search_iterations)?;
    st.serialize_field("clusters_found", &i.clusters_found)?;
    st.serialize_field("notes", &i.notes)?;
    st.end()
}

impl CacheStats {
    /// The end-of-run summary lines.
    pub fn summary(&self) -> String {
        let t = &self.times;
        let steps: Vec<String> = t.steps().iter().map(|(name, secs)| format!("{name} {secs:.3} s")).collect();
        let mut s = format!(
            "caches {} ({} stage 1 + {} stage 2) of {} valid pixels\n{} | total {:.3} s",
            self.total_caches,
            self.stage1_caches,
            self.stage2_caches,
            self.valid_pixels,
            steps.join(" | "),
            t.total
        );
        if let Some(sig) = self.placement.sigma_s {
            s += &format!(
                "\nVGC: sigma_s {sig:.5} (sigma_a {:.1} deg) after {} search iterations",
                self.placement.sigma_a_deg.unwrap_or(0.0),
                self.placement.search_iterations
            );
        }
        if let Some(th) = self.placement.sd_threshold {
            s += &format!("\nSD: threshold {th:.5} after {} search iterations", self.placement.search_iterations);
        }
        let c = &self.camera_paths;
        if c.specular_bounces > 0 || c.by_estimator > 0 {
            s += &format!(
                "\ncamera paths: {} samples, {} specular bounces, {} vertices after one ({} shaded from caches, {} by the per-sample estimator), {} left the scene",
                c.samples,
                c.specular_bounces,
                c.after_specular,
                c.after_specular.saturating_sub(c.by_estimator),
                c.by_estimator,
                c.escaped
            );
        }
        if let Some(scale) = &self.scale {
            s += &format!("\n{}", scale.summary());
        }
        if !self.prepared.is_empty() {
            let items: Vec<String> = self.prepared.iter().map(|(k, v)| format!("{k} {v}")).collect();
            s += &format!("\nprepared: {}", items.join(", "));
        }
        for n in self.notes.iter().chain(&self.placement.notes) {
            s += &format!("\nnote: {n}");
        }
        s
    }
}
