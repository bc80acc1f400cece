//! Contact of cloth with the ground.

use bevy_ecs::prelude::*;

use crate::components::Particles;
use crate::resources::Ground;
use crate::schedule::{SimSchedules, SubstepSystems};
use crate::solver::contact::resolve_ground;

/// Keeps every particle above the ground plane, with friction. Runs in
/// [`SubstepSystems::BodyContacts`].
pub fn collide_with_ground(ground: Res<Ground>, mut cloths: Query<&mut Particles>) {
    let Some(plane) = ground.0 else { return };
    for mut particles in &mut cloths {
        let Particles { position, velocity, .. } = &mut *particles;
        resolve_ground(plane, position, velocity);
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.substep.add_systems(collide_with_ground.in_set(SubstepSystems::BodyContacts));
}
