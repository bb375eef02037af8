//! STAGE 2 (scene): shape data and intersection: mesh readers (PLY, OBJ) produce [`mesh_data::MeshData`];
//! [`triangle`] and [`quadric`] intersect rays with triangles and analytic shapes.

pub mod mesh_data;
pub mod obj;
pub mod ply;
pub mod quadric;
#[cfg(test)]
mod test_files;
pub mod triangle;
