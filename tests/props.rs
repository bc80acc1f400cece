//! Rigid props coupled both ways with cloth (E5): a light ball dropped on a hammock sinks
//! into it and rests, and the pins then carry the weight of cloth and ball together, which
//! they can only do if the cloth's push on the ball and the ball's on the cloth balance.

mod common;

use glam::Vec3;
use selvedge::Simulation;
use selvedge::collision::collider::ColliderMotion;
use selvedge::components::{Collider, Prop};

/// The prop's centre.
fn prop_centre(sim: &mut Simulation) -> Vec3 {
    let world = sim.world_mut();
    let mut query = world.query::<(&Collider, &Prop)>();
    let (collider, _) = query.single(world).expect("one prop");
    match collider.motion {
        ColliderMotion::Driven(state) => state.pose.translation,
        _ => panic!("a prop's collider is driven by its body"),
    }
}

#[test]
fn a_light_ball_sinks_into_a_hammock_and_rests_there() {
    let mut sim = common::bundled("prop_hammock.ron");
    let weight = (0.2 * 1.0 * 0.6 + 0.15) * 9.81;
    common::run_frames(&mut sim, 150);
    let settled = prop_centre(&mut sim);
    let mut pins = 0.0;
    for _ in 0..30 {
        common::run_frames(&mut sim, 1);
        pins += common::probe(&sim, "pin_force_n") / 30.0;
        assert!(common::probe(&sim, "max_penetration_m") <= 0.002, "the ball stays out of the cloth's thickness");
    }
    let end = prop_centre(&mut sim);
    assert!((pins - weight).abs() < 0.02 * weight, "pins carry {pins} N, cloth and ball weigh {weight} N");
    assert!(end.y - 0.1 < 0.95, "the ball sank into the hammock: its bottom is at {} m", end.y - 0.1);
    assert!(
        (end - settled).length() < 0.002,
        "and rests: it moved {} m in the last half second",
        (end - settled).length()
    );
}
