//! Implicit integration: the θ-method, linearised at the start of each step (with optional
//! further Newton iterations), solved by preconditioned conjugate gradients over the
//! block-sparse derivatives.
//!
//! Elastic and external forces are weighted by θ, damping forces (element damping, air
//! drag and Rayleigh damping `C = αM − βK`, α [1/s], β [s]) are taken at the end of the
//! step. With `K = ∂f/∂x` and `D` the damping's `∂f/∂v`, the linearised step is
//!
//! `((1 + hα) M − h D − (hβ + h²θ²) K) Δv = h f₀ − hα M v₀ + (hβ + h²θ) K v₀`,
//! `x₁ = x₀ + h (v₀ + θ Δv)`.
//!
//! θ = 1 without Rayleigh damping is Baraff & Witkin's implicit Euler. θ = ½ with α, β is
//! Bricis's Newmark average-acceleration scheme (eqs 6.57–6.60) for the elastic forces.
//! Bricis weights the damping by θ too; but the trapezoidal rule is not L-stable, and the
//! stiff modes that a large β overdamps then ring at every step instead of decaying (a
//! 32×32 cotton sheet at Δt = 0.1 s never came to rest: 0.09 J of kinetic energy after
//! 30 s). Damping at the end of the step relaxes them at their physical rate 1/β and
//! leaves the undamped elastic motion without numerical damping. Pinned particles are
//! filtered out of the solve (their Δv stays zero), as in Baraff & Witkin's modified PCG.

use std::time::Instant;

use glam::{Mat3, Vec3, Vec3A};
use rayon::prelude::*;

use super::contact_springs::{self, ContactSpring, SpringTerms, Weights};
use super::descent::{BoundedMotion, Colouring, DescentSettings, DescentWorkspace, descend};
use super::elements::block::times;
use super::elements::spring::outer;
use super::elements::{BlockPattern, ConstantCouplings, SymmetricBlockMatrix, VelocityJacobian, WeightedCouplings};
use super::filter::Filters;
use super::integrate::{Dynamics, StageTimes, StepReport};
use super::multigrid::{Hierarchy, Multigrid};
use super::spring_couplings::SpringCouplings;
use super::warm_start::WarmStart;
use super::{PARALLEL_MIN_LEN, add_rows};
use crate::collision::body_bounds;
use crate::collision::body_contact::ContactBody;
use crate::collision::motion_bounds::{Bound, LayerContact, Mobility, MotionBounds, Others, Resting, Surface};

/// Rayleigh damping `C = αM + βK_s` (K_s the stiffness, `−∂f/∂x`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Rayleigh {
    /// Mass-proportional coefficient α [1/s].
    pub alpha: f32,
    /// Stiffness-proportional coefficient β [s].
    pub beta: f32,
}

impl Rayleigh {
    /// The coefficients that give damping ratio `ratio` at both angular frequencies
    /// `omega1` and `omega2` [rad/s], from `α + β ω² = 2 ω ξ` (Bricis eq. 6.53).
    pub fn from_frequencies(omega1: f32, omega2: f32, ratio: f32) -> Self {
        let beta = 2.0 * ratio / (omega1 + omega2);
        Self { alpha: 2.0 * ratio * omega1 * omega2 / (omega1 + omega2), beta }
    }
}

/// How the implicit step is set up and solved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImplicitSettings {
    /// θ ∈ [½, 1]: 1 is implicit Euler, ½ the trapezoidal (Newmark average-acceleration) rule.
    pub theta: f32,
    /// Rayleigh damping.
    pub rayleigh: Rayleigh,
    /// Relative residual at which conjugate gradients stop [-].
    pub cg_tolerance: f32,
    /// Iteration cap of conjugate gradients.
    pub cg_max_iterations: u32,
    /// Newton iterations per step: 1 is the linearly implicit step (Baraff & Witkin);
    /// more solve the nonlinear θ-step, which the trapezoidal rule needs to keep its
    /// stability when the forces are far from linear over a step.
    pub newton_iterations: u32,
    /// How each Newton system is solved.
    pub linear_solver: LinearSolver,
}

/// The solver of the linear system of each Newton iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LinearSolver {
    /// Block-Jacobi preconditioned conjugate gradients to `cg_tolerance`: accurate, but
    /// on stiff cloth at frame-sized steps it takes hundreds of iterations.
    ConjugateGradient,
    /// Conjugate gradients to `cg_tolerance` preconditioned by a smoothed-aggregation
    /// multigrid V-cycle ([`super::multigrid`]): each iteration costs about four of block
    /// Jacobi's, but the iterations no longer grow with the cloth's size and stiffness.
    Multigrid,
    /// Coloured block Gauss–Seidel with Chebyshev acceleration ([`super::descent`]): a
    /// fixed number of parallel sweeps, stopping early at `cg_tolerance`.
    BlockDescent(DescentSettings),
}

/// A system whose forces can be linearised: what an implicit solver needs beyond
/// [`Dynamics`]. Shared by the parallel loops that build the step's system.
pub trait LinearDynamics: Dynamics + Sync {
    /// The block pattern of the derivatives.
    fn pattern(&self) -> &BlockPattern;
    /// Mass of particle `i` [kg].
    fn mass(&self, i: usize) -> f32;
    /// Whether particle `i` is free to move (not pinned).
    fn is_free(&self, i: usize) -> bool;
    /// The particles grouped so that no two of a group share a block of the pattern.
    fn colouring(&self) -> &Colouring;
    /// The particles grouped level by level, for the multigrid preconditioner.
    fn hierarchy(&self) -> &Hierarchy;
    /// The derivatives' constant couplings outside their pattern, if any
    /// ([`ConstantCouplings`]: the quadratic bending's across an edge); none where the
    /// pattern holds every coupling.
    fn constant_couplings(&self) -> Option<&ConstantCouplings> {
        None
    }
    /// The surface whose contact with itself bounds each iteration of block descent, if
    /// the system collides with itself.
    fn contact_surface(&self) -> Option<Surface<'_>> {
        None
    }
    /// How the layers of the system's cloth meet, where it collides with itself: what a
    /// layer resting on a still one of it keeps to within block descent's sweeps.
    fn layer_contact(&self) -> Option<LayerContact> {
        None
    }
    /// The other cloths the system's cloth collides with, standing still while it is
    /// solved, which bound each iteration of block descent too.
    fn contact_others(&self) -> Option<Others<'_>> {
        None
    }
    /// The solid bodies, where the step ends, that bound each iteration of block descent.
    fn contact_bodies(&self) -> &[ContactBody] {
        &[]
    }
    /// The cloth–cloth contacts the step holds apart with springs in the solve.
    fn contact_springs(&self) -> &[ContactSpring] {
        &[]
    }
    /// The same, to lag their friction from the step's solution.
    fn contact_springs_mut(&mut self) -> &mut [ContactSpring] {
        &mut []
    }
    /// Forces [N] and their semi-definite derivatives at `(x, v, t)`.
    fn linearize(
        &mut self,
        x: &[Vec3],
        v: &[Vec3],
        t: f32,
        force: &mut [Vec3],
        dfdx: &mut SymmetricBlockMatrix,
        dfdv: &mut VelocityJacobian,
    );
}

