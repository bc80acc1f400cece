//! Adaptive RK45 (Cash–Karp): every accepted step's error estimate stays under the
//! tolerance, the global error follows the tolerance, and on a smooth problem it needs
//! fewer steps than fixed-step RK4 for the same accuracy.

mod common;

use common::oscillator::{ParticleSystem, exact_state, natural_frequency, with_tolerance};
use selvedge::solver::integrate::Integrator;

fn state_error((x, v): (f64, f64)) -> f64 {
    let (ex, ev) = exact_state(1.0);
    (x - ex).hypot((v - ev) / natural_frequency())
}

#[test]
fn rk45_meets_its_tolerance_with_fewer_steps_than_rk4() {
    let oscillator = ParticleSystem::oscillator();
    // Outer steps of 0.5 s: RK45 chooses its own steps inside them.
    let tolerance = 1e-4;
    let (state, report) = oscillator.oscillator_state(Integrator::Rk45, 0.5, 1.0, &with_tolerance(tolerance));
    let rk45_error = state_error(state);
    assert!(report.max_error_ratio <= 1.0, "accepted an error estimate above tolerance: {report:?}");
    // Local control at 1e-4 of the ~1 m state gives a global error of that order.
    assert!(rk45_error < 10.0 * f64::from(tolerance), "global error {rk45_error:e} at tolerance {tolerance:e}");

    // The fewest fixed RK4 steps that are as accurate.
    let rk4_steps = (1u32..=1000)
        .find(|&n| {
            state_error(oscillator.oscillator_state(Integrator::Rk4, 1.0 / f64::from(n), 1.0, &with_tolerance(0.0)).0)
                <= rk45_error
        })
        .expect("RK4 reaches the accuracy within 1000 steps");
    assert!(
        report.accepted + report.rejected < rk4_steps,
        "RK45 took {} steps ({} rejected) for error {rk45_error:e}; RK4 needs {rk4_steps}",
        report.accepted + report.rejected,
        report.rejected
    );
    eprintln!("RK45: {report:?}, error {rk45_error:e}; RK4 needs {rk4_steps} steps");
}

#[test]
fn a_tighter_tolerance_gives_a_smaller_error() {
    let oscillator = ParticleSystem::oscillator();
    let loose = state_error(oscillator.oscillator_state(Integrator::Rk45, 0.5, 1.0, &with_tolerance(1e-3)).0);
    let tight = state_error(oscillator.oscillator_state(Integrator::Rk45, 0.5, 1.0, &with_tolerance(1e-5)).0);
    eprintln!("tolerance 1e-3: {loose:e}, 1e-5: {tight:e}");
    assert!(tight < loose / 10.0, "tolerance 1e-3 gave {loose:e}, 1e-5 gave {tight:e}");
}
