//! Forces a user or an embedding program applies to particles.

use bevy_ecs::prelude::*;
use glam::Vec3;

/// External forces on chosen particles [N], constant until changed: the hook for mouse
/// drags in an editor or for scripted pulls (Durupınar's user force, D9).
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct UserForces {
    /// `(particle, force [N])` pairs; a particle may appear more than once.
    pub forces: Vec<(u32, Vec3)>,
}