/// Buffers of the implicit step, reused from step to step.
#[derive(Debug, Clone, Default)]
pub struct ImplicitWorkspace {
    start_force: Vec<Vec3>,
    /// ∂f/∂x and the system `A` share one storage, which moves from one to the other: a
    /// matrix of the pattern is some 350 bytes a particle, and nothing reads ∂f/∂x once
    /// `A` is built from it, nor `A` once the step linearises again.
    dfdx: SymmetricBlockMatrix,
    dfdv: VelocityJacobian,
    system: SymmetricBlockMatrix,
    rhs: Vec<Vec3>,
    dv: Vec<Vec3>,
    delta: Vec<Vec3>,
    /// The conjugate gradients' residual and search direction; between solves, the
    /// scratch of the Newton iterations' damping change and of the contact springs' force
    /// and stiffness product ([`add_springs`]), which no solve is reading then.
    residual: Vec<Vec3>,
    direction: Vec<Vec3>,
    /// The conjugate gradients' `A d`, then, once `r` is updated from it, the
    /// preconditioned residual `M⁻¹ r`: the one dies where the other is formed, so they
    /// share a buffer (12 bytes a particle).
    product: Vec<Vec3>,
    x: Vec<Vec3>,
    v: Vec<Vec3>,
    preconditioner: Vec<Mat3>,
    /// The weights of stiffness (`hβ + h²θ²`) and damping (`h`) in the system, which the
    /// contact springs' off-diagonal blocks take in each product.
    spring_weights: Weights,
    /// The contact springs' terms of the assembly's products and forces.
    spring_terms: SpringTerms,
    /// The acting contact springs' couplings in the system's products, prepared with the
    /// system, and their pushes in a product.
    spring_couplings: SpringCouplings,
    spring_pushes: Vec<Vec3>,
    /// Per chunk of [`VECTOR_CHUNK`] particles, the partial sums of the CG's dot products.
    partials: Vec<f64>,
    /// Per particle, the directions its Δv may take: identity (free), zero (pinned) or a
    /// projection off a contact normal.
    filter: Filters,
    /// Per particle, the part of Δv the constraints prescribe; empty, meaning zero, where
    /// there are no bodies to touch ([`prescribe`]).
    prescribed: Vec<Vec3>,
    /// Block descent's buffers.
    descent: DescentWorkspace,
    /// Where block descent's contact bounds were last measured, free of crossings.
    anchor: Vec<Vec3>,
    /// The search for the contact bounds.
    motion_bounds: MotionBounds,
    /// The multigrid preconditioner's levels.
    multigrid: Multigrid,
    /// The last steps' solutions, where conjugate gradients start the next.
    warm_start: WarmStart,
    /// Whether the preconditioner (block Jacobi's inverses or the multigrid's levels) was
    /// prepared for the system as it is now. Building the system or changing its contact
    /// springs makes it stale, so that the solves of one system (a loose one whose solution
    /// the friction is lagged from, then the accurate one) prepare it once: on the first 60
    /// frames of sphere_64 with multigrid, the step prepared its preconditioner 2.5 times.
    prepared: Prepared,
    /// Where the step's time has gone so far, for its report.
    stages: StageTimes,
    /// Impulse each contact constraint applied in the last step [N·s], parallel to the
    /// constraints passed to [`implicit_step`].
    pub constraint_impulses: Vec<Vec3>,
}

/// A particle touching a body: in the implicit solve its velocity along `normal` is set to
/// the body's (`velocity`), the rest left to the solve, or, where static friction holds
/// it (`stick`), its whole velocity — Baraff & Witkin's constraint by filtering, so that
/// the solver, not a projection after it, keeps cloth resting on a body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VelocityConstraint {
    /// The particle.
    pub particle: u32,
    /// Unit normal of the body at the contact, pointing out of the body.
    pub normal: Vec3,
    /// Velocity the particle must have at the end of the step [m/s]: along the normal
    /// only, or whole when `stick`.
    pub velocity: Vec3,
    /// Whether the whole velocity is prescribed (static friction), not only its normal
    /// part.
    pub stick: bool,
}

/// Bodies whose velocities are unknowns of the step, such as free rigid props: the
/// constraints holding particles on them prescribe the bodies' velocities, and the bodies'
/// velocities depend on the impulses those constraints need. [`implicit_step`] solves
/// again, with the velocities [`ConstraintBodies::rebalance`] asks for, until it asks for
/// no change, so the cloth and the bodies end the step in balance (strong coupling).
pub trait ConstraintBodies {
    /// Given the impulses [N·s] the `constraints` needed in a solve with `system`, moves
    /// their prescribed velocities towards the bodies' balance; returns false, changing
    /// nothing, once they are within tolerance of it.
    fn rebalance(&mut self, system: StepSystem<'_>, constraints: &mut [VelocityConstraint], impulses: &[Vec3]) -> bool;
}

/// The most solves a step makes for its [`ConstraintBodies`] after the first.
const MAX_BODY_ITERATIONS: usize = 12;

/// A step's implicit system.
#[derive(Clone, Copy)]
pub struct StepSystem<'a> {
    /// Which blocks exist.
    pub pattern: &'a BlockPattern,
    /// `A = (1 + hα) M − h ∂f/∂v − (hβ + h²θ²) ∂f/∂x`, over the pattern.
    pub matrix: &'a SymmetricBlockMatrix,
    /// Its constant couplings outside the pattern, if any (the quadratic bending's across
    /// an edge).
    pub far: Option<WeightedCouplings<'a>>,
}

impl<'a> StepSystem<'a> {
    /// The system of `matrix` over `pattern`, with nothing outside it.
    pub fn new(pattern: &'a BlockPattern, matrix: &'a SymmetricBlockMatrix) -> Self {
        Self { pattern, matrix, far: None }
    }

    /// The system of `matrix` over `pattern` with `couplings` outside it, if any, at
    /// `weight`.
    fn with_couplings(
        pattern: &'a BlockPattern,
        matrix: &'a SymmetricBlockMatrix,
        couplings: Option<&'a ConstantCouplings>,
        weight: f32,
    ) -> Self {
        let far = couplings.filter(|c| c.has_rows(pattern.rows())).map(|c| c.weighted(weight));
        Self { pattern, matrix, far }
    }

