//! A keyframed collider's surface velocity reaches contact: a cloth lying on a platform
//! that slides sideways at 0.5 m/s is carried along at the platform's speed by friction,
//! and stays on top of it.

mod common;

use glam::Vec3;
use selvedge::components::Particles;

#[test]
fn a_moving_platform_carries_the_cloth_on_it() {
    // 60 substeps: the light corner particles of a 10 × 10 grid need ω h < 2.
    let mut sim = common::simulation(&format!(
        "Scene(name: \"carry\", solver: (integrator: SymplecticEuler, substeps: 60), time: (fps: 60, duration_s: 2.0),
          cloths: [(name: \"c\", shape: Grid(size: (0.3, 0.3), resolution: (10, 10)),
                    placement: (translation: (0.0, 0.102, 0.0), rotation_deg: (-90.0, 0.0, 0.0)),
                    material: {}, thickness: 0.001)],
          colliders: [(name: \"platform\", shape: Cuboid(half_extents: (1.0, 0.05, 1.0)),
                       keyframes: [(0.5, (translation: (0.0, 0.05, 0.0))), (2.5, (translation: (1.0, 0.05, 0.0)))],
                       friction: 1.0)])",
        common::material(100.0, 0.05)
    ));
    common::run_frames(&mut sim, 120);
    let p = sim.world_mut().query::<&Particles>().single(sim.world()).expect("one cloth").clone();
    let n = p.len() as f32;
    let velocity = p.velocity.iter().sum::<Vec3>() / n;
    let lowest = p.position.iter().map(|x| x.y).fold(f32::INFINITY, f32::min);
    assert!((velocity.x - 0.5).abs() < 0.005, "cloth moves at {velocity} m/s, platform at 0.5 m/s along x");
    assert!(velocity.y.abs() < 1e-3 && velocity.z.abs() < 1e-3);
    assert!((lowest - 0.101).abs() < 1e-4, "the cloth rests on the platform top plus its thickness: {lowest}");
}
