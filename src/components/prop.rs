//! The link between a collider entity and its body in the rigid-body world.

use bevy_ecs::prelude::*;
use rapier3d::prelude::RigidBodyHandle;

use crate::collision::coupling::BodyCoupling;

/// A collider that is a free rigid prop (E5): its [`super::Collider`] motion is set from the
/// rapier body every step, and the cloth's push on it goes back to that body.
#[derive(Component, Debug, Clone, Copy, PartialEq)]
pub struct Prop {
    /// The body in [`crate::resources::PropWorld`].
    pub body: RigidBodyHandle,
    /// How the body takes the cloth's push, carried from step to step.
    pub coupling: BodyCoupling,
}

/// A scene collider's stand-in in the rigid-body world, so that props land on it: fixed,
/// or moved along the collider's keyframes.
#[derive(Component, Debug, Clone, Copy, PartialEq)]
pub struct RigidStandIn {
    /// The fixed or kinematic body in [`crate::resources::PropWorld`].
    pub body: RigidBodyHandle,
}
