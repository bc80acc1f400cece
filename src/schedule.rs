//! The four schedules and the order of their system sets: the only place ordering lives.
//! Each file under `systems/` places its systems into these sets and never orders them
//! against another file's systems.

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{LogLevel, ScheduleBuildSettings, ScheduleLabel, SingleThreadedExecutor};

use crate::systems;

/// One frame: `substeps` steps and the per-frame work around them.
#[derive(ScheduleLabel, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct FrameSchedule;

/// One step of length [`StepSettings::dt`](crate::resources::StepSettings), run
/// [`StepSettings::substeps`](crate::resources::StepSettings) times a frame.
#[derive(ScheduleLabel, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SubstepSchedule;

/// Once per frame, after [`FrameSchedule`]: the probes, which measure the frame and
/// change nothing a later frame reads. A schedule of their own, so that a benchmark times
/// the simulation apart from its measurement: the exact self-intersection count and the
/// energies took some 14 % of a 64² hang frame.
#[derive(ScheduleLabel, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ProbeSchedule;

/// Once per frame, after [`ProbeSchedule`]: derived data for renderers and exporters.
#[derive(ScheduleLabel, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RenderSchedule;

/// Sets of [`FrameSchedule`], run in this order:
///
/// 1. [`FrameSystems::Input`]: apply edits that are due (tears, pins, releases).
/// 2. [`FrameSystems::Motion`]: move bodies along their motions (bodies arrive later).
/// 3. [`FrameSystems::Prepare`]: rebuild derived caches of cloths whose structure changed.
/// 4. [`FrameSystems::Substeps`]: run [`SubstepSchedule`] `substeps` times.
/// 5. [`FrameSystems::Finish`]: health check, frame count.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FrameSystems {
    /// Apply edits that are due.
    Input,
    /// Move bodies along their motions.
    Motion,
    /// Rebuild derived caches of changed cloths.
    Prepare,
    /// Run the steps of the frame.
    Substeps,
    /// Health check, frame count.
    Finish,
}

/// Sets of [`SubstepSchedule`], run in this order:
///
/// 1. [`SubstepSystems::Props`]: advance the rigid props (rapier3d) by the step.
/// 2. [`SubstepSystems::Forces`]: accumulate the forces at the start of the step.
/// 3. [`SubstepSystems::Integrate`]: advance positions and velocities by one step.
/// 4. [`SubstepSystems::Constraints`]: move grips, hold pinned particles, limit strain.
/// 5. [`SubstepSystems::BodyContacts`]: contact with colliders, the ground and props, and
///    the cloth's push back on the props.
/// 6. [`SubstepSystems::SelfContacts`]: cloth against cloth.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SubstepSystems {
    /// Advance the rigid props.
    Props,
    /// Accumulate forces.
    Forces,
    /// Advance the state.
    Integrate,
    /// Enforce pins.
    Constraints,
    /// Contact with bodies and the ground.
    BodyContacts,
    /// Contact of cloth with cloth.
    SelfContacts,
}

/// Sets of [`RenderSchedule`]:
///
/// 1. [`RenderSystems::Writeback`]: vertex normals for render meshes and frame files.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RenderSystems {
    /// Refresh render meshes.
    Writeback,
}

/// The schedules while they are being filled, before they go into the world.
pub struct SimSchedules {
    /// The frame schedule.
    pub frame: Schedule,
    /// The step schedule.
    pub substep: Schedule,
    /// The probe schedule.
    pub probe: Schedule,
    /// The render schedule.
    pub render: Schedule,
}

/// A schedule that runs its systems one after another, in a deterministic order, and that
/// refuses to build if two systems touch the same data without an order between them.
fn strict_schedule(label: impl ScheduleLabel) -> Schedule {
    let mut schedule = Schedule::new(label);
    schedule
        .set_executor(SingleThreadedExecutor::new())
        .set_build_settings(ScheduleBuildSettings { ambiguity_detection: LogLevel::Error, ..Default::default() });
    schedule
}

/// Builds the four schedules with every system of [`systems`] in its set.
pub fn build_schedules() -> SimSchedules {
    let mut schedules = SimSchedules {
        frame: strict_schedule(FrameSchedule),
        substep: strict_schedule(SubstepSchedule),
        probe: strict_schedule(ProbeSchedule),
        render: strict_schedule(RenderSchedule),
    };
    schedules.frame.configure_sets(
        (
            FrameSystems::Input,
            FrameSystems::Motion,
            FrameSystems::Prepare,
            FrameSystems::Substeps,
            FrameSystems::Finish,
        )
            .chain(),
    );
    schedules.substep.configure_sets(
        (
            SubstepSystems::Props,
            SubstepSystems::Forces,
            SubstepSystems::Integrate,
            SubstepSystems::Constraints,
            SubstepSystems::BodyContacts,
            SubstepSystems::SelfContacts,
        )
            .chain(),
    );
    schedules.render.configure_sets(RenderSystems::Writeback);
    systems::add_to(&mut schedules);
    schedules
}

/// Builds the schedules and adds them to `world`.
pub fn add_schedules(world: &mut World) {
    let SimSchedules { frame, substep, probe, render } = build_schedules();
    world.add_schedule(frame);
    world.add_schedule(substep);
    world.add_schedule(probe);
    world.add_schedule(render);
}
