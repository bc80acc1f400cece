//! Time integrators over the particle state `(x, v)`.
//!
//! Every explicit integrator advances one step of length `h` given the acceleration at the
//! start of the step (computed in the forces stage) and a [`Dynamics`] it may evaluate
//! again at intermediate states. The explicit Runge–Kutta family (explicit Euler, midpoint,
//! RK4, RK5 and adaptive RK45) shares one tableau-driven kernel; symplectic Euler and
//! velocity Verlet are written out. The implicit methods ([`super::implicit`]) take the same
//! system and linearise it.

use std::ops::AddAssign;
use std::time::Duration;

use glam::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::PARALLEL_MIN_LEN;
use super::descent::DescentSettings;
use super::implicit::{
    ConstraintBodies, ImplicitSettings, ImplicitWorkspace, LinearDynamics, LinearSolver, Rayleigh, VelocityConstraint,
    implicit_step,
};

/// The integration method of a scene (Durupınar D10, Zheng Z4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Integrator {
    /// `x += h v; v += h a`: first order, unstable without damping; for comparison.
    ExplicitEuler,
    /// `v += h a; x += h v`: first order, symplectic, the cheapest stable choice.
    SymplecticEuler,
    /// Explicit midpoint: second order.
    Midpoint,
    /// Classic fourth-order Runge–Kutta.
    Rk4,
    /// Fifth-order Runge–Kutta (the Cash–Karp fifth-order solution) at a fixed step.
    Rk5,
    /// Cash–Karp embedded RK4(5) with error control and step rejection inside each step.
    Rk45,
    /// Velocity Verlet: second order, symplectic, exact for constant acceleration.
    VelocityVerlet,
    /// Implicit Euler in Baraff & Witkin's form, solved by conjugate gradients: stable at
    /// frame-sized steps, with numerical damping.
    ImplicitEuler,
    /// Bricis's Newmark θ-method (θ = ½ by default) with Rayleigh damping: stable at large
    /// steps without numerical damping of its own.
    Newmark,
    /// Implicit Euler solved by block descent ([`super::descent`]): a fixed number of
    /// coloured, parallel per-particle Newton sweeps per step, so a step costs the same
    /// whatever the stiffness; stable at frame-sized steps.
    BlockDescent,
}

impl Integrator {
    /// Whether the method solves a linear system each step.
    pub fn is_implicit(self) -> bool {
        matches!(self, Integrator::ImplicitEuler | Integrator::Newmark | Integrator::BlockDescent)
    }

    /// Whether its step, with `settings`, holds a self-colliding cloth's close pairs apart
    /// with springs in the solve ([`super::contact_springs`]): the implicit methods solved
    /// by conjugate gradients, not block descent, which bounds each vertex's motion instead.
    pub fn solves_contact_springs(self, settings: &MethodSettings) -> bool {
        matches!(self, Integrator::ImplicitEuler | Integrator::Newmark)
            && !matches!(self.linear_solver(settings), LinearSolver::BlockDescent(_))
    }

    /// Whether its step, with `settings`, is solved by block descent with its sweeps
    /// bounded by contact ([`super::descent`]).
    pub fn bounds_contact(self, settings: &MethodSettings) -> bool {
        self.is_implicit() && matches!(self.linear_solver(settings), LinearSolver::BlockDescent(d) if d.contact_bounds)
    }

    /// The linear solver of its step with `settings`, if it is implicit: block descent's
    /// own, else the settings'.
    fn linear_solver(self, settings: &MethodSettings) -> LinearSolver {
        match self {
            Integrator::BlockDescent => LinearSolver::BlockDescent(settings.descent),
            _ => settings.implicit.linear_solver,
        }
    }

    /// Every integrator, for listings and tests.
    pub const ALL: [Integrator; 10] = [
        Integrator::ExplicitEuler,
        Integrator::SymplecticEuler,
        Integrator::Midpoint,
        Integrator::Rk4,
        Integrator::Rk5,
        Integrator::Rk45,
        Integrator::VelocityVerlet,
        Integrator::ImplicitEuler,
        Integrator::Newmark,
        Integrator::BlockDescent,
    ];

    /// The name used in scene files and reports.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::ExplicitEuler => "ExplicitEuler",
            Integrator::SymplecticEuler => "SymplecticEuler",
            Integrator::Midpoint => "Midpoint",
            Integrator::Rk4 => "Rk4",
            Integrator::Rk5 => "Rk5",
            Integrator::Rk45 => "Rk45",
            Integrator::VelocityVerlet => "VelocityVerlet",
            Integrator::ImplicitEuler => "ImplicitEuler",
            Integrator::Newmark => "Newmark",
            Integrator::BlockDescent => "BlockDescent",
        }
    }
}

