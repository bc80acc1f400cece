//! Rigid props coupled both ways with cloth (E5). A light ball dropped on a hammock sinks
//! into it and rests, and the pins then carry the weight of cloth and ball together,
//! which they can only do if the cloth's push on the prop and the prop's on the cloth
//! balance; a box landing tilted on it is carried too, but does not yet come to rest (an
//! ignored test says how far it is from resting). A ball pulled through a hanging sheet
//! drags it along, and its momentum is the pull's impulse less what it gave the cloth.

mod common;

use glam::Vec3;
use parry3d::math::Pose3;
use selvedge::Simulation;
use selvedge::collision::collider::{ColliderMotion, ColliderState};
use selvedge::components::{Collider, ContactStats, Particles, Prop};

/// The weight [N] of the hammock of prop_hammock.ron and prop_box.ron (1 m × 0.6 m of
/// 0.2 kg/m²) with the 0.15 kg prop on it.
const LOADED_HAMMOCK: f64 = (0.2 * 1.0 * 0.6 + 0.15) * 9.81;

/// The prop's state.
fn prop_state(sim: &mut Simulation) -> ColliderState {
    let world = sim.world_mut();
    let mut query = world.query::<(&Collider, &Prop)>();
    let (collider, _) = query.single(world).expect("one prop");
    match collider.motion {
        ColliderMotion::Driven(state) => state,
        _ => panic!("a prop's collider is driven by its body"),
    }
}

#[test]
fn a_light_ball_sinks_into_a_hammock_and_rests_there() {
    let mut sim = common::bundled("prop_hammock.ron");
    let weight = LOADED_HAMMOCK;
    common::run_frames(&mut sim, 150);
    let settled = prop_state(&mut sim).pose.translation;
    let mut pins = 0.0;
    for _ in 0..30 {
        common::run_frames(&mut sim, 1);
        pins += common::probe(&sim, "pin_force_n") / 30.0;
        assert!(common::probe(&sim, "max_penetration_m") <= 0.002, "the ball stays out of the cloth's thickness");
    }
    let end = prop_state(&mut sim).pose.translation;
    assert!((pins - weight).abs() < 0.02 * weight, "pins carry {pins} N, cloth and ball weigh {weight} N");
    assert!(end.y - 0.1 < 0.95, "the ball sank into the hammock: its bottom is at {} m", end.y - 0.1);
    assert!(
        (end - settled).length() < 0.002,
        "and rests: it moved {} m in the last half second",
        (end - settled).length()
    );
}

/// What a box dropped as in prop_box.ron, moved by `(dx, dz)` [m] across the hammock, did
/// over its last second of four: the pins' mean force [N] and the box's poses. Every frame
/// it checks that no cloth triangle crosses the box and that the box stays out of the
/// cloth's thickness.
fn drop_box(dx: f32, dz: f32) -> (f64, Vec<Pose3>) {
    let mut sim = common::bundled_with("prop_box.ron", |scene| {
        scene.props[0].pose.translation += Vec3::new(dx, 0.0, dz);
    });
    let (frames, last) = (240, 60);
    let mut pins = 0.0;
    let mut places = Vec::new();
    for frame in 0..frames {
        common::run_frames(&mut sim, 1);
        let crossed = common::body_crossings(&mut sim, "box");
        assert_eq!(crossed, 0, "{crossed} cloth triangles cross the box's faces at frame {frame}");
        assert!(common::probe(&sim, "max_penetration_m") <= 0.002, "the box stays out of the cloth's thickness");
        if frame >= frames - last {
            pins += common::probe(&sim, "pin_force_n") / f64::from(last);
            places.push(prop_state(&mut sim).pose);
        }
    }
    (pins, places)
}