    /// The diagonal block of particle `i`.
    pub fn diagonal(&self, i: usize) -> Mat3 {
        self.matrix.diagonal(self.pattern, i)
    }

    /// Row `i` times `x`.
    #[inline]
    pub fn row_product(&self, i: usize, x: &[Vec3]) -> Vec3 {
        let within = self.matrix.row_product(self.pattern, i, x);
        self.far.map_or(within, |far| within + far.row_product(i, x))
    }

    /// Calls `visit(column, block)` for every block of row `i`: the pattern's, columns
    /// ascending, then the couplings outside it.
    pub fn for_row(&self, i: usize, mut visit: impl FnMut(u32, Mat3)) {
        self.matrix.for_row(self.pattern, i, |j, block, _| visit(j, block));
        if let Some(far) = self.far {
            far.for_row(i, visit);
        }
    }

    /// `out = A y`.
    pub fn multiply(&self, y: &[Vec3], out: &mut [Vec3]) {
        self.matrix.multiply(self.pattern, y, out);
        if let Some(far) = self.far {
            add_rows(out, |i| far.row_product(i, y));
        }
    }
}

/// The system of `matrix` over `dynamics`' pattern at stiffness weight `stiffness`, with
/// the dynamics' constant couplings outside the pattern (∂f/∂x's at weight 1, the
/// system's at `−(hβ + h²θ²)`).
fn step_system<'a>(
    dynamics: &'a impl LinearDynamics,
    matrix: &'a SymmetricBlockMatrix,
    stiffness: f32,
) -> StepSystem<'a> {
    StepSystem::with_couplings(dynamics.pattern(), matrix, dynamics.constant_couplings(), stiffness)
}

/// Relative size of a Newton correction below which the step counts as converged.
const NEWTON_TOLERANCE: f64 = 1e-5;

/// Advances `(x, v)` by one implicit θ-step of length `h`, with pinned particles held and
/// `constraints` keeping contacts.
pub fn implicit_step(
    settings: &ImplicitSettings,
    dynamics: &mut impl LinearDynamics,
    constraints: &mut [VelocityConstraint],
    bodies: Option<&mut dyn ConstraintBodies>,
    x: &mut [Vec3],
    v: &mut [Vec3],
    t: f32,
    h: f32,
    ws: &mut ImplicitWorkspace,
) -> StepReport {
    let n = x.len();
    for buffer in [&mut ws.rhs, &mut ws.delta, &mut ws.residual, &mut ws.direction, &mut ws.product] {
        buffer.resize(n, Vec3::ZERO);
    }
    // The start force and Δv apart from the last solution only for Newton iterations, and
    // an end state only for them, the contact springs' friction and block descent's
    // bounds: 48 bytes a particle of a cloth that needs none (the hangs). Sized from the
    // settings and the cloth, not from what it touches now, so that a warm step does
    // not allocate them when contact begins.
    let newton = iterates(settings);
    if newton {
        ws.start_force.resize(n, Vec3::ZERO);
        ws.dv.resize(n, Vec3::ZERO);
    }
    if newton || dynamics.contact_surface().is_some() || descent_bounds(settings) {
        ws.x.resize(n, Vec3::ZERO);
        ws.v.resize(n, Vec3::ZERO);
    }
    ws.filter.reset(n, |i| dynamics.is_free(i));
    ws.filter.reserve(constraints.len());
    for c in constraints.iter() {
        let projection = if c.stick { Mat3::ZERO } else { Mat3::IDENTITY - outer(c.normal, c.normal) };
        ws.filter.constrain(c.particle as usize, projection);
    }
    prescribe(dynamics, constraints, v, &mut ws.prescribed);
    let (theta, Rayleigh { alpha, beta }) = (settings.theta, settings.rayleigh);
    let mut report = StepReport { accepted: 1, ..StepReport::default() };
    if bounded(settings, dynamics) {
        // The step starts free of crossings, and at Δv = 0 moves inertially.
        ws.anchor.clear();
        ws.anchor.extend_from_slice(x);
        for i in 0..n {
            ws.x[i] = x[i] + h * v[i];
        }
    }

    // Linearised step about the start: F₀ = f₀ − αMv₀ + βKv₀, and
    // A Δv = h F₀ + h²θ K v₀.
    let assembly = Instant::now();
    ws.dfdx = std::mem::take(&mut ws.system);
    // The forces go where the right-hand side is then formed in place: a buffer of their
    // own was 12 bytes a particle.
    dynamics.linearize(x, v, t, &mut ws.rhs, &mut ws.dfdx, &mut ws.dfdv);
    step_system(dynamics, &ws.dfdx, 1.0).multiply(v, &mut ws.product);
    let springs = springs_of(settings, dynamics);
    contact_springs::add_forces(springs, &mut ws.spring_terms, x, v, &mut ws.rhs);
    contact_springs::add_product(springs, &mut ws.spring_terms, STIFFNESS, v, &mut ws.product);
    for i in 0..n {
        let start = ws.rhs[i] - alpha * dynamics.mass(i) * v[i] + beta * ws.product[i];
        if newton {
            ws.start_force[i] = start;
        }
        ws.rhs[i] = h * start + h * h * theta * ws.product[i];
    }
    build_system(settings, h, dynamics, ws);
    ws.stages.assembly += assembly.elapsed();
    // Where the springs will be lagged from this solution (their friction, armed springs
    // engaged), it need not be accurate: only the last lagged solve is.
    let lagged = contact_springs::lagged_from_solves(springs_of(settings, dynamics));
    let (tolerance, guide) = (settings.cg_tolerance, LAG_LOOSENING * settings.cg_tolerance);
    let first = if lagged { guide } else { tolerance };
    let start = match starts_warm(settings) && projected_start(dynamics, ws) {
        true => Start::Projected,
        false => Start::Prescribed,
    };
    report.iterations += solve(dynamics, settings, start, first, x, h * theta, ws);
    let mut accurate = !lagged;
    set_constraint_impulses(dynamics, constraints, ws);
    // Bodies moved by the constraints' impulses: solve again, from the last solution, with
    // the velocities their balance asks for, until they settle.
    if let Some(bodies) = bodies {
        for _ in 0..MAX_BODY_ITERATIONS {
            let system = step_system(dynamics, &ws.system, -ws.spring_weights.stiffness);
            if !bodies.rebalance(system, constraints, &ws.constraint_impulses) {
                break;
            }
            for (delta, prescribed) in ws.delta.iter_mut().zip(&ws.prescribed) {
                *delta -= *prescribed;
            }
            prescribe(dynamics, constraints, v, &mut ws.prescribed);
            for (delta, prescribed) in ws.delta.iter_mut().zip(&ws.prescribed) {
                *delta += *prescribed;
            }
            report.iterations += solve(dynamics, settings, Start::Given, tolerance, x, h * theta, ws);
            accurate = true;
            set_constraint_impulses(dynamics, constraints, ws);
        }
    }
    if lagged {
        for lag in 1..=FRICTION_LAGS {
            let lag_tolerance = if lag == FRICTION_LAGS { tolerance } else { guide };
            match lag_friction(dynamics, settings, lag_tolerance, constraints, x, v, h, ws) {
                Some(iterations) => {
                    report.iterations += iterations;
                    accurate = lag == FRICTION_LAGS;
                }
                None => break,
            }
        }
        if !accurate {
            report.iterations += solve(dynamics, settings, Start::Given, tolerance, x, h * theta, ws);
            set_constraint_impulses(dynamics, constraints, ws);
        }
    }
    if newton {
        ws.dv.copy_from_slice(&ws.delta);
    }
    if starts_warm(settings) {
        ws.warm_start.keep(&ws.delta);
    }
    for _ in 1..settings.newton_iterations {
        end_of_step(x, v, &ws.dv, h, theta, &mut ws.x, &mut ws.v);
        let assembly = Instant::now();
        ws.dfdx = std::mem::take(&mut ws.system);
        dynamics.linearize(&ws.x, &ws.v, t + h, &mut ws.rhs, &mut ws.dfdx, &mut ws.dfdv);
        let stiffness = step_system(dynamics, &ws.dfdx, 1.0);
        stiffness.multiply(&ws.v, &mut ws.product);
        // The damping change over the step, D Δv, which the end-of-step damping weighs by
        // 1 rather than θ: D = ∂f/∂v − αM + βK.
        ws.dfdv.multiply(dynamics.pattern(), &ws.dv, &mut ws.residual);
        stiffness.multiply(&ws.dv, &mut ws.direction);
        let springs = springs_of(settings, dynamics);
        contact_springs::add_forces(springs, &mut ws.spring_terms, &ws.x, &ws.v, &mut ws.rhs);
        contact_springs::add_product(springs, &mut ws.spring_terms, STIFFNESS, &ws.v, &mut ws.product);
        contact_springs::add_product(springs, &mut ws.spring_terms, DAMPING, &ws.dv, &mut ws.residual);
        contact_springs::add_product(springs, &mut ws.spring_terms, STIFFNESS, &ws.dv, &mut ws.direction);
        // −R = h((1−θ)F₀ + θF₁ + (1−θ) D Δv) − M Δv, with F₁ = f₁ − αMv₁ + βKv₁.
        for i in 0..n {
            let mass = dynamics.mass(i);
            let end_force = ws.rhs[i] - alpha * mass * ws.v[i] + beta * ws.product[i];
            let damping_change = ws.residual[i] - alpha * mass * ws.dv[i] + beta * ws.direction[i];
            ws.rhs[i] =
                h * ((1.0 - theta) * (ws.start_force[i] + damping_change) + theta * end_force) - mass * ws.dv[i];
        }
        build_system(settings, h, dynamics, ws);
        ws.stages.assembly += assembly.elapsed();
        report.iterations += solve(dynamics, settings, Start::Zero, settings.cg_tolerance, x, h * theta, ws);
        add_constraint_impulses(dynamics, constraints, ws);
        for i in 0..n {
            ws.dv[i] += ws.delta[i];
        }
        report.evaluations += 1;
        if dot(&ws.delta, &ws.delta) <= NEWTON_TOLERANCE * NEWTON_TOLERANCE * dot(&ws.dv, &ws.dv) {
            break;
        }
    }

    let dv = if newton { &ws.dv } else { &ws.delta };
    x.par_iter_mut().zip(v.par_iter_mut()).zip(dv.par_iter()).with_min_len(PARALLEL_MIN_LEN).for_each(
        |((x, v), dv)| {
            *x += h * (*v + theta * *dv);
            *v += *dv;
        },
    );
    report.stages = std::mem::take(&mut ws.stages);
    report
}

