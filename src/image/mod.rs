//! Images: f32 RGB in memory; EXR, PFM and PNG in and out. Being written.
