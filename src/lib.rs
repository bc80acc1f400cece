//! Selvedge: an entity-component-system engine for cloth and garment simulation.
//!
//! The pipeline, from file to frames:
//!
//! 1. [`scene`] reads a RON scene ([`scene::load_scene`]), checks it and spawns garments
//!    into a bevy_ecs [`World`](bevy_ecs::world::World) ([`scene::spawn_scene`]), using the
//!    [`builders`] for grids, meshes and pin selections.
//! 2. [`schedule`] wires the scheduled [`systems`] into four schedules (frame, substep,
//!    probe, render) in one place; [`Simulation`] owns the world and runs them.
//! 3. The systems are thin adapters over the pure kernels in [`solver`] (forces,
//!    integrators, constraints, contact, probes), which know nothing of the ECS.
//! 4. [`io`] writes frames (OBJ, PLY), `summary.json` and `probes.csv`, each file whole or
//!    not at all; [`cli`] is the `selvedge` command.

pub mod builders;
pub mod cli;
pub mod collision;
pub mod components;
pub mod fabrics;
pub mod io;
pub mod memory;
pub mod pool;
pub mod resources;
pub mod scene;
pub mod schedule;
pub mod simulation;
pub mod solver;

// The scheduled systems live in the top-level `systems/` folder (behaviour), beside `src/`
// (data and kernels), but compile into this one crate so that neither depends on the other
// through a package boundary.
#[path = "../systems/mod.rs"]
pub mod systems;

pub use simulation::{Divergence, FrameTiming, Simulation};