/// Most solves of a step that lag the contact springs' friction from the last one. On
/// `scenes/layer_slope.ron` (μ = 0.2, Coulomb's friction slides at 3.20 m/s²) the layer
/// slid at 2.3, 2.5 and 2.3 m/s² with one, two and three lags and pulling springs kept;
/// with pulling springs released, at 2.18, 3.01 and 3.17 m/s². Each lag costs a solve
/// from the last solution, all but the last one loose ([`LAG_LOOSENING`]).
const FRICTION_LAGS: u32 = 3;

/// How much looser than the settings' tolerance the solves are whose solution the contact
/// springs' friction is lagged from again: the next solve starts from it. On the first 60
/// frames of the fold_64 bench, solving those to the settings' tolerance took 85 % more
/// iterations than the friction lagged once from the start of the step (223 400 against
/// 120 800); 10 and 30 times looser, 38 % and 8 % more (100 times, 5 %), and the layer of
/// `scenes/layer_slope.ron` slid as before. At one step a frame (sphere_64_adaptive, three
/// starts, eleventh session) 30 is best too: 5 814 to 6 168 iterations over the run,
/// against 8 142 to 9 194 at 3, 6 425 to 7 573 at 10, 5 920 to 6 567 at 100 and 5 938 to
/// 6 724 at 300.
const LAG_LOOSENING: f32 = 30.0;

/// Lags the contact springs' friction from the step's solution `ws.delta`, releases the
/// springs that pull there and engages the armed ones whose pair it brings within its gap
/// ([`contact_springs::lag`]), then, unless that changes little,
/// solves again from the solution to `tolerance` (IPC's lagged iterations). The friction
/// the first solve met was lagged from the start of the step, whose pushes can be many
/// times those the springs give. Returns the solve's iterations, or `None` when it did
/// not solve.
fn lag_friction(
    dynamics: &mut impl LinearDynamics,
    settings: &ImplicitSettings,
    tolerance: f32,
    constraints: &[VelocityConstraint],
    x: &[Vec3],
    v: &[Vec3],
    h: f32,
    ws: &mut ImplicitWorkspace,
) -> Option<u32> {
    let theta = settings.theta;
    end_of_step(x, v, &ws.delta, h, theta, &mut ws.x, &mut ws.v);
    if !contact_springs::lag_changes(dynamics.contact_springs(), &ws.x, &ws.v) {
        return None;
    }
    add_springs(-1.0, dynamics.contact_springs(), dynamics.pattern(), settings, h, x, v, ws);
    contact_springs::lag(dynamics.contact_springs_mut(), &ws.x, &ws.v);
    add_springs(1.0, dynamics.contact_springs(), dynamics.pattern(), settings, h, x, v, ws);
    ws.spring_couplings.prepare(possible_springs(settings, dynamics), ws.spring_weights, dynamics.pattern().rows());
    let iterations = solve(dynamics, settings, Start::Given, tolerance, x, h * theta, ws);
    set_constraint_impulses(dynamics, constraints, ws);
    Some(iterations)
}

