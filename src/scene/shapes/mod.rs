//! STAGE 2 (scene): shape data and intersection: mesh readers (PLY, OBJ) produce [`mesh_data::MeshData`];
//! [`triangle`], [`quadric`] and [`curve`] intersect rays with triangles, analytic shapes and curves.

pub mod curve;
pub mod mesh_data;
pub mod obj;
pub mod ply;
pub mod quadric;
#[cfg(test)]
mod test_files;
pub mod triangle;
