//! Running the steps of a frame.

use bevy_ecs::prelude::*;

use crate::resources::{HealthReport, SimClock, StepSettings};
use crate::schedule::{FrameSystems, SimSchedules, SubstepSchedule};

/// Runs [`SubstepSchedule`] `substeps` times, advancing the clock by `dt` after each, and
/// stops early once a step has reported a problem. Runs in [`FrameSystems::Substeps`].
pub fn run_substeps(world: &mut World) {
    let settings = *world.resource::<StepSettings>();
    for _ in 0..settings.substeps {
        world.run_schedule(SubstepSchedule);
        let mut clock = world.resource_mut::<SimClock>();
        clock.time_s += f64::from(settings.dt);
        clock.step += 1;
        if world.resource::<HealthReport>().problem.is_some() {
            break;
        }
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.frame.add_systems(run_substeps.in_set(FrameSystems::Substeps));
}
