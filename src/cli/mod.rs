//! The subcommands of the `cachert` binary, as library functions so tests can call them.

pub mod compare;