/// The accelerations of a system as a pure function of its state.
pub trait Dynamics {
    /// Writes the acceleration of every particle at `(x, v, t)` [m/s²] to `out`.
    fn acceleration(&mut self, x: &[Vec3], v: &[Vec3], t: f32, out: &mut [Vec3]);
}

/// What one call of [`step`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepReport {
    /// Accepted internal steps (1 except for [`Integrator::Rk45`]).
    pub accepted: u32,
    /// Rejected internal steps ([`Integrator::Rk45`] only).
    pub rejected: u32,
    /// Evaluations of the dynamics beyond the start-of-step acceleration.
    pub evaluations: u32,
    /// Largest accepted error estimate relative to the tolerance (≤ 1; RK45 only).
    pub max_error_ratio: f32,
    /// Conjugate-gradient iterations (implicit methods only).
    pub iterations: u32,
    /// Where an implicit step's time went.
    pub stages: StageTimes,
}

/// Wall-clock time the implicit methods spent in the stages of their steps, for
/// `selvedge bench`'s account of where a frame's time goes. Nothing the steps compute
/// depends on it.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageTimes {
    /// Forces and their derivatives at the linearisation point, and the system built from
    /// them.
    pub assembly: Duration,
    /// The linear solver's preconditioner made ready for each system: the multigrid's
    /// levels, or block Jacobi's inverse diagonal.
    pub preconditioner: Duration,
    /// The linear solves' iterations (conjugate gradients or block descent's sweeps).
    pub solve: Duration,
}

impl StageTimes {
    /// The three stages together.
    pub fn total(&self) -> Duration {
        self.assembly + self.preconditioner + self.solve
    }
}

impl AddAssign for StageTimes {
    fn add_assign(&mut self, other: Self) {
        self.assembly += other.assembly;
        self.preconditioner += other.preconditioner;
        self.solve += other.solve;
    }
}

/// Why a step could not be completed.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum StepError {
    /// RK45 shrank its step below a millionth of the requested one without meeting the
    /// tolerance: the motion is too fast for the scene's step or the state blew up.
    #[error("adaptive step fell to {h:e} s at t = {t} s without meeting the tolerance")]
    StepSizeUnderflow {
        /// The step size reached [s].
        h: f32,
        /// The time it was reached at [s].
        t: f32,
    },
}

/// The settings every method may need.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MethodSettings {
    /// Relative error tolerance of [`Integrator::Rk45`] [-].
    pub tolerance: f32,
    /// θ, Rayleigh damping and solver settings of the implicit methods. For
    /// [`Integrator::ImplicitEuler`] θ is 1 whatever is given here.
    pub implicit: ImplicitSettings,
    /// Sweeps and acceleration of [`Integrator::BlockDescent`].
    pub descent: DescentSettings,
    /// Courant number α of Zheng's adaptive step for the explicit methods: each step is
    /// split into sub-steps of at most `α Δx √(ρ/E)` ([`super::cfl`]). `None`: no split.
    pub cfl: Option<f32>,
}

impl Default for MethodSettings {
    fn default() -> Self {
        Self {
            cfl: None,
            tolerance: 1e-4,
            implicit: ImplicitSettings {
                theta: 0.5,
                rayleigh: Rayleigh::default(),
                cg_tolerance: 1e-4,
                cg_max_iterations: 500,
                newton_iterations: 1,
                linear_solver: LinearSolver::ConjugateGradient,
            },
            descent: DescentSettings::default(),
        }
    }
}

/// Buffers for the stages, sized once per cloth and reused every step.
#[derive(Debug, Clone, Default)]
pub struct IntegratorWorkspace {
    /// Buffers of the implicit methods.
    pub implicit: ImplicitWorkspace,
    /// Acceleration at the start of the step [m/s²]; the caller fills it before an
    /// explicit method's [`step`]. Empty for the implicit methods, which evaluate their
    /// own, as are the explicit methods' other buffers: 36 bytes a particle they never
    /// read.
    pub start_acceleration: Vec<Vec3>,
    stage_velocity: Vec<Vec<Vec3>>,
    stage_acceleration: Vec<Vec<Vec3>>,
    x: Vec<Vec3>,
    v: Vec<Vec3>,
    /// The step RK45 proposes for its next internal step [s], kept across steps.
    next_adaptive_step: Option<f32>,
}

