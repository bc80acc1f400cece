//! Constraints after each step: pins, then strain limits.

use bevy_ecs::prelude::*;

use crate::components::{ClothTopology, Grips, Particles, Pins, SolverWorkspace, StrainLimit};
use crate::resources::{SimClock, StepSettings};
use crate::schedule::{SimSchedules, SubstepSystems};
use crate::solver::pins::hold_pins;
use crate::solver::strain_limit::{LimitedEdges, limit_strain};

/// Moves the pin targets of gripped particles to where their grips are at the end of the
/// step. Only targets change, so the cloth's topology is not rebuilt. Runs in
/// [`SubstepSystems::Constraints`], before the pins are held.
pub fn move_grips(clock: Res<SimClock>, settings: Res<StepSettings>, mut cloths: Query<(&mut Pins, &Grips)>) {
    let t = clock.step_end(settings.dt);
    for (mut pins, grips) in &mut cloths {
        let pins = pins.bypass_change_detection();
        for grip in &grips.0 {
            let pose = grip.motion.state_at(t).pose;
            for (&particle, &local) in grip.particles.iter().zip(&grip.local) {
                pins.insert(particle, pose * local);
            }
        }
    }
}

/// Puts pinned particles back on their targets at rest. Runs in
/// [`SubstepSystems::Constraints`].
pub fn hold_pinned_particles(mut cloths: Query<(&mut Particles, &Pins)>) {
    for (mut particles, pins) in &mut cloths {
        let Particles { position, velocity, .. } = &mut *particles;
        hold_pins(&pins.particles, &pins.targets, position, velocity);
    }
}

/// Projects the limited edges of every cloth back to their strain limit, after the pins.
/// Runs in [`SubstepSystems::Constraints`].
pub fn limit_cloth_strain(
    settings: Res<StepSettings>,
    mut cloths: Query<(&mut Particles, &StrainLimit, &ClothTopology, &mut SolverWorkspace)>,
) {
    for (mut particles, limit, topology, mut workspace) in &mut cloths {
        if limit.pairs.is_empty() {
            continue;
        }
        let edges = LimitedEdges {
            pairs: &limit.pairs,
            rest_length: &limit.rest_length,
            max_strain: limit.max_strain,
            iterations: limit.iterations,
        };
        let Particles { position, velocity, .. } = &mut *particles;
        limit_strain(&edges, &topology.free_inv_mass, settings.dt, position, velocity, &mut workspace.positions);
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.substep.add_systems(
        (move_grips, hold_pinned_particles, limit_cloth_strain).chain().in_set(SubstepSystems::Constraints),
    );
}
