//! Contact of cloth with solid bodies.

use bevy_ecs::prelude::*;

use crate::collision::body_contact::{ContactBody, resolve_body_contacts};
use crate::components::{
    Cloth, ClothMaterial, ClothTopology, Collider, ContactStats, Particles, SolverWorkspace, Touching,
};
use crate::resources::{SimClock, StepSettings};
use crate::schedule::{FrameSystems, SimSchedules, SubstepSystems};

/// Resolves every cloth's contacts with every collider at the end of the step (the
/// colliders where they are then), and adds what they did to the cloth's
/// [`ContactStats`]. Runs in [`SubstepSystems::BodyContacts`].
pub fn collide_with_bodies(
    clock: Res<SimClock>,
    settings: Res<StepSettings>,
    colliders: Query<&Collider>,
    mut cloths: Query<(
        &Cloth,
        &ClothMaterial,
        &mut Particles,
        &ClothTopology,
        &SolverWorkspace,
        &mut ContactStats,
        &mut Touching,
    )>,
) {
    if colliders.is_empty() {
        return;
    }
    let t = (clock.time_s + f64::from(settings.dt)) as f32;
    for (cloth, material, mut particles, topology, workspace, mut stats, mut touching) in &mut cloths {
        let bodies: Vec<ContactBody<'_>> = colliders
            .iter()
            .map(|c| ContactBody {
                shape: c.shape.as_ref(),
                state: c.motion.state_at(t),
                friction: c.friction,
                thickness: c.thickness + cloth.thickness,
                stick: c.stick,
            })
            .collect();
        let Particles { position, velocity, inv_mass, .. } = &mut *particles;
        let density = material.density;
        let area = |i: usize| 1.0 / (inv_mass[i] * density);
        let totals = resolve_body_contacts(
            &bodies,
            inv_mass,
            &topology.free_inv_mass,
            area,
            settings.dt,
            &workspace.step_start,
            &workspace.support,
            position,
            velocity,
            &mut touching.0,
        );
        stats.0.add(&totals);
    }
}

/// Starts each frame's contact sums from zero. Runs in [`FrameSystems::Prepare`].
pub fn reset_contact_stats(mut cloths: Query<&mut ContactStats>) {
    for mut stats in &mut cloths {
        *stats = ContactStats::default();
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.frame.add_systems(reset_contact_stats.in_set(FrameSystems::Prepare));
    schedules.substep.add_systems(collide_with_bodies.in_set(SubstepSystems::BodyContacts));
}
