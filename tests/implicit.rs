//! The implicit solvers at large steps: a 32 × 32 cotton sheet pinned at two corners,
//! released horizontal, stays bounded and comes to rest with its pins carrying its weight
//! under Newmark at Bricis's Δt = 0.1 s and under implicit Euler at Δt = 1/30 s. The
//! explicit integrators at 1/30 s are reported as diverging, without a panic.

mod common;

use selvedge::Simulation;
use selvedge::solver::integrate::Integrator;

const COTTON_DENSITY: f64 = 0.2578;
const G: f64 = 9.81;

fn sheet(solver: &str, fps: u32, seconds: f32) -> Simulation {
    common::simulation(&format!(
        "Scene(name: \"sheet\", solver: {solver}, time: (fps: {fps}, duration_s: {seconds}),
          cloths: [(name: \"cotton\", shape: Grid(size: (1.0, 1.0), resolution: (32, 32)),
                    placement: (translation: (0.0, 1.5, 0.0), rotation_deg: (90.0, 0.0, 0.0)),
                    fabric: Named(Cotton), pins: [Corners([BottomLeft, BottomRight])])])"
    ))
}

/// Runs to the end, checking the sheet stays bounded (no divergence, no edge stretched
/// beyond `strain_bound`), and returns (kinetic energy [J], pin force [N]).
fn settle(mut sim: Simulation, strain_bound: f64) -> (f64, f64) {
    let frames = sim.counts().time.frames;
    let mut peak_kinetic = 0.0f64;
    for _ in 0..frames {
        sim.step_frame().unwrap_or_else(|e| panic!("{e}"));
        peak_kinetic = peak_kinetic.max(common::probe(&sim, "kinetic_energy_j"));
        let strain = common::probe(&sim, "max_strain");
        assert!(strain < strain_bound, "strain {strain} at t = {} s", sim.clock().time_s);
    }
    assert!(peak_kinetic > 0.01, "the sheet swings down first: peak {peak_kinetic} J");
    (common::probe(&sim, "kinetic_energy_j"), common::probe(&sim, "pin_force_n"))
}

#[test]
fn newmark_at_a_tenth_of_a_second_comes_to_rest_carrying_the_weight() {
    let sim = sheet(
        "(integrator: Newmark, substeps: 1, rayleigh: Critical(omega1: 0.3, omega2: 0.9), cg_tolerance: 1e-5)",
        10,
        30.0,
    );
    // The swing down takes three steps of 0.1 s; the linearised trapezoidal step overshoots
    // into a stretch near the pins (up to about 96 %) that Bricis's β = 1.67 s lets creep
    // back over seconds. Newmark at this step is for quasi-static drape, as in the thesis.
    let (kinetic, pin_force) = settle(sim, 1.0);
    let weight = COTTON_DENSITY * G;
    assert!(kinetic < 1e-6, "still moving: {kinetic:e} J");
    assert!((pin_force - weight).abs() < 0.005 * weight, "pins carry {pin_force} N, the sheet weighs {weight} N");
}

#[test]
fn implicit_euler_at_a_thirtieth_of_a_second_comes_to_rest_carrying_the_weight() {
    let sim = sheet("(integrator: ImplicitEuler, substeps: 1, cg_tolerance: 1e-5)", 30, 15.0);
    let (kinetic, pin_force) = settle(sim, 0.5);
    let weight = COTTON_DENSITY * G;
    assert!(kinetic < 1e-6, "still moving: {kinetic:e} J");
    assert!((pin_force - weight).abs() < 0.005 * weight, "pins carry {pin_force} N, the sheet weighs {weight} N");
}

#[test]
fn explicit_integrators_at_a_thirtieth_of_a_second_are_reported_as_diverging() {
    for method in Integrator::ALL
        .into_iter()
        .filter(|m| !matches!(m, Integrator::ImplicitEuler | Integrator::Newmark | Integrator::Rk45))
    {
        let mut sim = sheet(&format!("(integrator: {}, substeps: 1)", method.name()), 30, 2.0);
        let frames = sim.counts().time.frames;
        let outcome = (0..frames).try_for_each(|_| sim.step_frame());
        let divergence = outcome.expect_err(&format!("{method:?} should not survive Δt = 1/30 s"));
        assert_eq!(divergence.cloth, "cotton");
        assert!(divergence.frame >= 1 && divergence.frame <= u64::from(frames), "{divergence}");
    }
}
