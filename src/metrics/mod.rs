//! Error metrics between a test and a reference image. Being written.
