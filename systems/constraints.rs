//! Holding pinned particles.

use bevy_ecs::prelude::*;

use crate::components::{Particles, Pins};
use crate::schedule::{SimSchedules, SubstepSystems};
use crate::solver::pins::hold_pins;

/// Puts pinned particles back on their targets at rest. Runs in
/// [`SubstepSystems::Constraints`].
pub fn hold_pinned_particles(mut cloths: Query<(&mut Particles, &Pins)>) {
    for (mut particles, pins) in &mut cloths {
        let Particles { position, velocity, .. } = &mut *particles;
        hold_pins(&pins.particles, &pins.targets, position, velocity);
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.substep.add_systems(hold_pinned_particles.in_set(SubstepSystems::Constraints));
}
