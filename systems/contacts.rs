//! Contact of cloth with solid bodies and with cloth.

use bevy_ecs::prelude::*;
use glam::Vec3;

use crate::collision::body_contact::{BodyContactOutput, BodyLoad, ContactBody, resolve_body_contacts};
use crate::collision::collider::{ColliderMotion, ColliderState};
use crate::collision::features::{ClothSurface, FeatureScratch};
use crate::collision::self_contact::{ContactMesh, SelfContactReport, SelfContactSolver};
use crate::components::{
    Cloth, ClothMaterial, ClothTopology, Collider, ContactStats, Particles, Prop, SelfCollision, SelfTouching,
    SolverWorkspace, Touching, Triangles,
};
use crate::resources::{ClothContacts, PropWorld, SimClock, SolverSettings, StepSettings};
use crate::schedule::{FrameSystems, SimSchedules, SubstepSystems};
use crate::solver::contact_springs::{Across, ContactSpring, Stencil};
use crate::solver::gather::reserve_floored;

/// Resolves every cloth's contacts with every collider at the end of the step (the
/// colliders where they are then), and adds what they did to the cloth's
/// [`ContactStats`]. The props among the colliders first take the velocity the cloth's
/// implicit steps settled on ([`crate::collision::coupling`]), and then the opposite of
/// the impulses the contacts gave the cloth, at the points where they gave them. Runs in
/// [`SubstepSystems::BodyContacts`].
pub fn collide_with_bodies(
    clock: Res<SimClock>,
    settings: Res<StepSettings>,
    mut colliders: Query<(&mut Collider, Option<&mut Prop>)>,
    mut rigid: Option<ResMut<PropWorld>>,
    mut cloths: Query<(
        &Cloth,
        &ClothMaterial,
        &mut Particles,
        &Triangles,
        &ClothTopology,
        &SolverWorkspace,
        &mut ContactStats,
        &mut Touching,
    )>,
    mut buffers: Local<BodyBuffers>,
) {
    if colliders.is_empty() {
        return;
    }
    if let Some(rigid) = &mut rigid {
        for (mut collider, prop) in &mut colliders {
            if let Some(prop) = prop {
                let body = &mut rigid.0.bodies[prop.body];
                prop.coupling.settle(body, settings.dt);
                collider.motion = ColliderMotion::Driven(ColliderState::of_body(body));
            }
        }
    }
    let t = clock.step_end(settings.dt);
    let BodyBuffers { bodies, output, total, scratch } = &mut *buffers;
    total.clear();
    total.resize(colliders.iter().len(), BodyLoad::default());
    for (cloth, material, mut particles, triangles, topology, workspace, mut stats, mut touching) in &mut cloths {
        bodies.clear();
        bodies.extend(colliders.iter().map(|(c, prop)| c.contact_body(t, cloth.thickness, prop.is_some())));
        let Particles { position, velocity, inv_mass, .. } = &mut *particles;
        let density = material.density;
        let area = |i: usize| 1.0 / (inv_mass[i] * density);
        let totals = resolve_body_contacts(
            bodies,
            inv_mass,
            &topology.free_inv_mass,
            area,
            settings.dt,
            &workspace.step_start,
            &workspace.support,
            position,
            velocity,
            &mut touching.0,
            output,
        );
        stats.0.add(&totals);
        for (sum, load) in total.iter_mut().zip(output.loads.iter()) {
            sum.add(load);
        }
        // Formed only for a collider with features: the edges are found at the first ask.
        let surface = || ClothSurface {
            edges: topology.edges(&triangles.indices),
            triangles: &triangles.indices,
            free_inv_mass: &topology.free_inv_mass,
            start: &workspace.step_start,
        };
        for (((collider, _), body), sum) in colliders.iter().zip(bodies.iter()).zip(total.iter_mut()) {
            let Some(features) = &collider.features else {
                continue;
            };
            let (pushes, load) =
                features.resolve(&body.state, body.thickness, settings.dt, surface(), position, velocity, scratch);
            stats.0.add(&pushes);
            sum.add(&load);
        }
    }
    let Some(mut rigid) = rigid else {
        return;
    };
    for ((_, prop), load) in colliders.iter_mut().zip(total.iter()) {
        let Some(prop) = prop else {
            continue;
        };
        let body = &mut rigid.0.bodies[prop.body];
        let (dv, dw) = prop.coupling.velocity_change(-load.impulse, -load.moment_about(body.center_of_mass()));
        if dv != Vec3::ZERO || dw != Vec3::ZERO {
            let (linear, angular) = (body.linvel() + dv, body.angvel() + dw);
            body.set_linvel(linear, true);
            body.set_angvel(angular, true);
        }
    }
}

