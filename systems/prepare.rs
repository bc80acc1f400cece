//! Rebuilding derived caches when a cloth's structure changed.

use bevy_ecs::prelude::*;

use crate::components::{ClothTopology, Csr, Particles, Pins, Springs, Triangles};
use crate::schedule::{FrameSystems, SimSchedules};

/// Rebuilds the incidence rows and the free inverse masses of every cloth whose springs,
/// triangles or pins changed since the last frame (and of new cloths); others keep
/// theirs. Runs in [`FrameSystems::Prepare`].
pub fn rebuild_cloth_topology(
    mut cloths: Query<
        (&Particles, &Springs, &Triangles, &Pins, &mut ClothTopology),
        Or<(Changed<Springs>, Changed<Triangles>, Changed<Pins>)>,
    >,
) {
    for (particles, springs, triangles, pins, mut topology) in &mut cloths {
        let count = particles.len();
        topology.particle_springs = Csr::from_items(count, &springs.pairs);
        topology.particle_triangles = Csr::from_items(count, &triangles.indices);
        topology.free_inv_mass.clone_from(&particles.inv_mass);
        for &p in &pins.particles {
            topology.free_inv_mass[p as usize] = 0.0;
        }
        topology.builds += 1;
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules
        .frame
        .add_systems(rebuild_cloth_topology.in_set(FrameSystems::Prepare));
}
