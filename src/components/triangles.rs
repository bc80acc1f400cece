//! The cloth's surface as triangles.

use bevy_ecs::prelude::*;

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
}
