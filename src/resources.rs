//! World-wide settings and state: the step, gravity, air, solver choice, ground, clock,
//! health, probes and scheduled edits.

use std::collections::BTreeMap;

use bevy_ecs::prelude::*;
use glam::Vec3;
use rapier3d::prelude::PhysicsWorld;

use crate::builders::pins::PinSelection;
use crate::builders::tear::Cut;
use crate::collision::self_contact::{ContactMesh, SelfContactReport, SelfContactSolver};
use crate::solver::contact_springs::ContactSpring;
use crate::solver::forces::Air;
use crate::solver::integrate::{Integrator, MethodSettings, StageTimes};
use crate::solver::probes::ClothProbe;

/// How time advances: a frame is `substeps` steps of `dt`.
#[derive(Resource, Debug, Clone, Copy, PartialEq)]
pub struct StepSettings {
    /// Length of one step [s].
    pub dt: f32,
    /// Steps per frame.
    pub substeps: u32,
}

/// A frame's steps chosen from the motion (`solver.step_motion`): as few as keep every
/// particle's move towards what it may touch within `motion` mean edges of its cloth per
/// step, and at most `most` (planned by [`crate::systems::substeps::plan_frame_steps`]).
/// Substeps exist for contact: a particle stopped by a body after the solve, while its
/// neighbours are not, strains the cloth by about its step's move (on sphere_64's
/// landing, at 2.4 m/s, 0.22 and 0.28 mean edges a step, 10 and 8 steps a frame, held the
/// largest strain to 6 %, 0.32 gave 35 % and 0.45 tore the sheet), and a cloth at rest on
/// a body moves far less. Still, a frame takes at least `least`: a particle that static
/// friction holds on a body is held for a whole step (`solver.min_substeps`).
#[derive(Resource, Debug, Clone, Copy, PartialEq)]
pub struct AdaptiveSteps {
    /// Length of a frame [s].
    pub frame_time: f32,
    /// Fewest steps a frame takes.
    pub least: u32,
    /// Most steps a frame takes.
    pub most: u32,
    /// How far a particle may move in a step [mean edge lengths].
    pub motion: f32,
}

impl AdaptiveSteps {
    /// Steps for a frame in which no particle moves farther than `reach` mean edges, and
    /// no fewer than `least`; all of them for an infinite reach (or one that is not a
    /// number).
    pub fn steps(&self, reach: f32) -> u32 {
        if reach.is_finite() { ((reach / self.motion).ceil() as u32).clamp(self.least, self.most) } else { self.most }
    }

    /// The step of a frame of `steps` steps.
    pub fn settings(&self, steps: u32) -> StepSettings {
        StepSettings { dt: self.frame_time / steps as f32, substeps: steps }
    }
}

/// Gravitational acceleration [m/s²].
#[derive(Resource, Debug, Clone, Copy, PartialEq)]
pub struct Gravity(pub Vec3);

/// The air every cloth moves through.
#[derive(Resource, Debug, Clone, Copy, PartialEq, Default)]
pub struct AirSettings(pub Air);

/// The integrator every cloth uses, and its settings.
#[derive(Resource, Debug, Clone, Copy, PartialEq)]
pub struct SolverSettings {
    /// Integration method.
    pub integrator: Integrator,
    /// Tolerances, θ, Rayleigh damping, solver limits.
    pub method: MethodSettings,
}

/// Simulated time.
#[derive(Resource, Debug, Clone, Copy, PartialEq, Default)]
pub struct SimClock {
    /// Time since the start [s].
    pub time_s: f64,
    /// Steps taken.
    pub step: u64,
    /// Frames completed.
    pub frame: u64,
}

impl SimClock {
    /// The time at the end of the step of length `dt` [s] now being taken: where moving
    /// bodies and grips are when the step's contacts and constraints are resolved.
    pub fn step_end(&self, dt: f32) -> f32 {
        (self.time_s + f64::from(dt)) as f32
    }
}

/// Limits past which a run is declared diverged.
#[derive(Resource, Debug, Clone, Copy, PartialEq)]
pub struct DivergenceLimit {
    /// Largest spring strain tolerated [-].
    pub max_strain: f32,
}