impl IntegratorWorkspace {
    /// Sizes the buffers of `method` for `count` particles.
    pub fn resize(&mut self, count: usize, method: Integrator) {
        if method.is_implicit() {
            return;
        }
        self.start_acceleration.resize(count, Vec3::ZERO);
        self.x.resize(count, Vec3::ZERO);
        self.v.resize(count, Vec3::ZERO);
        for stage in self.stage_velocity.iter_mut().chain(&mut self.stage_acceleration) {
            stage.resize(count, Vec3::ZERO);
        }
    }

    fn ensure_stages(&mut self, stages: usize) {
        let count = self.x.len();
        while self.stage_velocity.len() < stages {
            self.stage_velocity.push(vec![Vec3::ZERO; count]);
            self.stage_acceleration.push(vec![Vec3::ZERO; count]);
        }
    }
}

/// A Butcher tableau of an explicit Runge–Kutta method, with an optional embedded
/// lower-order solution for error control.
struct Tableau {
    c: &'static [f32],
    a: &'static [&'static [f32]],
    b: &'static [f32],
    /// `b − b̂`: weights of the error estimate (higher minus lower order).
    error: Option<&'static [f32]>,
    /// Order of the lower solution, which sets how the step adapts.
    order: u32,
}

const EULER: Tableau = Tableau { c: &[0.0], a: &[&[]], b: &[1.0], error: None, order: 1 };

const MIDPOINT: Tableau = Tableau { c: &[0.0, 0.5], a: &[&[], &[0.5]], b: &[0.0, 1.0], error: None, order: 2 };

const RK4: Tableau = Tableau {
    c: &[0.0, 0.5, 0.5, 1.0],
    a: &[&[], &[0.5], &[0.0, 0.5], &[0.0, 0.0, 1.0]],
    b: &[1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0],
    error: None,
    order: 4,
};

/// Cash & Karp (1990), as in Numerical Recipes' `rkck`.
const CASH_KARP_A: &[&[f32]] = &[
    &[],
    &[1.0 / 5.0],
    &[3.0 / 40.0, 9.0 / 40.0],
    &[3.0 / 10.0, -9.0 / 10.0, 6.0 / 5.0],
    &[-11.0 / 54.0, 5.0 / 2.0, -70.0 / 27.0, 35.0 / 27.0],
    &[1631.0 / 55296.0, 175.0 / 512.0, 575.0 / 13824.0, 44275.0 / 110592.0, 253.0 / 4096.0],
];
const CASH_KARP_C: &[f32] = &[0.0, 1.0 / 5.0, 3.0 / 10.0, 3.0 / 5.0, 1.0, 7.0 / 8.0];
const CASH_KARP_B5: &[f32] = &[37.0 / 378.0, 0.0, 250.0 / 621.0, 125.0 / 594.0, 0.0, 512.0 / 1771.0];
const CASH_KARP_ERROR: &[f32] = &[
    37.0 / 378.0 - 2825.0 / 27648.0,
    0.0,
    250.0 / 621.0 - 18575.0 / 48384.0,
    125.0 / 594.0 - 13525.0 / 55296.0,
    -277.0 / 14336.0,
    512.0 / 1771.0 - 0.25,
];

const RK5: Tableau = Tableau { c: CASH_KARP_C, a: CASH_KARP_A, b: CASH_KARP_B5, error: None, order: 5 };

const RK45: Tableau =
    Tableau { c: CASH_KARP_C, a: CASH_KARP_A, b: CASH_KARP_B5, error: Some(CASH_KARP_ERROR), order: 4 };

/// Errors below this [m, m/s] are rounding, not truncation: the floor of RK45's error scale.
const ERROR_FLOOR: f32 = 1e-6;

