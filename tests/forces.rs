//! External forces through the whole engine against closed-form motion: linear drag
//! (terminal velocity), wind on a facing cloth, and user forces.

mod common;

use glam::Vec3;
use selvedge::Simulation;
use selvedge::components::Particles;

/// Mass-weighted mean velocity of the only cloth.
fn mean_velocity(sim: &mut Simulation) -> Vec3 {
    let p = sim.world_mut().query::<&Particles>().single(sim.world()).expect("one cloth").clone();
    let mass = p.total_mass();
    (0..p.len()).map(|i| p.mass(i) * p.velocity[i]).sum::<Vec3>() / mass
}

fn free_sheet(gravity: &str, air: &str, extra: &str) -> Simulation {
    common::simulation(&format!(
        "Scene(name: \"forces\", gravity: {gravity}, air: {air}, solver: (integrator: Rk4, substeps: 10),
          time: (fps: 60, frames: 600),
          cloths: [(name: \"c\", shape: Grid(size: (1.0, 1.0), resolution: (8, 8)), material: {} {extra})])",
        common::material(100.0, 0.05)
    ))
}

#[test]
fn linear_drag_gives_the_exponential_approach_to_terminal_velocity() {
    let drag = 2.0f32;
    let mut sim = free_sheet("(0.0, -9.81, 0.0)", &format!("(drag: {drag})"), "");
    common::run_frames(&mut sim, 60);
    let t = sim.clock().time_s as f32;
    // m dv/dt = m g − c m v  ⇒  v(t) = (g / c)(1 − e^{−c t}).
    let expected = -(9.81 / drag) * (1.0 - (-drag * t).exp());
    let v = mean_velocity(&mut sim).y;
    assert!((v - expected).abs() < 1e-4 * expected.abs(), "v = {v}, expected {expected}");
}

#[test]
fn wind_on_a_facing_cloth_pushes_with_drag_times_area_times_speed_squared() {
    // The sheet lies in the XY plane; wind along +Z meets it face on.
    let (wind, wind_drag, mass) = (4.0f32, 0.6f32, 0.2f32);
    let mut sim = free_sheet("(0.0, 0.0, 0.0)", &format!("(wind: (0.0, 0.0, {wind}), wind_drag: {wind_drag})"), "");
    common::run_frames(&mut sim, 1);
    let t = sim.clock().time_s as f32;
    // While the cloth is slow against the wind, F = k A u² with u = wind − v:
    // m dv/dt = k A (w − v)²  ⇒  v(t) = w − 1 / (1/w + k A t / m).
    let rate = wind_drag * 1.0 / mass;
    let expected = wind - 1.0 / (1.0 / wind + rate * t);
    let v = mean_velocity(&mut sim);
    assert!((v.z - expected).abs() < 1e-3 * expected, "v = {v}, expected {expected} along z");
    assert!(v.x.abs() < 1e-6 && v.y.abs() < 1e-6, "wind along the normal pushes along the normal only");
}

#[test]
fn a_user_force_accelerates_the_centre_of_mass_by_force_over_mass() {
    let force = Vec3::new(0.1, 0.0, 0.05);
    let mut sim = free_sheet(
        "(0.0, 0.0, 0.0)",
        "()",
        &format!(", user_forces: [(particle: 5, force: ({}, {}, {}))]", force.x, force.y, force.z),
    );
    common::run_frames(&mut sim, 30);
    let t = sim.clock().time_s as f32;
    let expected = force / 0.2 * t;
    let v = mean_velocity(&mut sim);
    assert!((v - expected).length() < 1e-4 * expected.length(), "v = {v}, expected {expected}");
}
