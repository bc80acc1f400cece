//! Rigid props (E5): the rapier3d world advances by each cloth step, before the cloth, and
//! the props' colliders take the bodies' new states; cloth contact then pushes the bodies
//! back. A prop's velocity is an unknown of the cloth's implicit step, which holds the
//! particles resting on it (see [`crate::collision::coupling`]); the contacts after the
//! step push it by what they give the cloth (see [`super::contacts::collide_with_bodies`]).

use bevy_ecs::prelude::*;

use crate::collision::collider::{ColliderMotion, ColliderState};
use crate::collision::coupling::BodyCoupling;
use crate::components::{Collider, Prop, RigidStandIn};
use crate::resources::{Gravity, PropWorld, SimClock, StepSettings};
use crate::schedule::{SimSchedules, SubstepSystems};

/// Moves the colliders' stand-ins to where the colliders will be at the end of the step,
/// steps the rigid world by the cloth's step and gravity, and sets every prop's collider
/// to its body's new state. Runs in [`SubstepSystems::Props`].
pub fn step_props(
    clock: Res<SimClock>,
    settings: Res<StepSettings>,
    gravity: Res<Gravity>,
    rigid: Option<ResMut<PropWorld>>,
    stand_ins: Query<(&Collider, &RigidStandIn), Without<Prop>>,
    mut props: Query<(&mut Collider, &mut Prop)>,
) {
    let Some(mut rigid) = rigid else {
        return;
    };
    let rigid = &mut rigid.0;
    let t = clock.step_end(settings.dt);
    for (collider, stand_in) in &stand_ins {
        if let ColliderMotion::Keyframes(_) = collider.motion {
            rigid.bodies[stand_in.body].set_next_kinematic_position(collider.motion.state_at(t).pose);
        }
    }
    rigid.gravity = gravity.0;
    rigid.integration_parameters.dt = settings.dt;
    rigid.step();
    for (mut collider, mut prop) in &mut props {
        let body = &rigid.bodies[prop.body];
        collider.motion = ColliderMotion::Driven(ColliderState::of_body(body));
        prop.coupling = BodyCoupling::of_body(body);
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.substep.add_systems(step_props.in_set(SubstepSystems::Props));
}
