//! Rebuilding derived caches when a cloth's structure changed.

use bevy_ecs::prelude::*;

use crate::components::{
    BendingHinges, ClothElements, ClothTopology, MembraneTriangles, Particles, Pins, SolverParts, Springs, Triangles,
};
use crate::resources::SolverSettings;
use crate::schedule::{FrameSystems, SimSchedules};
use crate::solver::implicit::LinearSolver;
use crate::solver::integrate::Integrator;

/// Rebuilds the incidence rows, the derivative pattern and the free inverse masses of
/// every cloth whose elements or pins changed since the last frame (and of new cloths);
/// others keep theirs. Runs in [`FrameSystems::Prepare`]. The parts of the solver that
/// will step the cloth are built with it, as before: the multigrid's levels' structure
/// where the implicit solve is preconditioned by multigrid (not in the first solve, where
/// the scratch of its patterns would come on top of the solver's buffers), and block
/// descent's colouring where it solves.
pub fn rebuild_cloth_topology(
    solver: Res<SolverSettings>,
    mut cloths: Query<
        (&Particles, &Springs, &Triangles, &BendingHinges, &MembraneTriangles, &Pins, &mut ClothTopology),
        Or<(Changed<Springs>, Changed<Triangles>, Changed<BendingHinges>, Changed<MembraneTriangles>, Changed<Pins>)>,
    >,
) {
    let linear_solver = solver.method.implicit.linear_solver;
    let parts = SolverParts {
        hierarchy: linear_solver == LinearSolver::Multigrid,
        colouring: solver.integrator == Integrator::BlockDescent
            || matches!(linear_solver, LinearSolver::BlockDescent(_)),
    };
    for (particles, springs, triangles, hinges, membranes, pins, mut topology) in &mut cloths {
        let builds = topology.builds + 1;
        let elements = ClothElements { springs, triangles: &triangles.indices, hinges, membranes };
        *topology = ClothTopology::build(&particles.inv_mass, elements, &pins.particles, builds, parts);
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.frame.add_systems(rebuild_cloth_topology.in_set(FrameSystems::Prepare));
}