/// Advances `(x, v)` from time `t` by `h` [s] with `method`. For an explicit method the
/// caller has filled `ws.start_acceleration` with the acceleration at `(x, v, t)` (the
/// implicit methods evaluate their own, and honour the contact `constraints`, solving
/// with the `bodies` whose velocities the constraints follow; explicit methods leave
/// contacts to the contact stage).
pub fn step(
    method: Integrator,
    dynamics: &mut impl LinearDynamics,
    constraints: &mut [VelocityConstraint],
    bodies: Option<&mut dyn ConstraintBodies>,
    x: &mut [Vec3],
    v: &mut [Vec3],
    t: f32,
    h: f32,
    settings: &MethodSettings,
    ws: &mut IntegratorWorkspace,
) -> Result<StepReport, StepError> {
    ws.resize(x.len(), method);
    let tolerance = settings.tolerance;
    match method {
        Integrator::ImplicitEuler => {
            let euler = ImplicitSettings { theta: 1.0, ..settings.implicit };
            Ok(implicit_step(&euler, dynamics, constraints, bodies, x, v, t, h, &mut ws.implicit))
        }
        Integrator::BlockDescent => {
            let descent =
                ImplicitSettings { theta: 1.0, linear_solver: method.linear_solver(settings), ..settings.implicit };
            Ok(implicit_step(&descent, dynamics, constraints, bodies, x, v, t, h, &mut ws.implicit))
        }
        Integrator::Newmark => {
            Ok(implicit_step(&settings.implicit, dynamics, constraints, bodies, x, v, t, h, &mut ws.implicit))
        }
        Integrator::ExplicitEuler => Ok(runge_kutta(&EULER, dynamics, x, v, t, h, ws)),
        Integrator::Midpoint => Ok(runge_kutta(&MIDPOINT, dynamics, x, v, t, h, ws)),
        Integrator::Rk4 => Ok(runge_kutta(&RK4, dynamics, x, v, t, h, ws)),
        Integrator::Rk5 => Ok(runge_kutta(&RK5, dynamics, x, v, t, h, ws)),
        Integrator::Rk45 => adaptive_runge_kutta(&RK45, dynamics, x, v, t, h, tolerance, ws),
        Integrator::SymplecticEuler => {
            let a = &ws.start_acceleration;
            x.par_iter_mut().zip(v.par_iter_mut()).zip(a.par_iter()).with_min_len(PARALLEL_MIN_LEN).for_each(
                |((x, v), a)| {
                    *v += h * *a;
                    *x += h * *v;
                },
            );
            Ok(StepReport { accepted: 1, ..StepReport::default() })
        }
        Integrator::VelocityVerlet => {
            // Drift with the start acceleration, evaluate at the new positions, then kick
            // with the mean of both accelerations. Velocity-dependent forces see the
            // Euler-predicted end velocity, which keeps them second order too.
            let a0 = &ws.start_acceleration;
            let predicted = &mut ws.v;
            x.par_iter_mut()
                .zip(v.par_iter())
                .zip(predicted.par_iter_mut())
                .zip(a0.par_iter())
                .with_min_len(PARALLEL_MIN_LEN)
                .for_each(|(((x, v), predicted), a)| {
                    *x += h * *v + 0.5 * h * h * *a;
                    *predicted = *v + h * *a;
                });
            let a1 = &mut ws.x;
            dynamics.acceleration(x, predicted, t + h, a1);
            v.par_iter_mut()
                .zip(a0.par_iter().zip(a1.par_iter()))
                .with_min_len(PARALLEL_MIN_LEN)
                .for_each(|(v, (a0, a1))| *v += 0.5 * h * (*a0 + *a1));
            Ok(StepReport { accepted: 1, evaluations: 1, ..StepReport::default() })
        }
    }
}

/// Computes the stages of `tableau` from `(x, v)`; stage 0 is the start acceleration.
/// Leaves the stage velocities and accelerations in `ws`.
fn compute_stages(
    tableau: &Tableau,
    dynamics: &mut impl Dynamics,
    x: &[Vec3],
    v: &[Vec3],
    t: f32,
    h: f32,
    ws: &mut IntegratorWorkspace,
) {
    let stages = tableau.b.len();
    ws.ensure_stages(stages);
    ws.stage_velocity[0].copy_from_slice(v);
    ws.stage_acceleration[0].copy_from_slice(&ws.start_acceleration);
    for s in 1..stages {
        let weights = tableau.a[s];
        combine(x, &ws.stage_velocity[..s], weights, h, &mut ws.x);
        combine(v, &ws.stage_acceleration[..s], weights, h, &mut ws.v);
        dynamics.acceleration(&ws.x, &ws.v, t + tableau.c[s] * h, &mut ws.stage_acceleration[s]);
        ws.stage_velocity[s].copy_from_slice(&ws.v);
    }
}

/// `out = base + h Σ_j weights[j] · stages[j]`, particle by particle.
fn combine(base: &[Vec3], stages: &[Vec<Vec3>], weights: &[f32], h: f32, out: &mut [Vec3]) {
    out.par_iter_mut().with_min_len(PARALLEL_MIN_LEN).enumerate().for_each(|(i, out)| {
        let mut sum = Vec3::ZERO;
        for (stage, &w) in stages.iter().zip(weights) {
            if w != 0.0 {
                sum += w * stage[i];
            }
        }
        *out = base[i] + h * sum;
    });
}

