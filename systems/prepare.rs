//! Rebuilding derived caches when a cloth's structure changed.

use bevy_ecs::prelude::*;

use crate::components::{BendingHinges, ClothTopology, MembraneTriangles, Particles, Pins, Springs, Triangles};
use crate::schedule::{FrameSystems, SimSchedules};

/// Rebuilds the incidence rows, the derivative pattern and the free inverse masses of
/// every cloth whose elements or pins changed since the last frame (and of new cloths);
/// others keep theirs. Runs in [`FrameSystems::Prepare`].
pub fn rebuild_cloth_topology(
    mut cloths: Query<
        (&Particles, &Springs, &Triangles, &BendingHinges, &MembraneTriangles, &Pins, &mut ClothTopology),
        Or<(Changed<Springs>, Changed<Triangles>, Changed<BendingHinges>, Changed<MembraneTriangles>, Changed<Pins>)>,
    >,
) {
    for (particles, springs, triangles, hinges, membranes, pins, mut topology) in &mut cloths {
        let builds = topology.builds + 1;
        *topology =
            ClothTopology::build(&particles.inv_mass, springs, triangles, hinges, membranes, &pins.particles, builds);
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.frame.add_systems(rebuild_cloth_topology.in_set(FrameSystems::Prepare));
}
