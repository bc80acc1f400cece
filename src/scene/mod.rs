//! The RON scene boundary: the file format ([`format`]), reading it with errors that name
//! file, line and column ([`load`]), checking its physics ([`validate`]) and turning it
//! into entities ([`build`]).

pub mod build;
pub mod format;
pub mod load;
pub mod validate;

pub use build::{SceneCounts, spawn_scene};
pub use format::Scene;
pub use load::{SceneError, load_scene, parse_scene};
