//! Rebuilding derived caches when a cloth's structure changed.

use bevy_ecs::prelude::*;

use crate::components::{BendingHinges, ClothTopology, MembraneTriangles, Particles, Pins, Springs, Triangles};
use crate::resources::SolverSettings;
use crate::schedule::{FrameSystems, SimSchedules};
use crate::solver::implicit::LinearSolver;

/// Rebuilds the incidence rows, the derivative pattern and the free inverse masses of
/// every cloth whose elements or pins changed since the last frame (and of new cloths);
/// others keep theirs. Runs in [`FrameSystems::Prepare`]. Where the implicit solve is
/// preconditioned by multigrid, its levels' structure is built here too, with the
/// topology as before, not in the first solve, where the scratch of its patterns would
/// come on top of the solver's buffers.
pub fn rebuild_cloth_topology(
    solver: Res<SolverSettings>,
    mut cloths: Query<
        (&Particles, &Springs, &Triangles, &BendingHinges, &MembraneTriangles, &Pins, &mut ClothTopology),
        Or<(Changed<Springs>, Changed<Triangles>, Changed<BendingHinges>, Changed<MembraneTriangles>, Changed<Pins>)>,
    >,
) {
    let multigrid = solver.method.implicit.linear_solver == LinearSolver::Multigrid;
    for (particles, springs, triangles, hinges, membranes, pins, mut topology) in &mut cloths {
        let builds = topology.builds + 1;
        *topology =
            ClothTopology::build(&particles.inv_mass, springs, triangles, hinges, membranes, &pins.particles, builds);
        if multigrid {
            topology.hierarchy(springs, &triangles.indices, hinges, membranes);
        }
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.frame.add_systems(rebuild_cloth_topology.in_set(FrameSystems::Prepare));
}