/// The end `(x_end, v_end)` of the θ-step from `(x, v)` that changes the velocities by
/// `dv`: `x + h (v + θ Δv)` and `v + Δv`.
fn end_of_step(x: &[Vec3], v: &[Vec3], dv: &[Vec3], h: f32, theta: f32, x_end: &mut [Vec3], v_end: &mut [Vec3]) {
    for i in 0..x.len() {
        x_end[i] = x[i] + h * (v[i] + theta * dv[i]);
        v_end[i] = v[i] + dv[i];
    }
}

/// Adds `sign` times the `springs`' part of the step's system (their diagonal blocks at
/// `ws.spring_weights`) and of its right-hand side at the start `(x, v)`: `F − β K v` to
/// the start's force and `h (F − β K v) − h² θ K v` to the right-hand side, for the
/// springs' force `F` and stiffness `K`.
fn add_springs(
    sign: f32,
    springs: &[ContactSpring],
    pattern: &BlockPattern,
    settings: &ImplicitSettings,
    h: f32,
    x: &[Vec3],
    v: &[Vec3],
    ws: &mut ImplicitWorkspace,
) {
    let weights = Weights { stiffness: sign * ws.spring_weights.stiffness, drag: sign * ws.spring_weights.drag };
    contact_springs::add_diagonal(springs, weights, pattern, &mut ws.system);
    if ws.prepared == Prepared::Ready {
        ws.prepared = Prepared::SpringsChanged;
    }
    let (force, stiffness, terms) = (&mut ws.residual, &mut ws.direction, &mut ws.spring_terms);
    force.fill(Vec3::ZERO);
    stiffness.fill(Vec3::ZERO);
    contact_springs::add_forces(springs, terms, x, v, force);
    contact_springs::add_product(springs, terms, STIFFNESS, v, stiffness);
    let (theta, beta) = (settings.theta, settings.rayleigh.beta);
    // The start force is kept for Newton iterations only (`implicit_step`).
    let newton = iterates(settings);
    for i in 0..x.len() {
        let start = force[i] + beta * stiffness[i];
        if newton {
            ws.start_force[i] += sign * start;
        }
        ws.rhs[i] += sign * (h * start + h * h * theta * stiffness[i]);
    }
}

/// How the preconditioner stands to the step's system ([`ImplicitWorkspace::prepared`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
enum Prepared {
    /// Prepared for another system, or never.
    #[default]
    Stale,
    /// Prepared for the system before its contact springs changed, which changed only its
    /// diagonal blocks at the springs' vertices: the multigrid's finest level then takes
    /// the change instead of being formed again ([`Multigrid::prepare`]).
    SpringsChanged,
    /// Prepared for the system as it is.
    Ready,
}

/// `A = (1 + hα) M − h D − (hβ + h²θ²) K` from the derivatives in `ws`, in the storage of
/// ∂f/∂x, with the diagonal blocks of the contact springs' stiffness (the rest is added in
/// each product: [`multiply_system`]).
fn build_system(settings: &ImplicitSettings, h: f32, dynamics: &impl LinearDynamics, ws: &mut ImplicitWorkspace) {
    let (theta, Rayleigh { alpha, beta }) = (settings.theta, settings.rayleigh);
    let pattern = dynamics.pattern();
    let k_weight = h * beta + h * h * theta * theta;
    ws.system = std::mem::take(&mut ws.dfdx);
    ws.dfdv.combine_into(-h, k_weight, pattern, &mut ws.system, |i| (1.0 + h * alpha) * dynamics.mass(i));
    ws.spring_weights = Weights { stiffness: k_weight, drag: h };
    let springs = springs_of(settings, dynamics);
    contact_springs::add_diagonal(springs, ws.spring_weights, pattern, &mut ws.system);
    ws.spring_couplings.prepare(possible_springs(settings, dynamics), ws.spring_weights, pattern.rows());
    ws.prepared = Prepared::Stale;
}

/// The contact springs' part of `∂f/∂x` and of `∂f/∂v`, as [`Weights`].
const STIFFNESS: Weights = Weights { stiffness: -1.0, drag: 0.0 };
const DAMPING: Weights = Weights { stiffness: 0.0, drag: -1.0 };

/// The contact springs the step solves with: none for block descent, which bounds each
/// vertex's motion instead and whose sweeps see only the matrix.
fn springs_of<'a>(settings: &ImplicitSettings, dynamics: &'a impl LinearDynamics) -> &'a [ContactSpring] {
    match settings.linear_solver {
        LinearSolver::BlockDescent(_) => &[],
        _ => dynamics.contact_springs(),
    }
}

/// The contact springs the step solves with, or `None` where the cloth does not collide
/// with itself: no step of it has springs, and nothing need be kept for them.
fn possible_springs<'a>(settings: &ImplicitSettings, dynamics: &'a impl LinearDynamics) -> Option<&'a [ContactSpring]> {
    let springs = springs_of(settings, dynamics);
    (dynamics.contact_surface().is_some() || !springs.is_empty()).then_some(springs)
}

/// `out = A y`: the matrix, and the contact springs' off-diagonal blocks weighted as
/// stiffness and damping are in `A` (`couplings`, with `pushes` as their scratch).
fn multiply_system(
    system: StepSystem<'_>,
    couplings: &SpringCouplings,
    pushes: &mut Vec<Vec3>,
    y: &[Vec3],
    out: &mut [Vec3],
) {
    system.multiply(y, out);
    couplings.add_product(y, pushes, out);
}

/// `ws.product = A δ`: the system, with its contact springs, times the last solution.
fn multiply_solution(dynamics: &impl LinearDynamics, ws: &mut ImplicitWorkspace) {
    let system = step_system(dynamics, &ws.system, -ws.spring_weights.stiffness);
    multiply_system(system, &ws.spring_couplings, &mut ws.spring_pushes, &ws.delta, &mut ws.product);
}

fn dot(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(a, b)| f64::from(a.dot(*b))).sum()
}

/// Sets `ws.constraint_impulses` to what each constraint had to supply in the last solve
/// ([`add_constraint_impulses`]).
fn set_constraint_impulses(
    dynamics: &impl LinearDynamics,
    constraints: &[VelocityConstraint],
    ws: &mut ImplicitWorkspace,
) {
    ws.constraint_impulses.clear();
    ws.constraint_impulses.resize(constraints.len(), Vec3::ZERO);
    add_constraint_impulses(dynamics, constraints, ws);
}

