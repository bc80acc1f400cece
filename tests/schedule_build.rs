//! The schedules build with ambiguity detection set to error: no two systems touch the
//! same data without an order between them.

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::LogLevel;
use selvedge::components::Particles;
use selvedge::schedule::{SubstepSystems, build_schedules};

#[test]
fn every_schedule_initializes_without_ambiguities() {
    let mut world = World::new();
    let mut schedules = build_schedules();
    for schedule in [&mut schedules.frame, &mut schedules.substep, &mut schedules.probe, &mut schedules.render] {
        assert_eq!(schedule.get_build_settings().ambiguity_detection, LogLevel::Error);
        if let Err(error) = schedule.initialize(&mut world) {
            panic!("{:?} does not build: {}", schedule.label(), error.to_string(schedule.graph(), &world));
        }
    }
}

#[test]
fn an_unordered_conflict_would_be_caught() {
    fn nudge(mut particles: Query<&mut Particles>) {
        for mut p in &mut particles {
            p.velocity.clear();
        }
    }
    let mut world = World::new();
    let mut schedules = build_schedules();
    schedules.substep.add_systems(nudge.in_set(SubstepSystems::Integrate));
    assert!(
        schedules.substep.initialize(&mut world).is_err(),
        "a second writer of Particles in one set must be refused"
    );
}
