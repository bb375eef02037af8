//! cachert — a renderer for pbrt-v3 scene files built around cache-based rendering, where *where the
//! caches go* is a switchable strategy.
//!
//! The pipeline, one module per stage (see `DESIGN.md` in the shared documents):
//!
//! | stage | module | what it does |
//! |---|---|---|
//! | 1 | [`parse`] | scene text → directives with file:line:col |
//! | 2 | [`scene`] | directives → camera, film, shapes, instances, BVH |
//! | — | [`image`] | f32 RGB images; EXR, PFM and PNG in and out |
//! | — | [`metrics`] | RMSE, relMSE, HDR-FLIP |
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
pub mod image;
pub mod metrics;
pub mod parse;
pub mod placement;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod shading;

pub use error::{Error, Result, SourceLoc, Warning, Warnings};
