//! End-of-frame work: the health check and the frame count, and the probes after them.

use bevy_ecs::prelude::*;
use glam::Vec3;

use super::forces::{ForceElements, ForceEnvironment};
use crate::collision::body_contact::ContactTotals;
use crate::collision::intersection::IntersectionCounter;
use crate::components::{
    Cloth, Collider, ContactStats, MembraneTriangles, Particles, Pins, SelfCollision, SolverWorkspace, Springs,
    Triangles,
};
use crate::resources::{
    ClothContacts, DivergenceLimit, HealthProblem, HealthReport, ProbeRequests, Probes, SimClock, StepSettings,
};
use crate::schedule::{FrameSystems, SimSchedules};
use crate::solver::health::{Unhealthy, check_health};
use crate::solver::pins::pin_reaction;
use crate::solver::probes::kinetic_energy;

/// Records the first cloth whose state is non-finite or stretched past the divergence
/// limit (MuJoCo's `mj_checkPos`, as a named stage), and the largest edge strain over all
/// cloths. Runs in [`FrameSystems::Finish`].
pub fn check_cloth_health(
    limit: Res<DivergenceLimit>,
    mut health: ResMut<HealthReport>,
    cloths: Query<(&Cloth, &Particles, &Springs, &MembraneTriangles)>,
) {
    if health.problem.is_some() {
        return;
    }
    health.max_strain = 0.0;
    for (cloth, particles, springs, membranes) in &cloths {
        let (x, v, rest) = (&particles.position, &particles.velocity, &particles.rest_position);
        match check_health(x, v, rest, springs, membranes, limit.max_strain) {
            Ok(strain) => health.max_strain = health.max_strain.max(strain),
            Err(problem) => {
                if let Unhealthy::Overstretched { strain, .. } = problem {
                    health.max_strain = health.max_strain.max(strain);
                }
                health.problem = Some(HealthProblem { cloth: cloth.name.clone(), problem: problem.to_string() });
                return;
            }
        }
    }
}

/// Measures the frame's probes over all cloths: `kinetic_energy_j`, `potential_energy_j`
/// (gravity about y = 0 plus elastic energy), `max_strain` (largest edge strain, springs
/// and membrane triangle sides, as the frame's health check measured it), `pin_force_n`
/// (magnitude of the total force the pins carry, from the forces at the frame's final
/// state) and `self_intersections` (pairs of non-adjacent triangles of a cloth that
/// intersect, by an exact test independent of the contact code).
/// Runs in [`ProbeSchedule`](crate::schedule::ProbeSchedule).
pub fn measure_probes(
    environment: ForceEnvironment,
    health: Res<HealthReport>,
    mut probes: ResMut<Probes>,
    mut cloths: Query<(&Particles, ForceElements, &Pins, &mut SolverWorkspace)>,
    mut counter: Local<IntersectionCounter>,
) {
    let (mut kinetic, mut potential, mut pin_force) = (0.0, 0.0, Vec3::ZERO);
    let mut intersections = 0;
    for (particles, elements, pins, mut workspace) in &mut cloths {
        let model = environment.model(&particles.inv_mass, elements);
        intersections += counter.count(&particles.position, model.triangles);
        kinetic += kinetic_energy(&particles.velocity, &particles.inv_mass);
        let forces = &mut workspace.forces;
        potential += model.potential_energy(&particles.position, forces);
        if !pins.is_empty() {
            let (x, v) = (&particles.position, &particles.velocity);
            pin_force += pin_reaction(model.pin_forces(x, v, environment.time(), forces));
        }
    }
    probes.set("kinetic_energy_j", kinetic);
    probes.set("potential_energy_j", potential);
    probes.set("max_strain", f64::from(health.max_strain));
    probes.set("pin_force_n", f64::from(pin_force.length()));
    probes.set("self_intersections", intersections as f64);
}

