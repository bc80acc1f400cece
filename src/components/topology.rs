//! Caches derived from a cloth's structure, and per-cloth scratch space.

use bevy_ecs::prelude::*;
use glam::Vec3;

use crate::solver::forces::ForceScratch;
use crate::solver::integrate::IntegratorWorkspace;

/// Compressed rows: for each particle, the list of items (springs, triangles) touching it,
/// in ascending item order so that sums over them are deterministic.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Csr {
    /// Row `i` is `items[offsets[i]..offsets[i + 1]]`.
    pub offsets: Vec<u32>,
    /// Item indices, grouped by row.
    pub items: Vec<u32>,
}

impl Csr {
    /// Builds the rows of `row_count` particles from items that each touch a few particles.
    pub fn from_items<const N: usize>(row_count: usize, items: &[[u32; N]]) -> Self {
        let mut offsets = vec![0u32; row_count + 1];
        for item in items {
            for &p in item {
                offsets[p as usize + 1] += 1;
            }
        }
        for i in 0..row_count {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut rows = vec![0u32; offsets[row_count] as usize];
        for (index, item) in items.iter().enumerate() {
            for &p in item {
                rows[fill[p as usize] as usize] = index as u32;
                fill[p as usize] += 1;
            }
        }
        Self {
            offsets,
            items: rows,
        }
    }

    /// The items of row `row`.
    pub fn row(&self, row: usize) -> &[u32] {
        &self.items[self.offsets[row] as usize..self.offsets[row + 1] as usize]
    }
}

/// Structure derived from [`Springs`](crate::components::Springs),
/// [`Triangles`](crate::components::Triangles) and [`Pins`](crate::components::Pins):
/// rebuilt only when change detection says one of them changed.
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct ClothTopology {
    /// Springs touching each particle.
    pub particle_springs: Csr,
    /// Triangles touching each particle.
    pub particle_triangles: Csr,
    /// Inverse mass with pinned particles at zero [1/kg]: what the integrators accelerate.
    pub free_inv_mass: Vec<f32>,
    /// How many times this cache was built; lets tests see it is not rebuilt every step.
    pub builds: u32,
}

/// Per-cloth scratch buffers for integrators and force evaluation, reused every step so the
/// step path does not allocate once sized.
#[derive(Component, Debug, Default)]
pub struct SolverWorkspace {
    /// Stage buffers of the integrators.
    pub integrator: IntegratorWorkspace,
    /// Per-element force buffers of the force model.
    pub forces: ForceScratch,
    /// Forces at an intermediate state [N], for stage evaluations and probes.
    pub force: Vec<Vec3>,
}

/// What an embedding renderer needs each frame: vertex normals beside the particle
/// positions, refreshed once per frame in the render schedule.
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct RenderMesh {
    /// Area-weighted unit vertex normals, parallel to the particles.
    pub normals: Vec<Vec3>,
}