/// What [`collide_with_bodies`] keeps from step to step so that it does not allocate.
#[derive(Default)]
pub struct BodyBuffers {
    /// The colliders as the contact kernel sees them.
    bodies: Vec<ContactBody>,
    /// One cloth's contact results.
    output: BodyContactOutput,
    /// Every cloth's push on each body.
    total: Vec<BodyLoad>,
    /// Buffers of the sharp features' contacts.
    scratch: FeatureScratch,
}

/// Resolves cloth–cloth contact of every self-colliding cloth, all together as one mesh
/// so that layers meet one another: the step from where it started to where the
/// integrator, the constraints and the bodies put it is made free of crossings. Runs in
/// [`SubstepSystems::SelfContacts`].
pub fn collide_cloths(
    settings: Res<StepSettings>,
    solver_settings: Res<SolverSettings>,
    mut contacts: ResMut<ClothContacts>,
    mut cloths: Query<(
        Entity,
        &mut Particles,
        &Triangles,
        &ClothTopology,
        &SolverWorkspace,
        &Touching,
        &SelfCollision,
        &mut SelfTouching,
    )>,
) {
    let contacts = &mut *contacts;
    let members = || cloths.iter().map(|(entity, _, _, topology, ..)| (entity, topology.builds));
    if cloths.is_empty() {
        return;
    }
    if !members().eq(contacts.members.iter().copied()) {
        let mut mesh = ContactMesh::default();
        for (_, particles, triangles, topology, _, _, collision, _) in &cloths {
            let offset = mesh.half_gap.len() as u32;
            mesh.triangles.extend(triangles.indices.iter().map(|t| t.map(|k| k + offset)));
            // Each cloth's edges are sorted and numbered above the last cloth's, so the
            // whole list is sorted too.
            mesh.edges.extend(topology.edges(&triangles.indices).iter().map(|e| e.map(|k| k + offset)));
            mesh.half_gap.extend(std::iter::repeat_n(0.5 * collision.separation, particles.len()));
            mesh.friction.extend(std::iter::repeat_n(collision.friction, particles.len()));
            mesh.layer.extend(std::iter::repeat_n(collision.layer, particles.len()));
            mesh.first.push(offset);
        }
        mesh.first.push(mesh.half_gap.len() as u32);
        contacts.mesh = mesh;
        // A new mesh may start tangled: the solver starts over, looking for crossings.
        contacts.solver = SelfContactSolver::default();
        contacts.members = members().collect();
    }
    let ClothContacts { mesh, solver, start, end, velocity, frame, springs, .. } = contacts;
    mesh.springs = solver_settings.integrator.solves_contact_springs(&solver_settings.method);
    start.clear();
    end.clear();
    velocity.clear();
    mesh.inv_mass.clear();
    mesh.impulse_inv_mass.clear();
    for (_, particles, _, topology, workspace, touching, ..) in &cloths {
        // Particles resting on a body are infinitely heavy to impulses: cloth falling on
        // them must not push them into the body.
        let offset = mesh.inv_mass.len();
        mesh.inv_mass.extend_from_slice(&topology.free_inv_mass);
        mesh.impulse_inv_mass.extend_from_slice(&topology.free_inv_mass);
        for touch in &touching.0 {
            mesh.impulse_inv_mass[offset + touch.particle as usize] = 0.0;
        }
        start.extend_from_slice(&workspace.step_start);
        end.extend_from_slice(&particles.position);
        velocity.extend_from_slice(&particles.velocity);
    }
    let report = solver.resolve(mesh, settings.dt, start, end, velocity);
    frame.add(&report);
    solver.springs(mesh, settings.dt, start, end, velocity, springs);
    for (c, (_, mut particles, .., mut touching)) in (&mut cloths).into_iter().enumerate() {
        let range = mesh.first[c] as usize..mesh.first[c + 1] as usize;
        particles.position.copy_from_slice(&end[range.clone()]);
        particles.velocity.copy_from_slice(&velocity[range]);
        let SelfTouching { springs: own, across } = &mut *touching;
        own.clear();
        across.clear();
        reserve_floored(own, springs.len());
        for s in springs.iter() {
            if let Some(spring) = split_spring(s, c as u32, mesh, own.len(), across) {
                own.push(spring);
            }
        }
    }
}

