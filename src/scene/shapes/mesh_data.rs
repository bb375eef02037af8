//! STAGE 2 (scene): being written.