/// A cloth whose state went bad, found by the health check.
#[derive(Debug, Clone, PartialEq)]
pub struct HealthProblem {
    /// Name of the cloth.
    pub cloth: String,
    /// What is wrong with it.
    pub problem: String,
}

/// The health check's verdict for the last frame.
#[derive(Resource, Debug, Clone, Default, PartialEq)]
pub struct HealthReport {
    /// The first problem found, if any.
    pub problem: Option<HealthProblem>,
    /// The largest edge strain of any cloth at the last check (0 without edges): the
    /// check measures it to compare with the divergence limit, and the `max_strain` probe
    /// reports it.
    pub max_strain: f32,
}

/// Named measurements of the last frame, in name order. Any system may add a probe; the
/// CLI writes all of them to `summary.json` and `probes.csv`.
#[derive(Resource, Debug, Clone, Default, PartialEq)]
pub struct Probes {
    /// Probe values by name.
    pub values: BTreeMap<&'static str, f64>,
}

impl Probes {
    /// Sets probe `name` for this frame.
    pub fn set(&mut self, name: &'static str, value: f64) {
        self.values.insert(name, value);
    }

    /// The value of probe `name`, if measured.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.values.get(name).copied()
    }
}

/// The measurements of particular cloths the scene asked for.
#[derive(Resource, Debug, Clone, Default, PartialEq)]
pub struct ProbeRequests(pub Vec<ClothProbe>);

/// Work the integrators did, summed over the run.
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq)]
pub struct IntegratorStats {
    /// Accepted internal steps.
    pub accepted: u64,
    /// Rejected internal steps (adaptive only).
    pub rejected: u64,
    /// Evaluations of the force model, start-of-step ones included.
    pub evaluations: u64,
    /// Conjugate-gradient iterations of the implicit methods.
    pub iterations: u64,
    /// Where the implicit steps' time went.
    pub stages: StageTimes,
}

/// A change to a cloth's structure at a given time.
#[derive(Debug, Clone, PartialEq)]
pub enum EditAction {
    /// Cut every spring and triangle that crosses the cut.
    Tear(Cut),
    /// Pin the selected particles where they are.
    Pin(Vec<PinSelection>),
    /// Release the selected particles.
    Unpin(Vec<PinSelection>),
}

/// An edit due at a time.
#[derive(Debug, Clone, PartialEq)]
pub struct ScheduledEdit {
    /// When to apply it [s].
    pub at_s: f64,
    /// Name of the cloth it applies to.
    pub cloth: String,
    /// What to do.
    pub action: EditAction,
}

/// Edits waiting for their time, sorted by it.
#[derive(Resource, Debug, Clone, Default, PartialEq)]
pub struct ScheduledEdits {
    /// Pending edits, earliest first.
    pub pending: Vec<ScheduledEdit>,
}

/// Every self-colliding cloth as one contact mesh (so layers collide with one another as
/// well as with themselves), the trees over it kept from step to step, and what self
/// contact did in the current frame.
#[derive(Resource, Debug, Default)]
pub struct ClothContacts {
    /// The cloths in the mesh, in order: entity and the topology build it was made from.
    pub members: Vec<(Entity, u32)>,
    /// The combined mesh.
    pub mesh: ContactMesh,
    /// Trees and scratch space.
    pub solver: SelfContactSolver,
    /// Gathered start positions, end positions and velocities of a step.
    pub start: Vec<Vec3>,
    /// End positions.
    pub end: Vec<Vec3>,
    /// Velocities.
    pub velocity: Vec<Vec3>,
    /// Sums over the steps of the current frame.
    pub frame: SelfContactReport,
    /// The springs of the next step, numbered over the whole mesh.
    pub springs: Vec<ContactSpring>,
}

/// The rigid-body world of the scene's props (rapier3d), with stand-ins for its colliders;
/// present only when the scene has props. Stepped with the cloth, by the same step and
/// gravity.
#[derive(Resource, Default)]
pub struct PropWorld(pub PhysicsWorld);