/// The spring of cloth `cloth` that `spring` (in the contact mesh's numbers) makes, if any
/// of its vertices is the cloth's: the spring itself in the cloth's numbers, or, for a
/// pair with another cloth whose side the contact stage holds (pinned, or resting on a
/// body), this cloth's side of it, the other's vertices weighed zero, the other side
/// pushed to `across` as the cloth's spring `index` (the step places it where it will be,
/// `ClothEnds::place`). A pair with a free side of another cloth makes none: a spring of
/// one cloth has no reaction on the other, and a cloth landing on a free cloth was
/// stopped dead, its momentum lost (or, held against where the free cloth would be, the
/// two were thrown apart with six times the energy there was); the contact stage's
/// impulses, which act on both, keep it.
fn split_spring(
    spring: &ContactSpring,
    cloth: u32,
    mesh: &ContactMesh,
    index: usize,
    across: &mut Vec<Across>,
) -> Option<ContactSpring> {
    let Stencil { vertices, weights } = spring.stencil;
    let own = vertices.iter().position(|&k| mesh.cloth_of(k) == cloth)?;
    let outside = |k: &u32| mesh.cloth_of(*k) != cloth;
    if vertices.iter().filter(|k| outside(k)).any(|&k| !mesh.held(k)) {
        return None;
    }
    let local = |k: u32| k - mesh.first[mesh.cloth_of(k) as usize];
    let mut stencil = Stencil { vertices: vertices.map(local), weights };
    let mut other = Across { spring: index as u32, cloth, vertices: [0; 3], weights: [0.0; 3] };
    for (slot, k) in (0..4).filter(|&k| outside(&vertices[k])).enumerate() {
        other.cloth = mesh.cloth_of(vertices[k]);
        other.vertices[slot] = stencil.vertices[k];
        other.weights[slot] = weights[k];
        stencil.vertices[k] = stencil.vertices[own];
        stencil.weights[k] = 0.0;
    }
    if other.cloth != cloth {
        reserve_floored(across, 1);
        across.push(other);
    }
    Some(ContactSpring { stencil, ..*spring })
}

/// Starts each frame's contact sums from zero. Runs in [`FrameSystems::Prepare`].
pub fn reset_contact_stats(mut cloths: Query<&mut ContactStats>, mut contacts: ResMut<ClothContacts>) {
    for mut stats in &mut cloths {
        *stats = ContactStats::default();
    }
    contacts.frame = SelfContactReport::default();
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.frame.add_systems(reset_contact_stats.in_set(FrameSystems::Prepare));
    schedules.substep.add_systems(collide_with_bodies.in_set(SubstepSystems::BodyContacts));
    schedules.substep.add_systems(collide_cloths.in_set(SubstepSystems::SelfContacts));
}
