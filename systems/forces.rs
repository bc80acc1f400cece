//! Accumulating the forces on every cloth at the start of a step.

use bevy_ecs::prelude::*;
use bevy_ecs::system::SystemParam;
use glam::Vec3;

use crate::components::{
    BendingHinges, ClothMaterial, ClothTopology, Collider, MembraneTriangles, Particles, SelfCollision,
    SolverWorkspace, Springs, Touching, Triangles, UserForces,
};
use crate::resources::{AirSettings, Gravity, SimClock, SolverSettings};
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

    /// When the step of length `dt` [s] that starts now ends [s].
    pub fn step_end(&self, dt: f32) -> f32 {
        self.clock.step_end(dt)
    }
}

/// Writes the total force at the current state into [`Particles::force`], and keeps the
/// positions the step starts from where contact will read them (a collider to touch, or
/// the cloth colliding with itself): a cloth that touches nothing kept 12 bytes a particle
/// it never read. Runs in [`SubstepSystems::Forces`].
///
/// An implicit step reads the start force only where a particle touches a body (whether
/// the force presses it into the body) and evaluates what else it needs itself, so for a
/// cloth touching nothing the force is left zero. A cloth touching a body is evaluated
/// whole, and the implicit step takes that evaluation instead of making it again
/// ([`SolverWorkspace::whole_start_force`]). Evaluated at the touching particles alone
/// (as [`ForceModel::pin_forces`] does for the pins: serial, each element once for each
/// of its particles there)
/// and again whole by the step, it cost sphere_64 some 10 ms a frame.
pub fn accumulate_forces(
    environment: ForceEnvironment,
    solver: Res<SolverSettings>,
    mut cloths: Query<(&mut Particles, ForceElements, &Touching, &mut SolverWorkspace, Has<SelfCollision>)>,
    colliders: Query<(), With<Collider>>,
) {
    let bodies = !colliders.is_empty();
    for (mut particles, elements, touching, mut workspace, self_collision) in &mut cloths {
        if bodies || self_collision {
            workspace.step_start.clone_from(&particles.position);
        }
        let mut force = std::mem::take(&mut particles.force);
        let whole = !solver.integrator.is_implicit() || !touching.0.is_empty();
        if whole {
            let model = environment.model(&particles.inv_mass, elements);
            model.eval(&particles.position, &particles.velocity, environment.time(), &mut workspace.forces, &mut force);
        } else {
            force.fill(Vec3::ZERO);
        }
        workspace.whole_start_force = whole;
        particles.force = force;
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.substep.add_systems(accumulate_forces.in_set(SubstepSystems::Forces));
}
