//! Convergence order of the explicit integrators on a damped oscillator with a known
//! closed-form solution: the state error at t = 1 s must shrink with the step at the method's
//! order, measured as the slope of log(error) against log(step) over several halvings.

mod common;

use common::oscillator::{ParticleSystem, exact_state, natural_frequency, with_tolerance};
use selvedge::solver::integrate::Integrator;

/// Errors at t = 1 s for steps `h0, h0/2, h0/4, ...`.
fn errors(method: Integrator, h0: f64, halvings: u32) -> Vec<(f64, f64)> {
    let oscillator = ParticleSystem::oscillator();
    let (exact_x, exact_v) = exact_state(1.0);
    (0..=halvings)
        .map(|k| {
            let h = h0 / f64::from(1u32 << k);
            let ((x, v), _) = oscillator.oscillator_state(method, h, 1.0, &with_tolerance(0.0));
            // The state error, velocity weighed by 1/ω: unlike the position error alone it
            // never passes through zero by accident of phase.
            (h, (x - exact_x).hypot((v - exact_v) / natural_frequency()))
        })
        .collect()
}

/// Least-squares slope of log(error) against log(h).
fn slope(points: &[(f64, f64)]) -> f64 {
    let logs: Vec<(f64, f64)> = points.iter().map(|(h, e)| (h.ln(), e.ln())).collect();
    let n = logs.len() as f64;
    let (mx, my) = (logs.iter().map(|p| p.0).sum::<f64>() / n, logs.iter().map(|p| p.1).sum::<f64>() / n);
    let num: f64 = logs.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let den: f64 = logs.iter().map(|(x, _)| (x - mx).powi(2)).sum();
    num / den
}

fn assert_order(method: Integrator, h0: f64, halvings: u32, order: f64) {
    let points = errors(method, h0, halvings);
    let measured = slope(&points);
    assert!(
        (measured - order).abs() < 0.3,
        "{method:?}: measured order {measured:.2}, expected {order}; (step, error) = {points:?}"
    );
}

#[test]
fn explicit_euler_is_first_order() {
    assert_order(Integrator::ExplicitEuler, 1e-3, 4, 1.0);
}

#[test]
fn symplectic_euler_is_first_order() {
    assert_order(Integrator::SymplecticEuler, 1e-3, 4, 1.0);
}

#[test]
fn midpoint_is_second_order() {
    assert_order(Integrator::Midpoint, 1e-2, 4, 2.0);
}

#[test]
fn velocity_verlet_is_second_order() {
    assert_order(Integrator::VelocityVerlet, 1e-2, 4, 2.0);
}

#[test]
fn rk4_is_fourth_order() {
    assert_order(Integrator::Rk4, 0.1, 3, 4.0);
}

#[test]
fn rk5_is_fifth_order() {
    assert_order(Integrator::Rk5, 0.2, 3, 5.0);
}
