//! Rebuilding derived caches when a cloth's structure changed.

use bevy_ecs::prelude::*;

use crate::components::{
    BendingHinges, ClothElements, ClothTopology, MembraneTriangles, Particles, Pins, Springs, Triangles,
};
use crate::resources::SolverSettings;
use crate::schedule::{FrameSystems, SimSchedules};
use crate::solver::implicit::LinearSolver;
use crate::solver::integrate::Integrator;

/// Rebuilds the incidence rows, the derivative pattern and the free inverse masses of
/// every cloth whose elements or pins changed since the last frame (and of new cloths);
/// others keep theirs. Runs in [`FrameSystems::Prepare`]. Where the implicit solve is
/// preconditioned by multigrid, its levels' structure is built here too, with the
/// topology as before, not in the first solve, where the scratch of its patterns would
/// come on top of the solver's buffers; so is block descent's colouring where it solves.
pub fn rebuild_cloth_topology(
    solver: Res<SolverSettings>,
    mut cloths: Query<
        (&Particles, &Springs, &Triangles, &BendingHinges, &MembraneTriangles, &Pins, &mut ClothTopology),
        Or<(Changed<Springs>, Changed<Triangles>, Changed<BendingHinges>, Changed<MembraneTriangles>, Changed<Pins>)>,
    >,
) {
    let linear_solver = solver.method.implicit.linear_solver;
    let multigrid = linear_solver == LinearSolver::Multigrid;
    let descent =
        solver.integrator == Integrator::BlockDescent || matches!(linear_solver, LinearSolver::BlockDescent(_));
    for (particles, springs, triangles, hinges, membranes, pins, mut topology) in &mut cloths {
        let builds = topology.builds + 1;
        *topology =
            ClothTopology::build(&particles.inv_mass, springs, triangles, hinges, membranes, &pins.particles, builds);
        let elements = ClothElements { springs, triangles: &triangles.indices, hinges, membranes };
        if multigrid {
            topology.hierarchy(elements);
        }
        if descent {
            topology.colouring(elements);
        }
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.frame.add_systems(rebuild_cloth_topology.in_set(FrameSystems::Prepare));
}
