//! Refreshing render meshes once per frame.

use bevy_ecs::prelude::*;

use crate::components::{Particles, RenderMesh, Triangles};
use crate::schedule::{RenderSystems, SimSchedules};
use crate::solver::geometry::vertex_normals;

/// Recomputes the vertex normals of every cloth. Runs in [`RenderSystems::Writeback`].
pub fn update_render_normals(mut cloths: Query<(&Particles, &Triangles, &mut RenderMesh)>) {
    for (particles, triangles, mut mesh) in &mut cloths {
        vertex_normals(&particles.position, &triangles.indices, &mut mesh.normals);
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.render.add_systems(update_render_normals.in_set(RenderSystems::Writeback));
}
