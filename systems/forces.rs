//! Accumulating the forces on every cloth at the start of a step.

use bevy_ecs::prelude::*;

use crate::components::{
    ClothTopology, Particles, SolverWorkspace, Springs, Triangles, UserForces,
};
use crate::resources::{AirSettings, Gravity, SimClock};
use crate::schedule::{SimSchedules, SubstepSystems};
use crate::solver::forces::ForceModel;

/// The force model of one cloth in the world's gravity and air.
pub(crate) fn cloth_force_model<'a>(
    particles: &'a Particles,
    springs: &'a Springs,
    triangles: &'a Triangles,
    topology: &'a ClothTopology,
    user_forces: &'a UserForces,
    gravity: &Gravity,
    air: &AirSettings,
) -> ForceModel<'a> {
    ForceModel {
        inv_mass: &particles.inv_mass,
        springs,
        triangles: &triangles.indices,
        topology,
        gravity: gravity.0,
        air: air.0,
        user_forces: &user_forces.forces,
    }
}

/// Writes the total force on every particle at the current state into
/// [`Particles::force`]. Runs in [`SubstepSystems::Forces`].
pub fn accumulate_forces(
    gravity: Res<Gravity>,
    air: Res<AirSettings>,
    clock: Res<SimClock>,
    mut cloths: Query<(
        &mut Particles,
        &Springs,
        &Triangles,
        &ClothTopology,
        &UserForces,
        &mut SolverWorkspace,
    )>,
) {
    for (mut particles, springs, triangles, topology, user_forces, mut workspace) in &mut cloths {
        let mut force = std::mem::take(&mut particles.force);
        let model = cloth_force_model(
            &particles,
            springs,
            triangles,
            topology,
            user_forces,
            &gravity,
            &air,
        );
        model.eval(
            &particles.position,
            &particles.velocity,
            clock.time_s as f32,
            &mut workspace.forces,
            &mut force,
        );
        particles.force = force;
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules
        .substep
        .add_systems(accumulate_forces.in_set(SubstepSystems::Forces));
}
