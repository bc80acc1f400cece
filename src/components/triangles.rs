//! The cloth's surface as triangles.

use bevy_ecs::prelude::*;
use glam::Vec3;

/// Triangles of the cloth surface, counter-clockwise seen from the front, indexing
/// particles. They carry wind forces and make the rendered and exported surface.
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct Triangles {
    /// Particle indices of each triangle.
    pub indices: Vec<[u32; 3]>,
}

impl Triangles {
    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// The lengths of each triangle's sides at `positions` [m], in triangle order: an inner
    /// edge comes twice, once for each triangle.
    pub fn side_lengths<'a>(&'a self, positions: &'a [Vec3]) -> impl Iterator<Item = [f32; 3]> + 'a {
        self.indices.iter().map(move |&[a, b, c]| {
            [(a, b), (b, c), (c, a)].map(|(p, q)| positions[p as usize].distance(positions[q as usize]))
        })
    }
}
