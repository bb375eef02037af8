//! STAGE 2 (scene): shape data and intersection: mesh readers (PLY, OBJ) and the mesh-producing pbrt-v3
//! shapes ([`loopsubdiv`], [`heightfield`], [`nurbs`]) produce [`mesh_data::MeshData`]; [`triangle`],
//! [`quadric`] and [`curve`] intersect rays with triangles, analytic shapes and curves.

pub mod curve;
pub(crate) mod efloat;
pub mod heightfield;
pub mod loopsubdiv;
pub mod mesh_data;
pub mod nurbs;
pub mod obj;
pub mod ply;
pub mod quadric;
#[cfg(test)]
mod test_files;
pub mod triangle;
