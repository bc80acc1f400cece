//! Durupınar's response regimes (D11) against statics: a cloth that falls onto a floor
//! with the penalty response comes to rest where the penalty pressure carries its weight,
//! k (T_outside − d) = ρ g, and the contact pressure it reports is ρ g.

mod common;

use selvedge::components::Particles;

#[test]
fn a_cloth_rests_on_the_penalty_at_the_depth_that_carries_its_weight() {
    let mut sim = common::bundled("durupinar_regimes.ron");
    common::run_frames(&mut sim, 120);
    let particles = sim.world_mut().query::<&Particles>().single(sim.world()).expect("one cloth").clone();
    let heights: Vec<f32> = particles.position.iter().map(|x| x.y).collect();
    let mean = heights.iter().sum::<f32>() / heights.len() as f32;
    // Thickness 1 mm + T_outside 10 mm − ρ g / k.
    let expected = 0.001 + 0.01 - 0.2 * 9.81 / 1000.0;
    assert!((mean - expected).abs() < 0.01 * expected, "rests at {mean} m, statics say {expected} m");
    let spread = heights.iter().fold(0.0f32, |m, &y| m.max((y - mean).abs()));
    assert!(spread < 2e-4, "flat on the floor, heights within {spread} m of the mean");
    let pressure = common::probe(&sim, "contact_pressure_pa");
    assert!((pressure - 1.962).abs() < 0.01 * 1.962, "contact pressure {pressure} Pa, ρ g = 1.962 Pa");
    assert!(common::probe(&sim, "max_penetration_m") <= 0.0, "never behind the surface");
}
