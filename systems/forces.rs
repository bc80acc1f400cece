//! Accumulating the forces on every cloth at the start of a step.

use bevy_ecs::prelude::*;
use bevy_ecs::system::SystemParam;

use crate::components::{
    BendingHinges, ClothMaterial, ClothTopology, MembraneTriangles, Particles, SolverWorkspace, Springs, Triangles,
    UserForces,
};
use crate::resources::{AirSettings, Gravity, SimClock};
use crate::schedule::{SimSchedules, SubstepSystems};
use crate::solver::forces::ForceModel;

/// The components of a cloth that exert force besides its particles, to query together.
pub type ForceElements = (
    &'static ClothMaterial,
    &'static Springs,
    &'static Triangles,
    &'static BendingHinges,
    &'static MembraneTriangles,
    &'static ClothTopology,
    &'static UserForces,
);

/// What a [`ForceElements`] query yields for one cloth.
pub type ForceElementsItem<'a> = (
    &'a ClothMaterial,
    &'a Springs,
    &'a Triangles,
    &'a BendingHinges,
    &'a MembraneTriangles,
    &'a ClothTopology,
    &'a UserForces,
);

/// The world's gravity and air, and the time, as the force model sees them.
#[derive(SystemParam)]
pub struct ForceEnvironment<'w> {
    gravity: Res<'w, Gravity>,
    air: Res<'w, AirSettings>,
    clock: Res<'w, SimClock>,
}

impl ForceEnvironment<'_> {
    /// The force model of a cloth with inverse masses `inv_mass` [1/kg] and `elements`.
    pub fn model<'a>(&self, inv_mass: &'a [f32], elements: ForceElementsItem<'a>) -> ForceModel<'a> {
        let (material, springs, triangles, hinges, membranes, topology, user_forces) = elements;
        ForceModel {
            inv_mass,
            density: material.density,
            springs,
            triangles: &triangles.indices,
            hinges,
            membranes,
            topology,
            gravity: self.gravity.0,
            air: self.air.0,
            user_forces: &user_forces.forces,
        }
    }

    /// The current time [s].
    pub fn time(&self) -> f32 {
        self.clock.time_s as f32
    }
}

/// Writes the total force on every particle at the current state into
/// [`Particles::force`], and keeps the positions the step starts from. Runs in [`SubstepSystems::Forces`].
pub fn accumulate_forces(
    environment: ForceEnvironment,
    mut cloths: Query<(&mut Particles, ForceElements, &mut SolverWorkspace)>,
) {
    for (mut particles, elements, mut workspace) in &mut cloths {
        workspace.step_start.clone_from(&particles.position);
        let mut force = std::mem::take(&mut particles.force);
        let model = environment.model(&particles.inv_mass, elements);
        model.eval(&particles.position, &particles.velocity, environment.time(), &mut workspace.forces, &mut force);
        particles.force = force;
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.substep.add_systems(accumulate_forces.in_set(SubstepSystems::Forces));
}
