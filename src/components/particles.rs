//! Per-particle state as columns.

use bevy_ecs::prelude::*;
use glam::Vec3;

/// The particles of one cloth, as structure-of-arrays columns of equal length, indexed by
/// particle number.
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct Particles {
    /// World position [m].
    pub position: Vec<Vec3>,
    /// World velocity [m/s].
    pub velocity: Vec<Vec3>,
    /// Inverse mass [1/kg]; always finite and > 0 (pins hold particles, not infinite masses).
    pub inv_mass: Vec<f32>,
    /// Rest position [m] in the cloth's initial placement: the shape the cloth was cut in.
    pub rest_position: Vec<Vec3>,
    /// Force on each particle at the start of the current step [N]. An implicit
    /// integrator, which evaluates its forces within the step, may leave it zero on the
    /// particles not touching a body (`systems/forces.rs`).
    pub force: Vec<Vec3>,
}

impl Particles {
    /// Particles at rest at `positions` with the given masses [kg], which become their
    /// inverse masses in place (a list freed here would be a large block freed:
    /// [`crate::memory::release`]).
    pub fn at_rest(positions: Vec<Vec3>, mut masses: Vec<f32>) -> Self {
        let count = positions.len();
        for m in &mut masses {
            *m = 1.0 / *m;
        }
        Self {
            velocity: vec![Vec3::ZERO; count],
            inv_mass: masses,
            rest_position: positions.clone(),
            force: vec![Vec3::ZERO; count],
            position: positions,
        }
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Mass of particle `index` [kg].
    pub fn mass(&self, index: usize) -> f32 {
        1.0 / self.inv_mass[index]
    }

    /// Total mass [kg].
    pub fn total_mass(&self) -> f32 {
        self.inv_mass.iter().map(|w| 1.0 / w).sum()
    }
}
