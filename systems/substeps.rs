//! Running the steps of a frame.

use bevy_ecs::prelude::*;
use glam::Vec3;

use crate::collision::collider::ColliderState;
use crate::components::{Collider, Particles, SelfTouching, Triangles};
use crate::resources::{AdaptiveSteps, HealthReport, SimClock, StepSettings};
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

/// With [`AdaptiveSteps`], sets the frame's [`StepSettings`] from how far, in mean edge
/// lengths of its cloth, a particle would move over the frame at the speed it starts it
/// with plus the fastest that any collider's surface moves where it is (at the frame's
/// start or end): a bound on its motion relative to any collider, the largest of all the
/// cloths'. Edges are measured at rest, over the triangles' sides (an inner edge counted
/// twice); a cloth without triangles reaches infinitely far, so that it takes every step.
///
/// The self-contact springs the last step left, made for its length, are made over for
/// the new one ([`crate::solver::contact_springs::ContactSpring::restep`]). Runs in
/// [`FrameSystems::Prepare`], after the edits that may have cut triangles.
pub fn plan_frame_steps(
    adaptive: Option<Res<AdaptiveSteps>>,
    clock: Res<SimClock>,
    colliders: Query<&Collider>,
    cloths: Query<(&Particles, &Triangles)>,
    mut surfaces: Local<Vec<ColliderState>>,
    mut settings: ResMut<StepSettings>,
    mut touching: Query<&mut SelfTouching>,
) {
    let Some(adaptive) = adaptive else {
        return;
    };
    let (now, frame_time) = (clock.time_s as f32, adaptive.frame_time);
    surfaces.clear();
    surfaces.extend(
        colliders
            .iter()
            .flat_map(|c| [c.motion.state_at(now), c.motion.state_at(now + frame_time)])
            .filter(|state| state.linear != Vec3::ZERO || state.angular != Vec3::ZERO),
    );
    let reach = cloths
        .iter()
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
        .fold(0.0, f32::max);
    let last = settings.dt;
    *settings = adaptive.settings(adaptive.steps(reach));
    if settings.dt != last {
        for spring in touching.iter_mut().flat_map(|t| t.into_inner().0.iter_mut()) {
            spring.restep(last, settings.dt);
        }
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.frame.add_systems(plan_frame_steps.in_set(FrameSystems::Prepare));
    schedules.frame.add_systems(run_substeps.in_set(FrameSystems::Substeps));
}