/// Adds what each constraint had to supply in the last solve, `A δ − rhs` at its
/// particle: the body's push that the filter stood in for.
fn add_constraint_impulses(
    dynamics: &impl LinearDynamics,
    constraints: &[VelocityConstraint],
    ws: &mut ImplicitWorkspace,
) {
    if constraints.is_empty() {
        return;
    }
    multiply_solution(dynamics, ws);
    for (impulse, c) in ws.constraint_impulses.iter_mut().zip(constraints) {
        let i = c.particle as usize;
        *impulse += ws.product[i] - ws.rhs[i];
    }
}

/// Sets `prescribed` to the part of each particle's Δv that the `constraints` fix: the
/// change to the constraint's velocity along its normal, or whole where it sticks. Left
/// empty, all zero, where the system has no bodies to touch and no constraints: 12 bytes
/// a particle of zeros on a cloth that touches nothing (the hangs). Sized wherever there
/// are bodies, touched or not, so that a warm step does not allocate it when contact
/// begins.
fn prescribe(
    dynamics: &impl LinearDynamics,
    constraints: &[VelocityConstraint],
    v: &[Vec3],
    prescribed: &mut Vec<Vec3>,
) {
    prescribed.clear();
    if constraints.is_empty() && dynamics.contact_bodies().is_empty() {
        return;
    }
    prescribed.resize(v.len(), Vec3::ZERO);
    for c in constraints {
        let i = c.particle as usize;
        if dynamics.is_free(i) {
            let current = v[i] + prescribed[i];
            prescribed[i] +=
                if c.stick { c.velocity - current } else { (c.velocity - current).dot(c.normal) * c.normal };
        }
    }
}

/// Where a linear solve starts.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Start {
    /// From the prescribed part alone (the first Newton iteration).
    Prescribed,
    /// From zero (a Newton correction).
    Zero,
    /// From `delta` as it is: this step's last solution, its prescribed part changed.
    Given,
    /// From `delta` as the warm start left it, `A delta` in the conjugate gradients'
    /// product buffer ([`WarmStart::start`]).
    Projected,
}

/// Whether the step's first solve starts from the last steps' solutions
/// ([`WarmStart`]): by multigrid-preconditioned conjugate gradients, whose iteration
/// costs some five products with the system, against the start's one a kept solution.
/// Over the first 60 frames of the bench scenes, iterations fell from 734 to 645 on
/// hang_256 and from 3 677 to 2 859 on sphere_64_adaptive. With block Jacobi an
/// iteration is one product: on fold_64 at 10 steps a frame iterations fell from 76 326
/// to 64 683 and its frames took 134 against 148 ms, but on sphere_64 they rose from
/// 42 711 to 44 488 and its frames took 92 against 81 ms, so block Jacobi starts from
/// rest. Block descent does too: what its few sweeps leave of a start in the stiff
/// modes is an explicit step.
fn starts_warm(settings: &ImplicitSettings) -> bool {
    settings.linear_solver == LinearSolver::Multigrid
}

/// Sets `ws.delta` to the start [`WarmStart`] makes of the last solutions for the system
/// as built, with the prescribed part; returns false where it has none. Its time counts
/// as the solve's.
fn projected_start(dynamics: &impl LinearDynamics, ws: &mut ImplicitWorkspace) -> bool {
    let started = Instant::now();
    let system = step_system(dynamics, &ws.system, -ws.spring_weights.stiffness);
    let ImplicitWorkspace {
        warm_start,
        filter,
        rhs,
        prescribed,
        product,
        residual,
        direction,
        delta,
        spring_couplings,
        spring_pushes,
        ..
    } = ws;
    let multiply = |x: &[Vec3], out: &mut [Vec3]| multiply_system(system, spring_couplings, spring_pushes, x, out);
    let products = [product.as_mut_slice(), residual, direction];
    let started_warm = warm_start.start(filter, rhs, prescribed, multiply, products, delta);
    ws.stages.solve += started.elapsed();
    started_warm
}

/// Whether contact bounds block descent's iterations: the settings' solver is block
/// descent with contact bounds, and the system collides with itself or with bodies.
fn bounded(settings: &ImplicitSettings, dynamics: &impl LinearDynamics) -> bool {
    descent_bounds(settings) && (dynamics.contact_surface().is_some() || !dynamics.contact_bodies().is_empty())
}

/// Whether the settings' solver is block descent with contact bounds.
fn descent_bounds(settings: &ImplicitSettings) -> bool {
    matches!(settings.linear_solver, LinearSolver::BlockDescent(d) if d.contact_bounds)
}

/// Whether the step takes Newton iterations after its first solve, which read the start
/// force and keep Δv apart from the last solution.
fn iterates(settings: &ImplicitSettings) -> bool {
    settings.newton_iterations > 1
}