fn runge_kutta(
    tableau: &Tableau,
    dynamics: &mut impl Dynamics,
    x: &mut [Vec3],
    v: &mut [Vec3],
    t: f32,
    h: f32,
    ws: &mut IntegratorWorkspace,
) -> StepReport {
    compute_stages(tableau, dynamics, x, v, t, h, ws);
    combine(x, &ws.stage_velocity, tableau.b, h, &mut ws.x);
    combine(v, &ws.stage_acceleration, tableau.b, h, &mut ws.v);
    x.copy_from_slice(&ws.x);
    v.copy_from_slice(&ws.v);
    StepReport { accepted: 1, evaluations: tableau.b.len() as u32 - 1, ..StepReport::default() }
}

/// Internal steps of `tableau` with error control until `h` is covered. The proposed step
/// carries over between calls, so a smooth motion settles at few internal steps.
fn adaptive_runge_kutta(
    tableau: &Tableau,
    dynamics: &mut impl Dynamics,
    x: &mut [Vec3],
    v: &mut [Vec3],
    t: f32,
    h: f32,
    tolerance: f32,
    ws: &mut IntegratorWorkspace,
) -> Result<StepReport, StepError> {
    let error_weights = tableau.error.expect("an adaptive tableau has error weights");
    let order = tableau.order as f32;
    let mut report = StepReport::default();
    let mut done = 0.0f32;
    let mut trial = ws.next_adaptive_step.unwrap_or(h).min(h);
    let mut have_start = true;
    while done < h {
        let remaining = h - done;
        // Take the rest in one go when it is close, rather than leave a sliver.
        let sub = if trial >= remaining * 0.999 { remaining } else { trial };
        if !have_start {
            dynamics.acceleration(x, v, t + done, &mut ws.start_acceleration);
            report.evaluations += 1;
        }
        compute_stages(tableau, dynamics, x, v, t + done, sub, ws);
        report.evaluations += tableau.b.len() as u32 - 1;
        let ratio = error_ratio(error_weights, x, v, sub, tolerance, ws);
        if ratio <= 1.0 {
            combine(x, &ws.stage_velocity, tableau.b, sub, &mut ws.x);
            combine(v, &ws.stage_acceleration, tableau.b, sub, &mut ws.v);
            x.copy_from_slice(&ws.x);
            v.copy_from_slice(&ws.v);
            done = if sub == remaining { h } else { done + sub };
            have_start = false;
            report.accepted += 1;
            report.max_error_ratio = report.max_error_ratio.max(ratio);
            let grow = if ratio > 0.0 { 0.9 * ratio.powf(-1.0 / (order + 1.0)) } else { 5.0 };
            trial = sub * grow.clamp(1.0, 5.0);
        } else {
            report.rejected += 1;
            have_start = true;
            trial = sub * (0.9 * ratio.powf(-1.0 / order)).max(0.1);
            if trial < h * 1e-6 || !trial.is_finite() {
                return Err(StepError::StepSizeUnderflow { h: trial, t: t + done });
            }
        }
    }
    ws.next_adaptive_step = Some(trial);
    Ok(report)
}

/// Largest embedded error of the stages in `ws`, relative to `tolerance` times each
/// component's scale (`|y| + |h y'|`, as in Numerical Recipes, plus a rounding floor).
fn error_ratio(weights: &[f32], x: &[Vec3], v: &[Vec3], h: f32, tolerance: f32, ws: &IntegratorWorkspace) -> f32 {
    let stages = (&ws.stage_velocity, &ws.stage_acceleration);
    (0..x.len())
        .into_par_iter()
        .with_min_len(PARALLEL_MIN_LEN)
        .map(|i| {
            let mut ex = Vec3::ZERO;
            let mut ev = Vec3::ZERO;
            for (s, &w) in weights.iter().enumerate() {
                ex += w * stages.0[s][i];
                ev += w * stages.1[s][i];
            }
            let scale_x = tolerance * (x[i].length() + h * stages.0[0][i].length()) + ERROR_FLOOR;
            let scale_v = tolerance * (v[i].length() + h * stages.1[0][i].length()) + ERROR_FLOOR;
            let ratio = (h * ex.length() / scale_x).max(h * ev.length() / scale_v);
            // A non-finite state must be rejected, and `f32::max` would drop a NaN.
            if ratio.is_finite() { ratio } else { f32::INFINITY }
        })
        .reduce(|| 0.0, f32::max)
}
