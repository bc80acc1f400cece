//! Small particle systems built from the engine's own elements, stepped by its
//! integrators without a world: a damped mass on a spring (with its closed-form motion)
//! and a lone particle in gravity.

use glam::Vec3;
use selvedge::components::{
    BendingHinges, ClothElements, ClothTopology, MembraneTriangles, SolverParts, SpringKind, Springs, Triangles,
};
use selvedge::solver::forces::{Air, ClothDynamics, ForceModel, ForceScratch};
use selvedge::solver::integrate::{Integrator, IntegratorWorkspace, MethodSettings, StepReport, step};

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
    let (m, k, c, x0) = (f64::from(MASS), f64::from(STIFFNESS), f64::from(DAMPING), f64::from(STRETCH));
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

/// Particles with springs, some of them pinned, in uniform gravity.
pub struct ParticleSystem {
    pub x: Vec<Vec3>,
    pub inv_mass: Vec<f32>,
    pub springs: Springs,
    pub gravity: Vec3,
    topology: ClothTopology,
    triangles: Triangles,
    hinges: BendingHinges,
    membranes: MembraneTriangles,
}

impl ParticleSystem {
    pub fn new(x: Vec<Vec3>, masses: &[f32], springs: Springs, pinned: &[u32], gravity: Vec3) -> Self {
        let inv_mass: Vec<f32> = masses.iter().map(|m| 1.0 / m).collect();
        let (triangles, hinges, membranes) =
            (Triangles::default(), BendingHinges::default(), MembraneTriangles::default());
        let elements =
            ClothElements { springs: &springs, triangles: &triangles.indices, hinges: &hinges, membranes: &membranes };
        let topology = ClothTopology::build(&inv_mass, elements, pinned, 1, SolverParts::default());
        Self { x, inv_mass, springs, gravity, topology, triangles, hinges, membranes }
    }

    /// The damped oscillator: particle 0 held at the origin, particle 1 on the spring along +X.
    pub fn oscillator() -> Self {
        let mut springs = Springs::default();
        springs.push([0, 1], REST, STIFFNESS, DAMPING, SpringKind::Structural);
        Self::new(vec![Vec3::ZERO, Vec3::new(REST + STRETCH, 0.0, 0.0)], &[MASS, MASS], springs, &[0], Vec3::ZERO)
    }

    /// Integrates from rest to `duration` [s] in steps of `h`; returns the final positions
    /// and velocities and the summed step reports.
    pub fn run(
        &self,
        method: Integrator,
        h: f64,
        duration: f64,
        settings: &MethodSettings,
    ) -> (Vec<Vec3>, Vec<Vec3>, StepReport) {
        let model = ForceModel {
            inv_mass: &self.inv_mass,
            density: 1.0,
            springs: &self.springs,
            triangles: &self.triangles.indices,
            hinges: &self.hinges,
            membranes: &self.membranes,
            topology: &self.topology,
            gravity: self.gravity,
            air: Air::default(),
            user_forces: &[],
        };
        let mut scratch = ForceScratch::default();
        let mut dynamics = ClothDynamics {
            model,
            free_inv_mass: &self.topology.free_inv_mass,
            scratch: &mut scratch,
            self_collision: None,
            others: None,
            contact_springs: &mut [],
            bodies: &[],
            start_force: None,
        };
        let mut x = self.x.clone();
        let mut v = vec![Vec3::ZERO; x.len()];
        let mut ws = IntegratorWorkspace::default();
        let mut total = StepReport::default();
        let steps = (duration / h).round() as u32;
        for n in 0..steps {
            let t = (f64::from(n) * h) as f32;
            ws.resize(x.len(), method);
            if !method.is_implicit() {
                selvedge::solver::integrate::Dynamics::acceleration(
                    &mut dynamics,
                    &x,
                    &v,
                    t,
                    &mut ws.start_acceleration,
                );
            }
            let report = step(method, &mut dynamics, &mut [], None, &mut x, &mut v, t, h as f32, settings, &mut ws)
                .expect("a smooth problem");
            total.accepted += report.accepted;
            total.rejected += report.rejected;
            total.evaluations += report.evaluations + 1;
            total.iterations += report.iterations;
            total.max_error_ratio = total.max_error_ratio.max(report.max_error_ratio);
        }
        (x, v, total)
    }

    /// The oscillator's displacement from rest [m] and velocity [m/s] after `run`.
    pub fn oscillator_state(
        &self,
        method: Integrator,
        h: f64,
        duration: f64,
        settings: &MethodSettings,
    ) -> ((f64, f64), StepReport) {
        let (x, v, report) = self.run(method, h, duration, settings);
        ((f64::from(x[1].x - REST), f64::from(v[1].x)), report)
    }
}

/// Settings with the given RK45 tolerance.
pub fn with_tolerance(tolerance: f32) -> MethodSettings {
    MethodSettings { tolerance, ..MethodSettings::default() }
}
