//! Zheng's slope test (§3.7.1): a cloth falling onto a 30° slope presses on it with
//! ρ g cos 30° = 1.2217 Pa; with μ = 0.2 it slides with acceleration g (sin 30° − μ cos 30°)
//! under a friction stress μ ρ g cos 30° = 0.2443 Pa; with μ = tan 30° + 0.01 it sticks, the
//! friction carrying ρ g sin 30° = 0.7053 Pa. Both as Zheng ran them (explicit, small
//! steps, impulses) and at one implicit step a frame, where the resting cloth is held by
//! the solve's constraints and static friction holds it fast.

mod common;

use glam::Vec3;
use selvedge::Simulation;
use selvedge::components::Particles;
use selvedge::solver::integrate::Integrator;

const RHO: f64 = 0.14395;
const G: f64 = 9.8;

/// The bundled scene, as it is (explicit, 20 steps a frame), or with an implicit
/// integrator at the given steps a frame, where the slope holds the resting cloth by
/// constraints in the solve and friction comes from their push.
fn simulation(name: &str, implicit: Option<(Integrator, u32)>) -> Simulation {
    common::bundled_with(name, |scene| {
        if let Some((integrator, steps)) = implicit {
            scene.solver.integrator = integrator;
            scene.solver.substeps = Some(steps);
        }
    })
}

/// One implicit Euler step a frame (1/60 s).
const FRAME_STEPS: Option<(Integrator, u32)> = Some((Integrator::ImplicitEuler, 1));

/// Mean position and velocity of the cloth.
fn centre(sim: &mut Simulation) -> (Vec3, Vec3) {
    let p = sim.world_mut().query::<&Particles>().single(sim.world()).expect("one cloth").clone();
    let n = p.len() as f32;
    (p.position.iter().sum::<Vec3>() / n, p.velocity.iter().sum::<Vec3>() / n)
}

fn probe(sim: &Simulation, name: &str) -> f64 {
    sim.probes().get(name).unwrap_or_else(|| panic!("no probe {name}"))
}

/// Steps to time `t` [s], checking pressure (and friction stress) on every frame after
/// the cloth has landed.
fn run_until(sim: &mut Simulation, t: f64, friction_stress: f64) {
    let pressure = RHO * G * 30f64.to_radians().cos();
    while sim.clock().time_s < t - 1e-9 {
        sim.step_frame().unwrap_or_else(|e| panic!("{e}"));
        if sim.clock().time_s > 0.3 {
            let measured = probe(sim, "contact_pressure_pa");
            assert!(
                (measured - pressure).abs() < 0.01 * pressure,
                "pressure {measured} Pa at {} s",
                sim.clock().time_s
            );
            let measured = probe(sim, "friction_stress_pa");
            assert!((measured - friction_stress).abs() < 0.02 * friction_stress, "friction {measured} Pa");
            assert!(probe(sim, "max_penetration_m") <= 0.001, "the cloth stays out of the slope");
        }
    }
}

#[test]
fn with_mu_0_2_the_cloth_slides_at_the_coulomb_acceleration() {
    slides_at_the_coulomb_acceleration(None);
}

#[test]
fn with_mu_0_2_the_cloth_slides_at_the_coulomb_acceleration_at_implicit_frame_steps() {
    slides_at_the_coulomb_acceleration(FRAME_STEPS);
}

#[test]
fn with_mu_0_2_the_cloth_slides_at_the_coulomb_acceleration_under_block_descent() {
    // At four steps a frame; at one, see the next test.
    slides_at_the_coulomb_acceleration(Some((Integrator::BlockDescent, 4)));
}

