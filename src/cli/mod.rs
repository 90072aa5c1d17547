//! The command line's parts that are not the library's work: its arguments, progress bar,
//! allocator, environment and the viewer's window. Only the `glint` binary compiles them.

pub mod alloc;
pub mod args;
pub mod env;
pub mod progress;
#[cfg(feature = "view")]
pub mod view;
