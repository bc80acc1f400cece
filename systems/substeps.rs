//! Running the steps of a frame.

use bevy_ecs::prelude::*;
use glam::Vec3;

use crate::components::{Collider, Particles, Triangles};
use crate::resources::{AdaptiveSteps, HealthReport, SimClock, StepSettings};
use crate::schedule::{FrameSystems, SimSchedules, SubstepSchedule};

/// Runs [`SubstepSchedule`] `substeps` times, advancing the clock by `dt` after each, and
/// stops early once a step has reported a problem; with [`AdaptiveSteps`], first sets the
/// frame's steps from the motion ([`frame_reach`]). Runs in [`FrameSystems::Substeps`].
pub fn run_substeps(world: &mut World) {
    if let Some(adaptive) = world.get_resource::<AdaptiveSteps>().copied() {
        let reach = frame_reach(world, adaptive.frame_time);
        world.insert_resource(adaptive.settings(adaptive.steps(reach)));
    }
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

/// How far, in mean edge lengths of its cloth, a particle would move over a frame of
/// `frame_time` at the speed it starts the frame with plus the fastest that any collider's
/// surface moves where it is (at the frame's start or end): a bound on its motion
/// relative to any collider, the largest of all the cloths'. Edges are measured at rest,
/// over the triangles' sides (an inner edge counted twice); a cloth without triangles
/// reaches infinitely far, so that it takes every step.
fn frame_reach(world: &mut World, frame_time: f32) -> f32 {
    let now = world.resource::<SimClock>().time_s as f32;
    let mut colliders = world.query::<&Collider>();
    let surfaces: Vec<_> = colliders
        .iter(world)
        .flat_map(|c| [c.motion.state_at(now), c.motion.state_at(now + frame_time)])
        .filter(|state| state.linear != Vec3::ZERO || state.angular != Vec3::ZERO)
        .collect();
    let mut cloths = world.query::<(&Particles, &Triangles)>();
    cloths
        .iter(world)
        .map(|(particles, triangles)| {
            let rest = &particles.rest_position;
            let sides: f32 = triangles
                .indices
                .iter()
                .map(|t| (0..3).map(|k| rest[t[k] as usize].distance(rest[t[(k + 1) % 3] as usize])).sum::<f32>())
                .sum();
            let edge = sides / (3 * triangles.len()).max(1) as f32;
            let fastest = particles
                .position
                .iter()
                .zip(&particles.velocity)
                .map(|(&p, v)| v.length() + surfaces.iter().map(|s| s.velocity_at(p).length()).fold(0.0, f32::max))
                .fold(0.0, f32::max);
            if edge > 0.0 { fastest * frame_time / edge } else { f32::INFINITY }
        })
        .fold(0.0, f32::max)
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.frame.add_systems(run_substeps.in_set(FrameSystems::Substeps));
}
