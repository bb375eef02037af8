//! STAGE 2 (scene): shape data. Mesh readers (PLY, OBJ) turn files into [`mesh_data::MeshData`].

pub mod mesh_data;
pub mod quadric;
pub mod triangle;
pub mod obj;
pub mod ply;
