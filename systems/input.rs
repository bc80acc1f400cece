//! Applying scheduled edits: tears, pins and releases at their time.

use bevy_ecs::prelude::*;

use crate::builders::tear::tear;
use crate::components::{BendingHinges, Cloth, MembraneTriangles, Particles, Pins, Springs, StrainLimit, Triangles};
use crate::resources::{EditAction, ScheduledEdits, SimClock, StepSettings};
use crate::schedule::{FrameSystems, SimSchedules};

/// Applies every edit whose time has come (within half a step, so that rounding of the
/// clock never delays an edit by a frame). Structure changes here are what
/// [`rebuild_cloth_topology`](crate::systems::prepare::rebuild_cloth_topology) picks up.
/// A box selection that holds no particle at that time pins or releases nothing.
/// Runs in [`FrameSystems::Input`].
pub fn apply_scheduled_edits(
    clock: Res<SimClock>,
    settings: Res<StepSettings>,
    mut edits: ResMut<ScheduledEdits>,
    mut cloths: Query<(
        &Cloth,
        &Particles,
        &mut Springs,
        &mut Triangles,
        &mut BendingHinges,
        &mut MembraneTriangles,
        &mut StrainLimit,
        &mut Pins,
    )>,
) {
    let now = clock.time_s + 0.5 * f64::from(settings.dt);
    let due = edits.pending.iter().take_while(|e| e.at_s <= now).count();
    if due == 0 {
        return;
    }
    for edit in edits.pending.drain(..due) {
        let Some((cloth, particles, mut springs, mut triangles, mut hinges, mut membranes, mut limit, mut pins)) =
            cloths.iter_mut().find(|(cloth, ..)| cloth.name == edit.cloth)
        else {
            continue;
        };
        match &edit.action {
            EditAction::Tear(cut) => {
                tear(
                    cut,
                    &particles.position,
                    &particles.rest_position,
                    &mut springs,
                    &mut triangles,
                    &mut hinges,
                    &mut membranes,
                    &mut limit,
                );
            }
            EditAction::Pin(selections) => {
                for particle in
                    selections.iter().flat_map(|s| s.resolve(&particles.position, &cloth.layout).unwrap_or_default())
                {
                    pins.insert(particle, particles.position[particle as usize]);
                }
            }
            EditAction::Unpin(selections) => {
                for particle in
                    selections.iter().flat_map(|s| s.resolve(&particles.position, &cloth.layout).unwrap_or_default())
                {
                    pins.remove(particle);
                }
            }
        }
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.frame.add_systems(apply_scheduled_edits.in_set(FrameSystems::Input));
}