#[test]
fn with_mu_0_2_block_descent_at_one_step_a_frame_slides_on_as_fast_as_it_goes() {
    // The contact constraints hold the sliding cloth on the slope, so its moves along the
    // slope have a normal part of round-off alone; the slope's plane in its sweeps' bounds
    // once cut those moves whole, and from 3.5 m/s (1.13 s) the cloth slowed at 1.2 m/s².
    // Its 60 sweeps a step leave 1.6 % of the pull along the slope unsolved (free fall
    // along it at 4.82 m/s² instead of 4.90), so its acceleration is 3.12 m/s² against
    // Coulomb's 3.20: within 3 %, and the same as the slide grows to 6 m/s.
    let mut sim = simulation("zheng_slope.ron", Some((Integrator::BlockDescent, 1)));
    let friction_stress = 0.2 * RHO * G * 30f64.to_radians().cos();
    let downhill = Vec3::new(30f32.to_radians().cos(), -30f32.to_radians().sin(), 0.0);
    let mut speeds = Vec::new();
    for t in [0.5, 1.1, 1.9] {
        run_until(&mut sim, t, friction_stress);
        let (_, v) = centre(&mut sim);
        speeds.push((sim.clock().time_s, f64::from(v.dot(downhill))));
    }
    let accelerations: Vec<f64> = speeds.windows(2).map(|w| (w[1].1 - w[0].1) / (w[1].0 - w[0].0)).collect();
    let expected = G * (0.5 - 0.2 * 30f64.to_radians().cos());
    assert!(speeds[2].1 > 5.5, "the slide reached {} m/s", speeds[2].1);
    for a in &accelerations {
        assert!((a - expected).abs() < 0.03 * expected, "accelerations {accelerations:?} m/s², expected {expected}");
    }
    assert!(
        (accelerations[1] - accelerations[0]).abs() < 0.005 * expected,
        "the slide slows as it grows: {accelerations:?} m/s²"
    );
}

#[test]
fn with_mu_above_tan_30_the_cloth_sticks() {
    sticks(None);
}

#[test]
fn with_mu_above_tan_30_the_cloth_sticks_at_implicit_frame_steps() {
    sticks(FRAME_STEPS);
}

#[test]
fn with_mu_above_tan_30_the_cloth_sticks_under_block_descent() {
    // The body's plane stops the landing within the sweeps, so the friction of its push
    // comes from the solve (`push_friction`): without it the cloth slid on after landing,
    // 0.165 m in a second at one step a frame and 0.58 at four.
    sticks(Some((Integrator::BlockDescent, 1)));
    sticks(Some((Integrator::BlockDescent, 4)));
}

fn slides_at_the_coulomb_acceleration(implicit: Option<(Integrator, u32)>) {
    let mut sim = simulation("zheng_slope.ron", implicit);
    let cos30 = 30f64.to_radians().cos();
    let friction_stress = 0.2 * RHO * G * cos30;
    assert!((friction_stress - 0.2443).abs() < 1e-4);
    run_until(&mut sim, 0.5, friction_stress);
    let (t0, (_, v0)) = (sim.clock().time_s, centre(&mut sim));
    run_until(&mut sim, 1.4, friction_stress);
    let (t1, (_, v1)) = (sim.clock().time_s, centre(&mut sim));
    let downhill = Vec3::new(30f32.to_radians().cos(), -30f32.to_radians().sin(), 0.0);
    let acceleration = f64::from((v1 - v0).dot(downhill)) / (t1 - t0);
    let expected = G * (0.5 - 0.2 * cos30);
    assert!((acceleration - expected).abs() < 0.02 * expected, "acceleration {acceleration} m/s², expected {expected}");
}

fn sticks(implicit: Option<(Integrator, u32)>) {
    let mut sim = simulation("zheng_slope_stick.ron", implicit);
    let hold = RHO * G * 0.5;
    assert!((hold - 0.7053).abs() < 1e-4);
    run_until(&mut sim, 0.5, hold);
    let (start, _) = centre(&mut sim);
    run_until(&mut sim, 1.5, hold);
    let (end, _) = centre(&mut sim);
    assert!((end - start).length() < 1e-3, "slid {} m in a second", (end - start).length());
}