/// Measures the cloth probes the scene asked for (cantilever angle, drape coefficient,
/// mean stress). Runs in [`ProbeSchedule`](crate::schedule::ProbeSchedule).
pub fn measure_cloth_probes(
    requests: Res<ProbeRequests>,
    mut probes: ResMut<Probes>,
    cloths: Query<(&Cloth, &Particles, &Triangles, &MembraneTriangles)>,
) {
    for request in &requests.0 {
        if let Some((_, particles, triangles, membranes)) = cloths.iter().find(|(c, ..)| c.name == request.cloth()) {
            let value = request.measure(&particles.position, &particles.rest_position, &triangles.indices, membranes);
            probes.set(request.name(), value);
        }
    }
}

/// Measures contact over the frame, when the scene has bodies: `contact_force_n`
/// (magnitude of the frame-averaged vector sum of contact forces on all cloths),
/// `contact_pressure_pa` and `friction_stress_pa` (mean normal and friction force per
/// contact area), `max_penetration_m` (deepest particle inside a body), `contact_corrections`
/// (particles the contact stage found within the contact thickness of a body, or whose path
/// crossed one, and put back, summed over the frame's steps). Runs in
/// [`ProbeSchedule`](crate::schedule::ProbeSchedule).
pub fn measure_contact_probes(
    settings: Res<StepSettings>,
    colliders: Query<(), With<Collider>>,
    cloths: Query<&ContactStats>,
    mut probes: ResMut<Probes>,
) {
    if colliders.is_empty() {
        return;
    }
    let frame_time = f64::from(settings.dt) * f64::from(settings.substeps);
    let total = cloths.iter().fold(ContactTotals::default(), |mut sum, s| {
        sum.add(&s.0);
        sum
    });
    // Mean force over mean area: (ΣJ / T) / (ΣA / steps) = ΣJ / (dt ΣA).
    let per_area = |impulse: f32| {
        if total.contact_area > 0.0 {
            f64::from(impulse) / (f64::from(settings.dt) * f64::from(total.contact_area))
        } else {
            0.0
        }
    };
    probes.set("contact_force_n", f64::from(total.impulse.length()) / frame_time);
    probes.set("contact_pressure_pa", per_area(total.normal_impulse));
    probes.set("friction_stress_pa", per_area(total.friction_impulse));
    probes.set("max_penetration_m", f64::from(total.max_penetration));
    probes.set("contact_corrections", f64::from(total.corrections));
}

/// Reports self contact over the frame, when a cloth collides with itself:
/// `self_contact_pairs` (mean number of pairs closer than their separation per step),
/// `self_impacts` (continuous collisions resolved by impulses in the frame) and
/// `impact_zone_rounds` (rounds of rigid impact zones the frame needed; 0 when impulses
/// sufficed) and `untangle_crossings` (edge–triangle crossings found at the starts of the
/// frame's steps, summed, and being untangled; 0 once the cloths are apart). Runs in
/// [`ProbeSchedule`](crate::schedule::ProbeSchedule).
pub fn measure_self_contact_probes(
    settings: Res<StepSettings>,
    contacts: Res<ClothContacts>,
    cloths: Query<(), With<SelfCollision>>,
    mut probes: ResMut<Probes>,
) {
    if cloths.is_empty() {
        return;
    }
    let frame = &contacts.frame;
    probes.set("self_contact_pairs", f64::from(frame.proximity) / f64::from(settings.substeps.max(1)));
    probes.set("self_impacts", f64::from(frame.impacts));
    probes.set("impact_zone_rounds", f64::from(frame.zone_rounds));
    probes.set("untangle_crossings", f64::from(frame.crossings));
}

/// Counts the frame. Runs in [`FrameSystems::Finish`], last.
pub fn count_frame(mut clock: ResMut<SimClock>) {
    clock.frame += 1;
}

/// Adds this module's systems.
pub fn add_to(schedules: &mut SimSchedules) {
    schedules.frame.add_systems((check_cloth_health, count_frame).chain().in_set(FrameSystems::Finish));
    schedules.probe.add_systems(
        (measure_probes, measure_cloth_probes, measure_contact_probes, measure_self_contact_probes).chain(),
    );
}
