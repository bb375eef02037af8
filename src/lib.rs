//! cachert — a renderer for pbrt-v3 scene files built around cache-based rendering, where *where the
//! caches go* is a switchable strategy.
//!
//! One layer per module, lowest first; a module imports only from lower layers (`ARCHITECTURE.md` has the
//! rules and where new work goes; `tests/layers.rs` checks them):
//!
//! | layer | module | what it does |
//! |---|---|---|
//! | 0 | [`error`], [`os`] | errors with file:line:col; probes of the system (CPU time, memory) |
//! | 1 | [`parse`] | stage 1: scene text → directives with file:line:col; integrator parameters (`parse::integrator`) |
//! | 1 | [`image`], [`sampling`], [`cache`] | f32 RGB images and their files; random streams, sequences, pixel samples, warps; the kd-tree over caches and the selection of a sample's caches (Eq. 5) |
//! | 2 | [`scene`], [`metrics`] | stage 2: directives → camera, film, shapes, instances, BVH; RMSE, relMSE, HDR-FLIP |
//! | 3 | [`gbuffer`], [`shading`] | stage 3: one shading point per pixel centre; textures, materials, lights and the direct-light estimators |
//! | 4 | [`placement`] | stage 4: where caches go: the strategies (IM, SD, VGC; AS, DGS) and their registry by name |
//! | 4 | [`application`] | what a cache holds: one module per cache-based application (the `Application` trait) and `application::registry`, the one list of them — **the seam for a new application** |
//! | 4 | [`render`] | the per-pixel integrators (`ambientocclusion`, `directlighting`, `path`) and their pixel loop |
//! | 5 | [`integrator`] | every integrator by name, and `integrator::cache`, the one generic driver of every cache-based integrator |
//! | 6 | [`job`] | one render job as data: load → render by name → write the image and cache outputs |
//! | 7 | [`golden`], [`experiment`] | the studies: golden-image regression; sweeps, benchmarks and the pbrt peers |
//! | 8 | [`cli`] | the subcommands of the `cachert` binary: flags → library calls |
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
pub mod provenance;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod shading;
#[cfg(test)]
mod test_support;

pub use error::{Error, Result, SourceLoc, Warning, Warnings};
