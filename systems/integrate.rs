//! Advancing every cloth by one step with the scene's integrator.

use bevy_ecs::prelude::*;

use super::forces::{ForceElements, ForceEnvironment};
use crate::components::{Cloth, Particles, SolverWorkspace};
use crate::resources::{HealthProblem, HealthReport, IntegratorStats, SolverSettings, StepSettings};
use crate::schedule::{SimSchedules, SubstepSystems};
use crate::solver::forces::ClothDynamics;
use crate::solver::integrate::step;

/// Integrates each cloth from the forces of [`SubstepSystems::Forces`], re-evaluating the
/// force model at intermediate states for multi-stage methods. A step the integrator
/// cannot complete is reported to the [`HealthReport`]. Runs in [`SubstepSystems::Integrate`].
pub fn integrate_cloths(
    settings: Res<StepSettings>,
    solver: Res<SolverSettings>,
    environment: ForceEnvironment,
    mut stats: ResMut<IntegratorStats>,
    mut health: ResMut<HealthReport>,
    mut cloths: Query<(&Cloth, &mut Particles, ForceElements, &mut SolverWorkspace)>,
) {
    for (cloth, mut particles, elements, mut workspace) in &mut cloths {
        let SolverWorkspace { integrator, forces, .. } = &mut *workspace;
        integrator.resize(particles.len());
        for ((a, f), w) in integrator.start_acceleration.iter_mut().zip(&particles.force).zip(&elements.5.free_inv_mass)
        {
            *a = *f * *w;
        }
        let mut x = std::mem::take(&mut particles.position);
        let mut v = std::mem::take(&mut particles.velocity);
        let model = environment.model(&particles.inv_mass, elements);
        let mut dynamics = ClothDynamics { model, free_inv_mass: &elements.5.free_inv_mass, scratch: forces };
        let result = step(
            solver.integrator,
            &mut dynamics,
            &mut x,
            &mut v,
            environment.time(),
            settings.dt,
            &solver.method,
            integrator,
        );
        particles.position = x;
        particles.velocity = v;
        match result {
            Ok(report) => {
                stats.accepted += u64::from(report.accepted);
                stats.rejected += u64::from(report.rejected);
                stats.evaluations += 1 + u64::from(report.evaluations);
                stats.iterations += u64::from(report.iterations);
            }
            Err(error) => {
                health.problem.get_or_insert(HealthProblem { cloth: cloth.name.clone(), problem: error.to_string() });
            }
        }
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.substep.add_systems(integrate_cloths.in_set(SubstepSystems::Integrate));
}
