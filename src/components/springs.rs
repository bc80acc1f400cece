//! Damped springs as columns.

use bevy_ecs::prelude::*;
use serde::{Deserialize, Serialize};

/// What a spring models, after Provot's topology: each kind has its own coefficients.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum SpringKind {
    /// Along warp or weft between neighbours: resists stretch.
    Structural,
    /// Across a cell diagonal: resists in-plane shear.
    Shear,
    /// Skipping one particle, or across a shared edge: resists bending.
    Bend,
}

/// The springs of one cloth as columns of equal length. Removing springs tears the cloth
/// there; the [`ClothTopology`](crate::components::ClothTopology) cache follows through
/// change detection.
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct Springs {
    /// The two particles each spring joins.
    pub pairs: Vec<[u32; 2]>,
    /// Rest length [m], > 0.
    pub rest_length: Vec<f32>,
    /// Hooke stiffness [N/m], ≥ 0.
    pub stiffness: Vec<f32>,
    /// Damping along the spring [N·s/m], ≥ 0.
    pub damping: Vec<f32>,
    /// What each spring models.
    pub kind: Vec<SpringKind>,
}

impl Springs {
    /// Number of springs.
    pub fn len(&self) -> usize {
        self.pairs.len()
    }

    /// Whether there are no springs.
    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// Appends one spring.
    pub fn push(&mut self, pair: [u32; 2], rest_length: f32, stiffness: f32, damping: f32, kind: SpringKind) {
        self.pairs.push(pair);
        self.rest_length.push(rest_length);
        self.stiffness.push(stiffness);
        self.damping.push(damping);
        self.kind.push(kind);
    }

    /// Removes every spring for which `remove(index)` is true, keeping the others in order.
    /// Returns how many were removed.
    pub fn remove_where(&mut self, mut remove: impl FnMut(usize) -> bool) -> usize {
        let keep: Vec<bool> = (0..self.len()).map(|s| !remove(s)).collect();
        let before = self.len();
        retain_by(&mut self.pairs, &keep);
        retain_by(&mut self.rest_length, &keep);
        retain_by(&mut self.stiffness, &keep);
        retain_by(&mut self.damping, &keep);
        retain_by(&mut self.kind, &keep);
        before - self.len()
    }
}

fn retain_by<T>(column: &mut Vec<T>, keep: &[bool]) {
    let mut index = 0;
    column.retain(|_| {
        index += 1;
        keep[index - 1]
    });
}
