//! A damped mass on a spring, built from the engine's own force model, with its
//! closed-form motion: the reference problem for order and step-control tests.

use glam::Vec3;
use selvedge::components::{ClothTopology, Csr, SpringKind, Springs};
use selvedge::solver::forces::{Air, ClothDynamics, ForceModel, ForceScratch};
use selvedge::solver::integrate::{Integrator, IntegratorWorkspace, StepReport, step};

/// Mass [kg], stiffness [N/m], damping [N·s/m], rest length [m], initial stretch [m].
pub const MASS: f32 = 1.0;
pub const STIFFNESS: f32 = 40.0;
pub const DAMPING: f32 = 1.0;
pub const REST: f32 = 0.6;
pub const STRETCH: f32 = 0.5;

/// Displacement from rest [m] and velocity [m/s] at time `t` of the underdamped
/// oscillator released from `STRETCH` at rest:
/// `x = e^{−ζω t}(x0 cos ω_d t + (ζω x0 / ω_d) sin ω_d t)`.
pub fn exact_state(t: f64) -> (f64, f64) {
    let (m, k, c, x0) = (
        f64::from(MASS),
        f64::from(STIFFNESS),
        f64::from(DAMPING),
        f64::from(STRETCH),
    );
    let omega = (k / m).sqrt();
    let zeta = c / (2.0 * (k * m).sqrt());
    let omega_d = omega * (1.0 - zeta * zeta).sqrt();
    let (a, b) = (x0, zeta * omega * x0 / omega_d);
    let decay = (-zeta * omega * t).exp();
    let (sin, cos) = (omega_d * t).sin_cos();
    let x = decay * (a * cos + b * sin);
    let v = decay * (-zeta * omega * (a * cos + b * sin) + omega_d * (b * cos - a * sin));
    (x, v)
}

/// Natural frequency [rad/s], to weigh velocity errors against position errors.
pub fn natural_frequency() -> f64 {
    (f64::from(STIFFNESS) / f64::from(MASS)).sqrt()
}

/// The oscillator: particle 0 held at the origin, particle 1 on the spring along +X.
pub struct Oscillator {
    springs: Springs,
    topology: ClothTopology,
    inv_mass: Vec<f32>,
}

impl Oscillator {
    pub fn new() -> Self {
        let mut springs = Springs::default();
        springs.push([0, 1], REST, STIFFNESS, DAMPING, SpringKind::Structural);
        let topology = ClothTopology {
            particle_springs: Csr::from_items(2, &springs.pairs),
            particle_triangles: Csr::from_items::<3>(2, &[]),
            free_inv_mass: vec![0.0, 1.0 / MASS],
            builds: 1,
        };
        Self {
            springs,
            topology,
            inv_mass: vec![1.0 / MASS; 2],
        }
    }

    /// Integrates to `duration` [s] in steps of `h`; returns the final displacement [m] and
    /// velocity [m/s], and the summed step reports.
    pub fn run(
        &self,
        method: Integrator,
        h: f64,
        duration: f64,
        tolerance: f32,
    ) -> ((f64, f64), StepReport) {
        let model = ForceModel {
            inv_mass: &self.inv_mass,
            springs: &self.springs,
            triangles: &[],
            topology: &self.topology,
            gravity: Vec3::ZERO,
            air: Air::default(),
            user_forces: &[],
        };
        let mut scratch = ForceScratch::default();
        let mut dynamics = ClothDynamics {
            model,
            free_inv_mass: &self.topology.free_inv_mass,
            scratch: &mut scratch,
        };
        let mut x = vec![Vec3::ZERO, Vec3::new(REST + STRETCH, 0.0, 0.0)];
        let mut v = vec![Vec3::ZERO; 2];
        let mut ws = IntegratorWorkspace::default();
        let mut total = StepReport::default();
        let steps = (duration / h).round() as u32;
        for n in 0..steps {
            ws.resize(2);
            let mut a = [Vec3::ZERO; 2];
            selvedge::solver::integrate::Dynamics::acceleration(
                &mut dynamics,
                &x,
                &v,
                (f64::from(n) * h) as f32,
                &mut a,
            );
            ws.start_acceleration.copy_from_slice(&a);
            let report = step(
                method,
                &mut dynamics,
                &mut x,
                &mut v,
                (f64::from(n) * h) as f32,
                h as f32,
                tolerance,
                &mut ws,
            )
            .expect("the oscillator is smooth");
            total.accepted += report.accepted;
            total.rejected += report.rejected;
            total.evaluations += report.evaluations + 1;
            total.max_error_ratio = total.max_error_ratio.max(report.max_error_ratio);
        }
        ((f64::from(x[1].x - REST), f64::from(v[1].x)), total)
    }
}