#[test]
fn a_light_box_landing_tilted_on_a_stiff_hammock_is_carried_by_it() {
    // Coupled after the cloth's step, this box was thrown off within a second: the
    // hammock's apparent inertia is many times the box's (strong coupling, ARCHITECTURE.md).
    // Without the box's edges meeting the cloth's, 22 cloth triangles crossed its rim.
    let (pins, places) = drop_box(0.0, 0.0);
    // The box keeps rocking on the hammock (the next test), so over the last second the
    // pins carry the weight only to within a few per cent: 0.04 to 2.2 % in drops moved
    // by up to 2 mm.
    let weight = LOADED_HAMMOCK;
    assert!((pins - weight).abs() < 0.03 * weight, "pins carry {pins} N, cloth and box weigh {weight} N");
    let end = places[places.len() - 1];
    // It sank into the hammock, its bottom 5 cm below the pins (the ball, on a smaller
    // patch, sinks further).
    assert!(end.translation.y - 0.05 < 0.96, "the box's bottom is at {} m", end.translation.y - 0.05);
    // On its 20 × 20 cm face, the face's normal within 10° of vertical (the hammock's sag
    // tilts it a little, not the way it was dropped).
    let up = end.rotation * Vec3::Y;
    assert!(up.y.abs() > 10f32.to_radians().cos(), "the box's face normal is {up}");
}

#[test]
#[ignore = "known defect: the box keeps rocking on the hammock (ARCHITECTURE.md, props)"]
fn a_light_box_on_a_stiff_hammock_comes_to_rest_wherever_it_lands() {
    // Dropped where prop_box.ron drops it and moved by 1 or 2 mm along x or z, the box
    // should rest over its last second in every drop: within 2 mm and 0.02 rad of where it
    // ends, the pins carrying the weight to 0.5 %. Today it rests in 3 of 8 (rms spin 0.12
    // to 0.43 rad/s); which ones changes with any change of rounding.
    let drops = [
        (0.0, 0.0),
        (-0.002, 0.0),
        (-0.001, 0.0),
        (0.001, 0.0),
        (0.002, 0.0),
        (0.0, -0.002),
        (0.0, 0.001),
        (0.0, 0.002),
    ];
    let mut restless = Vec::new();
    for (dx, dz) in drops {
        let (pins, places) = drop_box(dx, dz);
        let end = places[places.len() - 1];
        let strayed = places.iter().map(|p| (p.translation - end.translation).length()).fold(0.0, f32::max);
        let turned = places.iter().map(|p| p.rotation.angle_between(end.rotation)).fold(0.0, f32::max);
        let off = (pins - LOADED_HAMMOCK) / LOADED_HAMMOCK;
        if strayed >= 0.002 || turned >= 0.02 || off.abs() >= 0.005 {
            restless.push(format!("({dx}, {dz}) m: strayed {strayed} m, turned {turned} rad, pins {off:+.4}"));
        }
    }
    assert!(restless.is_empty(), "the box did not rest in {} drops: {restless:#?}", restless.len());
}

#[test]
fn a_ball_pulled_through_a_hanging_sheet_drags_it_and_momentum_balances() {
    let mut sim = common::bundled("prop_pull.ron");
    let (mass, pull, frames) = (0.2, 1.5, 90);
    let start = prop_state(&mut sim).pose.translation;
    let mut given = Vec3::ZERO;
    let mut furthest = f32::MIN;
    for _ in 0..frames {
        common::run_frames(&mut sim, 1);
        assert!(common::probe(&sim, "max_penetration_m") <= 0.002, "the ball stays out of the cloth's thickness");
        let world = sim.world_mut();
        let mut cloth = world.query::<(&Particles, &ContactStats)>();
        let (particles, stats) = cloth.single(world).expect("one cloth");
        given += stats.0.impulse;
        let centroid = particles.position.iter().sum::<Vec3>() / particles.len() as f32;
        furthest = furthest.max(centroid.z);
    }
    let end = prop_state(&mut sim);
    let impulse = pull * f64::from(frames) / 60.0;
    // Along the pull only the pull and the cloth act on the ball (its weight is borne).
    let momentum = mass * f64::from(end.linear.z) + f64::from(given.z);
    assert!((momentum - impulse).abs() < 0.005 * impulse, "ball + cloth momentum {momentum} N·s, pull {impulse} N·s");
    assert!(f64::from(given.z) > 0.1 * impulse, "the cloth took {} N·s of the ball's momentum", given.z);
    assert!(furthest > 0.2, "the sheet was dragged {furthest} m along the pull");
    assert!(end.pose.translation.z - start.z > 2.0, "the ball came out on the far side");
}