/// Solves `A delta = rhs` (the system and the contact springs) within the filters with the
/// settings' linear solver, from `start`, to the relative residual `tolerance`. Block
/// descent keeps each particle within its contact bounds, the particles at
/// `ws.x + scale · delta` (`scale` = hθ [s]). Returns the iterations (or sweeps) taken,
/// and adds the time they took to `ws.stages` (the preconditioner's apart).
fn solve(
    dynamics: &impl LinearDynamics,
    settings: &ImplicitSettings,
    start: Start,
    tolerance: f32,
    x: &[Vec3],
    scale: f32,
    ws: &mut ImplicitWorkspace,
) -> u32 {
    let (started, preconditioner) = (Instant::now(), ws.stages.preconditioner);
    // A step's first solve starts from rest (Δv = 0: the inertial step) or, by multigrid,
    // from the best combination of the last steps' Δv ([`WarmStart`]), never from the last
    // Δv itself: what a few descent sweeps leave of that guess in the stiff modes is an
    // explicit step, and a hanging sheet diverged within ten frames. Conjugate gradients,
    // which cannot diverge from it, took more iterations from it too (the filtered last Δv
    // plus the prescribed part): 1 107 against 987 on hang_64 with multigrid, 47 640
    // against 42 711 in sphere_64's first 60 frames with block Jacobi. Within a step, a
    // solve for other body velocities starts from the last solution of the same system.
    match start {
        Start::Prescribed if ws.prescribed.is_empty() => ws.delta.fill(Vec3::ZERO),
        Start::Prescribed => ws.delta.copy_from_slice(&ws.prescribed),
        Start::Zero => ws.delta.fill(Vec3::ZERO),
        Start::Given | Start::Projected => {}
    }
    let (pattern, couplings, springs) =
        (dynamics.pattern(), dynamics.constant_couplings(), possible_springs(settings, dynamics));
    let known = match start {
        Start::Zero => StartProduct::Zero,
        Start::Prescribed if ws.prescribed.is_empty() => StartProduct::Zero,
        Start::Projected => StartProduct::Formed,
        Start::Prescribed | Start::Given => StartProduct::Unknown,
    };
    let iterations = match settings.linear_solver {
        LinearSolver::ConjugateGradient => {
            conjugate_gradient(pattern, couplings, None, springs, settings, tolerance, x, known, ws)
        }
        LinearSolver::Multigrid => {
            let hierarchy = Some(dynamics.hierarchy());
            let iterations =
                conjugate_gradient(pattern, couplings, hierarchy, springs, settings, tolerance, x, known, ws);
            // A looser solve's iterations say nothing of the levels' strength.
            if tolerance == settings.cg_tolerance {
                ws.multigrid.record(iterations);
            }
            iterations
        }
        LinearSolver::BlockDescent(descent) => {
            let ImplicitWorkspace { x: base, anchor, motion_bounds, .. } = ws;
            let (surface, others, bodies, layers) = (
                dynamics.contact_surface(),
                dynamics.contact_others(),
                dynamics.contact_bodies(),
                dynamics.layer_contact(),
            );
            let mut bound = bounded(settings, dynamics).then_some(
                move |x: &[Vec3], wanted: f32, mobility: &[Mobility], out: &mut [Bound]| {
                    match surface {
                        Some(surface) => {
                            let resting = layers.map(|layers| Resting { mobility, separation: layers.separation });
                            motion_bounds.compute(surface, others, resting, x, wanted, out);
                        }
                        None => out.fill(Bound::FREE),
                    }
                    body_bounds::limit(bodies, x, out);
                },
            );
            let motion = bound.as_mut().map(|bound| BoundedMotion { base, scale, anchor, bound });
            let held = motion.is_some();
            let sweeps = descend(
                step_system(dynamics, &ws.system, -ws.spring_weights.stiffness),
                dynamics.colouring(),
                &ws.rhs,
                &ws.filter,
                &descent,
                tolerance,
                motion,
                &mut ws.delta,
                &mut ws.descent,
            );
            if held {
                push_friction(dynamics, x, scale, ws);
            }
            sweeps
        }
    };
    ws.stages.solve += started.elapsed().saturating_sub(ws.stages.preconditioner - preconditioner);
    iterations
}

/// The friction of the bodies' pushes within block descent's sweeps. A body's plane stops
/// a landing particle within the sweeps, so the contact stage after the step meets no
/// impact, and the friction the impact would have carried never acts: on Zheng's slope a
/// cloth with μ above tan 30° slid on after landing (0.58 m in a second at 10 steps a
/// frame) where conjugate gradients, which leave the impact to the contact stage, stick.
/// The push is in the solve's residual: where a particle free of constraints ends resting
/// on a convex body ([`body_bounds::resting_on`]), `J = (A Δv − b)_i` along the body's
/// normal is the impulse the body gave it, and Coulomb's friction takes up to `μ J_n / m`
/// off its velocity along the surface, relative to the body (the step's end velocity, its
/// move over `h`: θ is 1). Particles the contact constraints hold are left to them. A
/// particle resting on a still layer of its cloth, whose plane held it within the sweeps
/// ([`MotionBounds::resting_on`]), takes the layers' friction from its push the same way,
/// relative to the layer under it.
fn push_friction(dynamics: &impl LinearDynamics, x: &[Vec3], h: f32, ws: &mut ImplicitWorkspace) {
    let (bodies, others) = (dynamics.contact_bodies(), dynamics.contact_others());
    let layers = dynamics.layer_contact().zip(dynamics.contact_surface()).filter(|_| ws.motion_bounds.supported());
    if bodies.is_empty() && layers.is_none() {
        return;
    }
    multiply_solution(dynamics, ws);
    let (end, rhs, filter, motion_bounds) = (&ws.anchor, &ws.rhs, &ws.filter, &ws.motion_bounds);
    ws.product.par_iter_mut().enumerate().with_min_len(PARALLEL_MIN_LEN).for_each(|(i, change)| {
        let push = *change - rhs[i];
        *change = Vec3::ZERO;
        if !filter.is_free(i) {
            return;
        }
        let on_layer = || {
            layers
                .and_then(|(layers, surface)| motion_bounds.resting_on(surface.triangles, others, layers, i, end, x, h))
        };
        let Some((normal, velocity, friction)) = body_bounds::resting_on(bodies, end[i]).or_else(on_layer) else {
            return;
        };
        let pressed = push.dot(normal);
        let relative = (end[i] - x[i]) / h - velocity;
        let slide = relative - normal.dot(relative) * normal;
        let speed = slide.length();
        if pressed > 0.0 && speed > 0.0 {
            *change = -(friction * pressed / (dynamics.mass(i) * speed)).min(1.0) * slide;
        }
    });
    let ImplicitWorkspace { delta, product, .. } = ws;
    add_rows(delta, |i| product[i]);
}

/// What the conjugate gradients know of `A δ` where they start.
#[derive(Debug, Clone, Copy, PartialEq)]
enum StartProduct {
    /// `δ` is zero, and so is its product.
    Zero,
    /// The product buffer holds it ([`Start::Projected`]).
    Formed,
    /// It is to be multiplied.
    Unknown,
}

/// Particles per task in the conjugate gradients' vector kernels. Fixed, so that the
/// partial sums of every dot product, and hence the iterates, are the same on any number
/// of threads.
const VECTOR_CHUNK: usize = 2048;

/// The per-chunk partial sums added in chunk order.
fn total(partials: &[f64]) -> f64 {
    partials.iter().sum()
}

/// Sets every `out[i]` by `update(i, &mut out[i], input[i])`, in parallel over chunks of
/// [`VECTOR_CHUNK`], and returns the sum of what the updates return, added in index order
/// within a chunk and chunk by chunk: one pass for a CG vector update and the dot product
/// it needs.
fn fused(
    out: &mut [Vec3],
    input: &[Vec3],
    partials: &mut Vec<f64>,
    update: impl Fn(usize, &mut Vec3, Vec3) -> f64 + Sync,
) -> f64 {
    const C: usize = VECTOR_CHUNK;
    out.par_chunks_mut(C)
        .zip(input.par_chunks(C))
        .enumerate()
        .map(|(c, (out, input))| {
            out.iter_mut().zip(input).enumerate().fold(0.0, |sum, (k, (o, x))| sum + update(c * C + k, o, *x))
        })
        .collect_into_vec(partials);
    total(partials)
}

