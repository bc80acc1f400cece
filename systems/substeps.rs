//! Running the steps of a frame.

use bevy_ecs::prelude::*;
use glam::Vec3;

use crate::collision::collider::ColliderState;
use crate::components::{Cloth, Collider, Particles, SelfCollision, SelfTouching, Triangles};
use crate::resources::{AdaptiveSteps, Gravity, HealthReport, SimClock, StepSettings};
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

/// How many times its reach over a frame a particle must be from a collider for the
/// collider to be left out of its planning. The reach is the particle's speed at the
/// frame's start, plus what gravity adds over the frame, plus the collider's surface
/// speed there, over the frame; the cloth's own forces can speed a particle up more
/// within a frame than gravity does (a corner whipping round a body).
const REACH_SLACK: f32 = 2.0;

/// With [`AdaptiveSteps`], sets the frame's [`StepSettings`]: the fewest steps that keep
/// every particle's move towards what it may touch within the frame within `motion` mean
/// rest edges of its cloth a step ([`AdaptiveSteps::steps`]), the largest over the cloths.
///
/// A particle may touch a collider that lies within [`REACH_SLACK`] times its reach;
/// towards it, it moves at most at its speed plus the collider's surface speed where it
/// is (at the frame's start or end). Cloths that collide with cloth may touch each
/// other, and any part of themselves: two of their particles approach each other no
/// faster than the sum of their speeds relative to the mean velocity of all their
/// particles. So a cloth falling flat, or swinging far from any body, takes one step a
/// frame, and one landing on a body takes them all. Edges are measured at rest, over the
/// triangles' sides (an inner edge counted twice); a cloth without triangles takes every
/// step.
///
/// The self-contact springs the last step left, made for its length, are made over for
/// the new one ([`crate::solver::contact_springs::ContactSpring::restep`]). Runs in
/// [`FrameSystems::Prepare`], after the edits that may have cut triangles.
#[allow(clippy::too_many_arguments)]
pub fn plan_frame_steps(
    adaptive: Option<Res<AdaptiveSteps>>,
    clock: Res<SimClock>,
    gravity: Res<Gravity>,
    colliders: Query<&Collider>,
    cloths: Query<(&Cloth, &Particles, &Triangles, Has<SelfCollision>)>,
    mut states: Local<Vec<[ColliderState; 2]>>,
    mut settings: ResMut<StepSettings>,
    mut touching: Query<&mut SelfTouching>,
) {
    let Some(adaptive) = adaptive else {
        return;
    };
    let (now, frame_time) = (clock.time_s as f32, adaptive.frame_time);
    states.clear();
    states.extend(colliders.iter().map(|c| [c.motion.state_at(now), c.motion.state_at(now + frame_time)]));
    let (sum, count) =
        cloths.iter().filter(|(.., colliding)| *colliding).fold((Vec3::ZERO, 0), |(sum, count), (_, particles, ..)| {
            (sum + particles.velocity.iter().sum::<Vec3>(), count + particles.len())
        });
    let common = sum / count.max(1) as f32;
    let gained = gravity.0.length() * frame_time;
    let reach = cloths
        .iter()
        .map(|(cloth, particles, triangles, colliding)| {
            let sides: f32 = triangles.side_lengths(&particles.rest_position).map(|s| s.iter().sum::<f32>()).sum();
            let edge = sides / (3 * triangles.len()).max(1) as f32;
            let fastest = particles
                .position
                .iter()
                .zip(&particles.velocity)
                .map(|(&p, &v)| {
                    let speed = v.length();
                    let own = if colliding { (v - common).length() } else { 0.0 };
                    colliders
                        .iter()
                        .zip(states.iter())
                        .filter_map(|(collider, [start, end])| {
                            let surface = start.velocity_at(p).length().max(end.velocity_at(p).length());
                            let gap = collider.shape.distance_to_point(&start.pose, p, true)
                                - collider.contact_thickness(cloth.thickness)
                                - collider.response.reach();
                            (gap <= REACH_SLACK * frame_time * (speed + gained + surface)).then_some(speed + surface)
                        })
                        .fold(own, f32::max)
                })
                .fold(0.0, f32::max);
            if edge > 0.0 { fastest * frame_time / edge } else { f32::INFINITY }
        })
        .fold(0.0, f32::max);
    let last = settings.dt;
    *settings = adaptive.settings(adaptive.steps(reach));
    if settings.dt != last {
        for spring in touching.iter_mut().flat_map(|t| t.into_inner().springs.iter_mut()) {
            spring.restep(last, settings.dt);
        }
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.frame.add_systems(plan_frame_steps.in_set(FrameSystems::Prepare));
    schedules.frame.add_systems(run_substeps.in_set(FrameSystems::Substeps));
}
