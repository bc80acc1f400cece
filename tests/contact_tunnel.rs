//! Tunnelling: a cloth thrown at 10 m/s at a 2 mm plate moves 4.2 mm a step, more than the
//! plate is thick, and still never gets below its top face.

mod common;

use selvedge::components::Particles;

#[test]
fn a_fast_cloth_does_not_pass_through_a_thin_plate() {
    let mut sim = common::bundled("tunnel.ron");
    let dt = sim.counts().time.dt;
    assert!(10.0 * dt > 0.002, "the test needs steps longer than the plate is thick");
    let top = 0.001f32;
    for frame in 1..=sim.counts().time.frames {
        sim.step_frame().unwrap_or_else(|e| panic!("{e}"));
        let particles = sim.world_mut().query::<&Particles>().single(sim.world()).expect("one cloth").clone();
        let lowest = particles.position.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
        assert!(lowest >= top, "frame {frame}: a particle reached y = {lowest} m, below the plate's top {top} m");
    }
    let particles = sim.world_mut().query::<&Particles>().single(sim.world()).expect("one cloth").clone();
    assert!(particles.position.iter().all(|p| (p.y - 0.0015).abs() < 1e-4), "resting on the plate at its thickness");
}