/// Solves `A delta = rhs` within the constraint filters to the relative residual
/// `tolerance` by preconditioned conjugate gradients (Baraff & Witkin's modified PCG), `A`
/// the system matrix with the `springs`' off-diagonal blocks ([`multiply_system`]):
/// `delta` starts as given and only moves within the filters. The preconditioner is a
/// multigrid V-cycle over `hierarchy` if given, else block Jacobi; the system's constant
/// `couplings` outside its pattern, if any, enter both and every product. A solve that
/// starts where `known` gives `A delta` takes its first residual without a product. Returns the
/// iterations taken. Stops early on a direction of non-positive curvature, which a
/// semi-definite assembly should not give. The vector work runs in parallel over fixed chunks of
/// particles, each pass computing the dot products it needs on the way, summed in chunk
/// order. `springs` is `None` where the cloth does not collide with itself, so that the
/// multigrid keeps nothing for springs that will never come.
fn conjugate_gradient(
    pattern: &BlockPattern,
    couplings: Option<&ConstantCouplings>,
    hierarchy: Option<&Hierarchy>,
    springs: Option<&[ContactSpring]>,
    settings: &ImplicitSettings,
    tolerance: f32,
    x: &[Vec3],
    known: StartProduct,
    ws: &mut ImplicitWorkspace,
) -> u32 {
    const C: usize = VECTOR_CHUNK;
    let ImplicitWorkspace {
        system,
        rhs,
        delta,
        residual,
        direction,
        product,
        preconditioner,
        partials,
        filter,
        multigrid,
        prepared,
        spring_weights,
        spring_couplings,
        spring_pushes,
        stages,
        ..
    } = ws;
    let weights = *spring_weights;
    let system = StepSystem::with_couplings(pattern, system, couplings, -weights.stiffness);
    // The springs that may come, prepared: none where the cloth does not collide with itself.
    let spring_couplings = &*spring_couplings;
    let possible = springs.map(|_| spring_couplings);
    if *prepared != Prepared::Ready {
        let preparing = Instant::now();
        let springs_changed = *prepared == Prepared::SpringsChanged;
        match hierarchy {
            Some(hierarchy) => multigrid.prepare(hierarchy, system, filter, x, possible, springs_changed),
            None => (0..filter.len())
                .into_par_iter()
                .with_min_len(PARALLEL_MIN_LEN)
                .map(|i| {
                    let block = system.diagonal(i);
                    if block.determinant().abs() > 0.0 { block.inverse() } else { Mat3::IDENTITY }
                })
                .collect_into_vec(preconditioner),
        }
        *prepared = Prepared::Ready;
        stages.preconditioner += preparing.elapsed();
    }
    let (filter, rhs) = (&*filter, &*rhs);
    // r = S (b − A δ), z = M⁻¹ r, d = z: from rest, r = S b, with no product of the
    // matrix with zero (0.76 ms a frame of hang_256's, whose steps start from rest).
    let mut rr = match known {
        StartProduct::Zero => fused(residual, rhs, partials, |i, r, b| {
            *r = filter.apply(i, b);
            f64::from(r.length_squared())
        }),
        StartProduct::Formed | StartProduct::Unknown => {
            if known == StartProduct::Unknown {
                multiply_system(system, spring_couplings, spring_pushes, delta, product);
            }
            fused(residual, product, partials, |i, r, q| {
                *r = filter.apply(i, rhs[i] - q);
                f64::from(r.length_squared())
            })
        }
    };
    rhs.par_chunks(C)
        .enumerate()
        .map(|(c, b)| (0..b.len()).map(|k| f64::from(filter.apply(c * C + k, b[k]).length_squared())).sum())
        .collect_into_vec(partials);
    let target = f64::from(tolerance).powi(2) * total(partials);
    // A solve that starts within its tolerance (often one of a step's lagged solves)
    // takes no preconditioning: a V-cycle it would not use.
    if rr <= target {
        return 0;
    }
    // z = M⁻¹ r, returning r·z.
    let precondition = |multigrid: &mut Multigrid, r: &[Vec3], z: &mut [Vec3], partials: &mut Vec<f64>| {
        if let Some(hierarchy) = hierarchy {
            multigrid.apply(hierarchy, system, filter, r, z, possible);
        }
        let jacobi = hierarchy.is_none().then_some(&*preconditioner);
        fused(z, r, partials, |i, z, r| {
            if let Some(jacobi) = jacobi {
                *z = filter.apply(i, Vec3::from(times(&jacobi[i], Vec3A::from(r))));
            }
            f64::from(r.dot(*z))
        })
    };
    let mut rz = precondition(multigrid, residual, product, partials);
    direction.copy_from_slice(product);
    for iteration in 1..=settings.cg_max_iterations {
        // q = S A d, and d·q: the constant couplings' rows, if any, added in the pass that
        // filters.
        multiply_system(StepSystem { far: None, ..system }, spring_couplings, spring_pushes, direction, product);
        let along = &*direction;
        let curvature = fused(product, along, partials, |i, q, d| {
            *q = filter.apply(i, system.far.map_or(*q, |far| *q + far.row_product(i, along)));
            f64::from(d.dot(*q))
        });
        if curvature <= 0.0 {
            return iteration - 1;
        }
        // δ += α d, r −= α q, with α = r·z / d·q; then z = M⁻¹ r.
        let step = (rz / curvature) as f32;
        delta
            .par_chunks_mut(C)
            .zip(residual.par_chunks_mut(C))
            .zip(direction.par_chunks(C).zip(product.par_chunks(C)))
            .map(|((x, r), (d, q))| {
                (0..x.len()).fold(0.0, |sum, k| {
                    x[k] += step * d[k];
                    r[k] -= step * q[k];
                    sum + f64::from(r[k].length_squared())
                })
            })
            .collect_into_vec(partials);
        rr = total(partials);
        // The solve ends with the update that brings it within its tolerance: the
        // preconditioning and the direction that would follow serve no update (a V-cycle
        // a solve, an eighth of hang_64's).
        if rr <= target || iteration == settings.cg_max_iterations {
            return iteration;
        }
        // z = M⁻¹ r, into the buffer of q, which is spent.
        let next = precondition(multigrid, residual, product, partials);
        let ratio = (next / rz) as f32;
        rz = next;
        direction.par_iter_mut().zip(product.par_iter()).with_min_len(PARALLEL_MIN_LEN).for_each(|(d, z)| {
            *d = *z + ratio * *d;
        });
    }
    settings.cg_max_iterations
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bricis_critical_damping_at_0_3_and_0_9_gives_his_coefficients() {
        let r = Rayleigh::from_frequencies(0.3, 0.9, 1.0);
        assert!((r.alpha - 0.45).abs() < 1e-6, "α = {}", r.alpha);
        assert!((r.beta - 5.0 / 3.0).abs() < 1e-6, "β = {}", r.beta);
        // Both modes critically damped: α + β ω² = 2 ω.
        for omega in [0.3f32, 0.9] {
            assert!((r.alpha + r.beta * omega * omega - 2.0 * omega).abs() < 1e-6);
        }
    }
}
