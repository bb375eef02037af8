//! Sampling building blocks shared by every stage that draws random numbers: counter-based random streams
//! keyed by (seed, stage, index) ([`rng`]), draws stratified across a pixel's sub-pixel samples
//! ([`stratum`]), discrete distributions drawn in expected O(1) ([`cdf`]), low-discrepancy point sets ([`sequence`]), the sample values of one camera sample
//! ([`pixel_samples`]), warps from the unit square to hemispheres and disks ([`warp`]) and orthonormal
//! frames ([`frame`]).
//!
//! Nothing here knows about scenes or images; it depends only on glam.

pub mod cdf;
pub mod frame;
pub mod pixel_samples;
pub mod rng;
pub mod sequence;
pub mod stratum;
pub mod warp;

pub use cdf::Cdf;
pub use frame::Frame;
pub use rng::{Rng, hash3, unit_f64};
pub use stratum::Stratum;
