//! cachert — a renderer for pbrt-v3 scene files built around cache-based rendering, where *where the
//! caches go* is a switchable strategy.
//!
//! The pipeline, one module per stage (see `DESIGN.md` in the shared documents):
//!
//! | stage | module | what it does |
//! |---|---|---|
//! | 1 | [`parse`] | scene text → directives with file:line:col |
//! | 2 | [`scene`] | directives → camera, film, shapes, instances, BVH |
//! | 3 | [`gbuffer`] | one shading point per pixel centre: what placement reads and shading starts from |
//! | 4 | [`placement`] | where caches go: the strategies (IM, SD, VGC; AS, DGS) and their registry by name |
//! | 5 | [`cache`] | the kd-tree over cache positions and the selection of a sample's caches (Eq. 5) |
//! | 5 | [`application`] | what a cache holds: one file per cache-based application (the `Application` trait) and `application::registry`, the one list of them — **the seam for a new application** |
//! | 5 | [`shading`] | textures, materials, lights: what a surface does with light |
//! | 6 | [`render`] | the per-pixel integrators (`ambientocclusion`, `directlighting`, `path`) and their pixel loop |
//! | 7 | [`integrator`] | every integrator by name, and `integrator::cache`, the one generic driver of every cache-based integrator |
//! | 8 | [`job`] | one render job as data: load → render by name → write the image and cache outputs |
//! | — | [`experiment`] | sweeps of placements × budgets × seeds against the per-sample reference |
//! | — | [`golden`] | golden-image regression: a manifest of renders re-rendered and compared bit for bit |
//! | — | [`sampling`] | random streams keyed by pixel, low-discrepancy sequences, warps, frames |
//! | — | [`image`] | f32 RGB images; EXR, PFM and PNG in and out |
//! | — | [`metrics`] | RMSE, relMSE, HDR-FLIP |
//! | — | [`os`] | probes of the system: CPU time, peak and available memory |
//! | — | [`cli`] | the subcommands of the `cachert` binary |
//!
//! Errors from user input are [`error::Error`]s with locations; nothing reachable from a scene file or a flag
//! panics.
#![deny(missing_docs)]

pub mod application;
pub mod cache;
pub mod cli;
pub mod error;
pub mod experiment;
pub mod gbuffer;
pub mod golden;
pub mod image;
pub mod integrator;
pub mod job;
pub mod metrics;
pub mod os;
pub mod parse;
pub mod placement;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod shading;

pub use error::{Error, Result, SourceLoc, Warning, Warnings};
