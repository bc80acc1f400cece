//! Advancing every cloth by one step with the scene's integrator.

use bevy_ecs::prelude::*;
use glam::Vec3;

use super::forces::{ForceElements, ForceEnvironment};
use crate::collision::body_contact::ContactBody;
use crate::collision::coupling::PropCoupling;
use crate::collision::motion_bounds::{ClothSurfaces, Surface};
use crate::components::{Cloth, Collider, Particles, Prop, SelfCollision, SelfTouching, SolverWorkspace, Touching};
use crate::resources::{ClothContacts, HealthProblem, HealthReport, IntegratorStats, SolverSettings, StepSettings};
use crate::schedule::{SimSchedules, SubstepSystems};
use crate::solver::cfl::cfl_step;
use crate::solver::contact_springs::ClothEnds;
use crate::solver::forces::ClothDynamics;
use crate::solver::implicit::ConstraintBodies;
use crate::solver::integrate::{Dynamics, StepReport, step};

/// Integrates each cloth from the forces of [`SubstepSystems::Forces`], re-evaluating the
/// force model at intermediate states for multi-stage methods, and splitting the step by
/// the CFL limit when the scene asks for Zheng's adaptive step. A step the integrator
/// cannot complete is reported to the [`HealthReport`]. Runs in [`SubstepSystems::Integrate`].
pub fn integrate_cloths(
    settings: Res<StepSettings>,
    solver: Res<SolverSettings>,
    environment: ForceEnvironment,
    mut stats: ResMut<IntegratorStats>,
    mut health: ResMut<HealthReport>,
    contacts: Res<ClothContacts>,
    mut cloths: Query<(
        Entity,
        &Cloth,
        &mut Particles,
        ForceElements,
        &Touching,
        &mut SolverWorkspace,
        Option<&SelfCollision>,
        Option<&mut SelfTouching>,
    )>,
    mut colliders: Query<(&Collider, Option<&mut Prop>)>,
    mut props: Local<PropCoupling>,
    mut bodies: Local<Vec<ContactBody>>,
    mut surfaces: Local<ClothSurfaces>,
    mut ends: Local<ClothEnds>,
) {
    // Springs with another cloth's held side hold the cloth against where that side will
    // be: on a cloth before this one where its step ended, else where its velocity takes it.
    let mesh_number = |entity: Entity| contacts.members.iter().position(|&(e, _)| e == entity);
    let across = cloths.iter().any(|(.., touching)| touching.is_some_and(|t| !t.across.is_empty()));
    if across {
        for (entity, _, particles, ..) in &cloths {
            if let Some(number) = mesh_number(entity) {
                ends.expect(number, &particles.position, &particles.velocity, settings.dt);
            }
        }
    }
    // Block descent bounds each cloth's sweeps by the other cloths it collides with too,
    // where they stand when its turn comes: those before it where their steps ended.
    let colliding = cloths.iter().filter(|(.., self_collision, _)| self_collision.is_some()).count();
    let bounded = solver.integrator.bounds_contact(&solver.method) && colliding > 1;
    if bounded {
        surfaces.clear();
        for (_, _, particles, (_, _, triangles, _, _, topology, _), .., self_collision, _) in &cloths {
            if let Some(s) = self_collision {
                let triangles = &triangles.indices;
                let surface = Surface { triangles, edges: topology.edges(triangles) };
                surfaces.add(surface, s.layers(), &particles.position, &particles.velocity);
            }
        }
    }
    let mut members = 0;
    for (index, (entity, cloth, mut particles, elements, touching, mut workspace, self_collision, self_touching)) in
        cloths.iter_mut().enumerate()
    {
        // The cloth's number among those bounded by one another: the query yields the
        // cloths in the same order both times.
        let member = (bounded && self_collision.is_some()).then(|| {
            members += 1;
            members - 1
        });
        let SolverWorkspace { integrator, forces, support, constraints, whole_start_force, .. } = &mut *workspace;
        // Particles the last step left on a body stay on it while the forces press them
        // into it (closing what gap the last step left), held fast where static friction
        // held them; those pulled away are let go. On a free prop they follow the prop,
        // whose velocity the step solves for too.
        props.begin(index, colliders.iter().map(|(_, prop)| prop.map(|p| p.coupling)), touching.0.len());
        constraints.clear();
        constraints.reserve(touching.0.len());
        constraints.extend(
            touching
                .0
                .iter()
                .filter(|t| particles.force[t.particle as usize].dot(t.normal) < 0.0)
                .map(|t| props.constrain(t, particles.position[t.particle as usize], settings.dt)),
        );
        let coupled = solver.integrator.is_implicit() && props.has_free_bodies();
        // Only an explicit method's buffers are sized: an implicit one's start
        // acceleration is empty, and this fills nothing.
        integrator.resize(particles.len(), solver.integrator);
        for ((a, f), w) in integrator.start_acceleration.iter_mut().zip(&particles.force).zip(&elements.5.free_inv_mass)
        {
            *a = *f * *w;
        }
        let mut x = std::mem::take(&mut particles.position);
        let mut v = std::mem::take(&mut particles.velocity);
        let (material, springs, _, _, membranes, topology, _) = elements;
        // Zheng's adaptive step: split the step into equal sub-steps no longer than the
        // CFL limit of the cloth as it is now.
        let splits = match (solver.method.cfl, solver.integrator.is_implicit()) {
            (Some(alpha), false) => cfl_step(alpha, &x, material.density, springs, membranes)
                .map_or(1, |limit| (settings.dt / limit).ceil().max(1.0) as u32),
            _ => 1,
        };
        let h = settings.dt / splits as f32;
        let model = environment.model(&particles.inv_mass, elements);
        // The bodies where the step ends, as the contact stage after it will meet them.
        let end = environment.step_end(settings.dt);
        bodies.clear();
        bodies.extend(colliders.iter().map(|(c, prop)| c.contact_body(end, cloth.thickness, prop.is_some())));
        let mut dynamics = ClothDynamics {
            model,
            free_inv_mass: &topology.free_inv_mass,
            scratch: forces,
            self_collision: self_collision.map(SelfCollision::layers),
            others: member.and_then(|m| surfaces.others(m)),
            contact_springs: self_touching.map_or(&mut [], |s| {
                let SelfTouching { springs, across } = s.into_inner();
                ends.place(across, springs);
                springs.as_mut_slice()
            }),
            bodies: &bodies,
            start_force: whole_start_force.then_some(&particles.force),
        };
        let mut result = Ok(StepReport::default());
        for split in 0..splits {
            let t = environment.time() + split as f32 * h;
            if split > 0 {
                dynamics.acceleration(&x, &v, t, &mut integrator.start_acceleration);
            }
            let bodies = coupled.then_some(&mut *props as &mut dyn ConstraintBodies);
            result = step(
                solver.integrator,
                &mut dynamics,
                constraints,
                bodies,
                &mut x,
                &mut v,
                t,
                h,
                &solver.method,
                integrator,
            )
            .map(|report| {
                let total = result.unwrap_or_default();
                let mut stages = total.stages;
                stages += report.stages;
                StepReport {
                    accepted: total.accepted + report.accepted,
                    rejected: total.rejected + report.rejected,
                    evaluations: total.evaluations + report.evaluations + u32::from(split > 0),
                    iterations: total.iterations + report.iterations,
                    max_error_ratio: total.max_error_ratio.max(report.max_error_ratio),
                    stages,
                }
            });
            if result.is_err() {
                break;
            }
        }
        particles.position = x;
        particles.velocity = v;
        if let Some(member) = member {
            surfaces.moved(member, &particles.position, &particles.velocity);
        }
        if let Some(number) = mesh_number(entity).filter(|_| across) {
            ends.ended(number, &particles.position, &particles.velocity);
        }
        // Only the contact with bodies reads the support: with no collider none is kept
        // (12 bytes a particle).
        support.clear();
        if !colliders.is_empty() {
            support.resize(particles.len(), Vec3::ZERO);
        }
        if solver.integrator.is_implicit() {
            for (c, impulse) in constraints.iter().zip(&integrator.implicit.constraint_impulses) {
                support[c.particle as usize] += *impulse;
            }
        }
        if coupled {
            // The props took the opposite of the support: the next cloth steps against them
            // as they are now.
            let impulses = &integrator.implicit.constraint_impulses;
            for (b, (_, prop)) in colliders.iter_mut().enumerate() {
                if let (Some(mut prop), Some(state)) = (prop, props.settled(b, impulses)) {
                    prop.coupling = state;
                }
            }
        }
        match result {
            Ok(report) => {
                stats.accepted += u64::from(report.accepted);
                stats.rejected += u64::from(report.rejected);
                stats.evaluations += 1 + u64::from(report.evaluations);
                stats.iterations += u64::from(report.iterations);
                stats.stages += report.stages;
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
