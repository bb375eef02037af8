//! STAGE 2: directives → [`Scene`]-level objects: graphics state, transforms, camera, film, shapes,
//! instances and the ray-tracing acceleration structure.
//!
//! Depends on `parse` (for directives) and on nothing later in the pipeline.

pub mod shapes;
pub mod accel;
pub mod camera;
pub mod film;
pub mod filter;
pub mod ray;
pub mod sampler;
pub mod transform;
