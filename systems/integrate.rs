//! Advancing every cloth by one step with the scene's integrator.

use bevy_ecs::prelude::*;

use super::forces::cloth_force_model;
use crate::components::{
    Cloth, ClothTopology, Particles, SolverWorkspace, Springs, Triangles, UserForces,
};
use crate::resources::{
    AirSettings, Gravity, HealthProblem, HealthReport, IntegratorStats, SimClock, SolverSettings,
    StepSettings,
};
use crate::schedule::{SimSchedules, SubstepSystems};
use crate::solver::forces::ClothDynamics;
use crate::solver::integrate::step;

/// Integrates each cloth from the forces of [`SubstepSystems::Forces`], re-evaluating the
/// force model at intermediate states for multi-stage methods. A step the integrator
/// cannot complete is reported to the [`HealthReport`]. Runs in [`SubstepSystems::Integrate`].
pub fn integrate_cloths(
    settings: Res<StepSettings>,
    solver: Res<SolverSettings>,
    gravity: Res<Gravity>,
    air: Res<AirSettings>,
    clock: Res<SimClock>,
    mut stats: ResMut<IntegratorStats>,
    mut health: ResMut<HealthReport>,
    mut cloths: Query<(
        &Cloth,
        &mut Particles,
        &Springs,
        &Triangles,
        &ClothTopology,
        &UserForces,
        &mut SolverWorkspace,
    )>,
) {
    for (cloth, mut particles, springs, triangles, topology, user_forces, mut workspace) in
        &mut cloths
    {
        let SolverWorkspace {
            integrator, forces, ..
        } = &mut *workspace;
        integrator.resize(particles.len());
        for ((a, f), w) in integrator
            .start_acceleration
            .iter_mut()
            .zip(&particles.force)
            .zip(&topology.free_inv_mass)
        {
            *a = *f * *w;
        }
        let mut x = std::mem::take(&mut particles.position);
        let mut v = std::mem::take(&mut particles.velocity);
        let model = cloth_force_model(
            &particles,
            springs,
            triangles,
            topology,
            user_forces,
            &gravity,
            &air,
        );
        let mut dynamics = ClothDynamics {
            model,
            free_inv_mass: &topology.free_inv_mass,
            scratch: forces,
        };
        let result = step(
            solver.integrator,
            &mut dynamics,
            &mut x,
            &mut v,
            clock.time_s as f32,
            settings.dt,
            solver.tolerance,
            integrator,
        );
        particles.position = x;
        particles.velocity = v;
        match result {
            Ok(report) => {
                stats.accepted += u64::from(report.accepted);
                stats.rejected += u64::from(report.rejected);
                stats.evaluations += 1 + u64::from(report.evaluations);
            }
            Err(error) => {
                health.problem.get_or_insert(HealthProblem {
                    cloth: cloth.name.clone(),
                    problem: error.to_string(),
                });
            }
        }
    }
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules
        .substep
        .add_systems(integrate_cloths.in_set(SubstepSystems::Integrate));
}
