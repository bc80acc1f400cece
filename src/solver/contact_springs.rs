//! Cloth–cloth contact inside the implicit solve: each pair of primitives closer than its
//! separation at the start of a step pushes its sides apart with a spring along the pair's
//! normal, whose stiffness enters the step's matrix and couples the pair's four vertices.
//!
//! Friction enters the same solve, as a damper across the normal whose coefficient is
//! lagged (IPC's lagged friction): Coulomb's force where the pair slides, a stiff damper
//! that holds it where it barely moves. It is lagged first from the start of the step,
//! then again from the step's own solution, solving again each time ([`lag`]); there a
//! spring that pulls is released, as contact does not pull, and an armed one (made for a
//! pair a little beyond its separation) engages where the solution brings its pair
//! within it.
//!
//! The contact stage after the step ([`crate::collision::self_contact`]) stops a vertex
//! that the solve carried into another layer, but the solve moved it there together with
//! its neighbours, and stopping that vertex alone stores the work it undid as strain,
//! which the next step releases: a stiff heap gained energy step after step. A spring in
//! the solve stops the pair while the membrane is solved for, and passes each layer's
//! weight to the layer below within the step (a velocity held along the normal did not,
//! and propped piles up). The contact stage stays as the backstop.

use glam::{Mat3, Vec3};
use rayon::prelude::*;

use super::PARALLEL_MIN_LEN;
use super::elements::spring::outer;
use super::elements::{BlockPattern, SymmetricBlockMatrix};
use super::gather::reserve_floored;

/// A pair of primitives as four vertices and weights: the pair's relative position (or
/// velocity) is `Σ weights[k] x[vertices[k]]`, pointing from the second side to the first.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stencil {
    /// A vertex and a triangle's three, or two edges' two each.
    pub vertices: [u32; 4],
    /// Weights of the vertices in the relative position: 1 and minus the barycentric
    /// weights of the closest point for a vertex and a triangle.
    pub weights: [f32; 4],
}

impl Stencil {
    /// Vertex `p` against the point of triangle `tri` at barycentric weights `w`.
    pub fn point_triangle(p: u32, tri: [u32; 3], w: [f32; 3]) -> Stencil {
        Stencil { vertices: [p, tri[0], tri[1], tri[2]], weights: [1.0, -w[0], -w[1], -w[2]] }
    }

    /// The point at `s` along edge `e` against the point at `u` along edge `f`.
    pub fn edge_edge(e: [u32; 2], f: [u32; 2], s: f32, u: f32) -> Stencil {
        Stencil { vertices: [e[0], e[1], f[0], f[1]], weights: [1.0 - s, s, u - 1.0, -u] }
    }

    /// Its slots `(k, vertex, weight)`, but those weighed zero (another cloth's,
    /// [`Outside`]).
    pub(crate) fn weighted(&self) -> impl Iterator<Item = (usize, usize, f32)> + '_ {
        (0..4).filter(|&k| self.weights[k] != 0.0).map(|k| (k, self.vertices[k] as usize, self.weights[k]))
    }

    /// The pair's relative position (or velocity) `Σ w x` at `x`.
    pub fn relative(&self, x: &[Vec3]) -> Vec3 {
        (0..4).map(|k| self.weights[k] * x[self.vertices[k] as usize]).sum()
    }

    /// The pair's inverse effective mass along any direction, `Σ w_k² / m_k`, for the
    /// vertices' inverse masses `inv_mass` [1/kg].
    pub fn inverse_mass(&self, inv_mass: &[f32]) -> f32 {
        (0..4).map(|k| self.weights[k] * self.weights[k] * inv_mass[self.vertices[k] as usize]).sum()
    }
}

/// The longest step, in seconds, whose length a contact spring's stiffness is made for: a
/// spring for a longer step is as stiff as for this one ([`spring_step`]).
pub const SPRING_STEP: f32 = 0.002;

/// The step length a contact spring for a step of length `h` is made for: `h`, or
/// [`SPRING_STEP`] if `h` is longer. A spring made to restore a free pair's gap within its
/// step (`k h² / m` fixed) is `(h / SPRING_STEP)²` times softer at a longer step, and
/// soft against the loads of a heap at a frame-sized one: a fold of sphere_64_adaptive
/// resting at one step a frame (1/60 s: springs a hundred times softer than at its
/// frames of ten steps) carried its load 1.5 mm into its 2 mm gap, and the contact stage
/// pushed the pairs' vertices back out alone against the membrane the solve had balanced,
/// stretching their edges by 6 to 7 % at every step.
///
/// 2 ms leaves the springs of frames of ten steps at 60 frames a second (sphere_64,
/// fold_64) as they were, to the bit. Over five starts of sphere_64_adaptive the sheet at
/// rest strains 0.024 in its median frame, against 0.032 with springs made for each step
/// and 0.035 with them as stiff as for 4 ms, for 18 to 29 % more iterations (the
/// multigrid's finest level holds only the springs' diagonal blocks; without those it
/// took 31 to 49 % more; its coarse levels hold them whole since the twelfth session,
/// [`super::coarse_springs`], which left these iterations as they were).
pub fn spring_step(h: f32) -> f32 {
    h.min(SPRING_STEP)
}

/// Relative tangential speed below which a contact spring's friction holds like a stiff
/// damper rather than Coulomb's constant force [m/s].
const STATIC_SPEED: f32 = 1e-3;

/// A pair of primitives held apart in a cloth's implicit step: its distance along
/// `normal` is pushed towards `gap`. A pair with another cloth is a spring of the cloth
/// whose side is free, holding it against the other side where that stands held
/// ([`Outside`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSpring {
    /// The pair, in the cloth's particle numbers; the other cloth's vertices of a pair with
    /// another cloth are weighed zero (their part is `outside`).
    pub stencil: Stencil,
    /// Unit normal from the second side to the first at the start of the step.
    pub normal: Vec3,
    /// The separation the pair keeps [m].
    pub gap: f32,
    /// Stiffness [N/m].
    pub stiffness: f32,
    /// Coefficient of friction between the pair's sides.
    pub friction: f32,
    /// Friction, as a damping coefficient of the pair's relative velocity across the
    /// normal [N·s/m]: see [`ContactSpring::lag_friction`].
    pub drag: f32,
    /// The stiffness a spring made for a pair beyond its gap takes where a solve brings
    /// the pair within it ([`lag`]) [N/m]; zero for one made within its gap, whose
    /// release is final.
    pub armed: f32,
    /// Another cloth's part of the pair; zero for a pair within the cloth.
    pub outside: Outside,
}

/// Another cloth's part of a pair's relative position and velocity, `Σ w x` and `Σ w v`
/// over its vertices, which stand still while this cloth's step is solved. Only a side
/// that the contact stage holds (pinned, or resting on a body: its impulse inverse mass
/// zero) is made so: its reaction goes into its pins or its body. A spring against a free
/// cloth would have no reaction on it, and those pairs are left to the contact stage,
/// whose impulses act on both sides (`systems::contacts::split_spring`). The side is
/// placed before each step of this cloth where it will be at the step's end
/// ([`ClothEnds::place`]): where its cloth's step ended if it has stepped, else where
/// its velocity takes it (a pinned side stays, one resting on a moving body goes with it).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Outside {
    /// Part of the relative position at the end of the step [m].
    pub position: Vec3,
    /// Part of the relative velocity [m/s].
    pub velocity: Vec3,
}

/// A spring's side in another cloth, by which [`Outside`] is placed: that cloth, and the
/// spring's vertices there (in its particle numbers) with their weights.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Across {
    /// The spring, in its cloth's list.
    pub spring: u32,
    /// The other cloth, by its number among the cloths that collide with one another.
    pub cloth: u32,
    /// Its vertices of the pair.
    pub vertices: [u32; 3],
    /// Their weights in the pair's relative position (zero where a slot is unused).
    pub weights: [f32; 3],
}

impl Across {
    /// The spring's other side with the other cloth's particles at `position`, moving at
    /// `velocity`: where its step will end, and how fast.
    pub fn outside(&self, position: &[Vec3], velocity: &[Vec3]) -> Outside {
        let sum = |x: &[Vec3]| (0..3).map(|k| self.weights[k] * x[self.vertices[k] as usize]).sum::<Vec3>();
        Outside { position: sum(position), velocity: sum(velocity) }
    }
}

/// Where the cloths that collide with one another stand in a step's turn of them: one not
/// yet stepped where its velocity takes it within the step, one that has stepped where
/// its step ended, with their velocities; by their numbers among those cloths. Places the
/// other side of each spring with another cloth before its cloth steps
/// ([`ClothEnds::place`]). Kept from step to step, so that a warm step allocates nothing.
#[derive(Debug, Clone, Default)]
pub struct ClothEnds {
    position: Vec<Vec<Vec3>>,
    velocity: Vec<Vec<Vec3>>,
}

impl ClothEnds {
    /// Cloth `cloth`, its particles at `x` moving at `v`, before a step of `h` [s]: where
    /// they will be at its end if their velocities hold.
    pub fn expect(&mut self, cloth: usize, x: &[Vec3], v: &[Vec3], h: f32) {
        self.ended(cloth, x, v);
        for (end, v) in self.position[cloth].iter_mut().zip(v) {
            *end += h * *v;
        }
    }

    /// Cloth `cloth` after its step: its particles at `x`, moving at `v`.
    pub fn ended(&mut self, cloth: usize, x: &[Vec3], v: &[Vec3]) {
        if self.position.len() <= cloth {
            self.position.resize_with(cloth + 1, Vec::new);
            self.velocity.resize_with(cloth + 1, Vec::new);
        }
        self.position[cloth].clear();
        self.position[cloth].extend_from_slice(x);
        self.velocity[cloth].clear();
        self.velocity[cloth].extend_from_slice(v);
    }

    /// Places the other side of `springs` by their `across`.
    pub fn place(&self, across: &[Across], springs: &mut [ContactSpring]) {
        for a in across {
            let cloth = a.cloth as usize;
            springs[a.spring as usize].outside = a.outside(&self.position[cloth], &self.velocity[cloth]);
        }
    }
}

impl ContactSpring {
    /// The pair's relative position at `x` (the cloth's particles), its other cloth's part
    /// included.
    fn relative_position(&self, x: &[Vec3]) -> Vec3 {
        self.stencil.relative(x) + self.outside.position
    }

    /// The pair's relative velocity at `v`, its other cloth's part included.
    fn relative_velocity(&self, v: &[Vec3]) -> Vec3 {
        self.stencil.relative(v) + self.outside.velocity
    }

    /// The spring's push along its normal at `x` [N]: `k (gap − d)`, negative where it
    /// pulls (the pair has come further apart than its gap).
    pub fn push(&self, x: &[Vec3]) -> f32 {
        self.stiffness * (self.gap - self.relative_position(x).dot(self.normal))
    }

    /// The force on the pair's first side at `(x, v)`: the spring's push, `k (gap − d) n`,
    /// and friction, `−c (I − n nᵀ) v_rel`. Vertex `k` takes `w_k` times it.
    fn force(&self, x: &[Vec3], v: &[Vec3]) -> Vec3 {
        self.push(x) * self.normal - self.drag * self.slip(v)
    }

    /// The pair's relative velocity across the normal at `v` [m/s].
    fn slip(&self, v: &[Vec3]) -> Vec3 {
        let relative = self.relative_velocity(v);
        relative - relative.dot(self.normal) * self.normal
    }

    /// The pair's speed across the normal at `v`, no less than [`STATIC_SPEED`] [m/s].
    fn sliding(&self, v: &[Vec3]) -> f32 {
        self.slip(v).length().max(STATIC_SPEED)
    }

    /// Makes a spring made for a step of length `from` serve one of length `to` [s]: its
    /// stiffness scaled as if made for the new step (as `k h²` over the pair's mass, `h`
    /// no longer than [`SPRING_STEP`]: [`spring_step`]). Its friction stays: it was
    /// lagged from the force the pair carried, which does not depend on the step (a layer
    /// at rest carries its weight), while the push of the rescaled spring at the same
    /// distance would give a quarter of it when the step doubles. Without this, a spring
    /// made at the end of a frame of ten steps served the first of a frame of one as if
    /// made for a step ten times shorter, and one made there the next frame's ten steps as
    /// if made for one ten times longer.
    pub fn restep(&mut self, from: f32, to: f32) {
        let ratio = spring_step(from) / spring_step(to);
        let scale = ratio * ratio;
        self.stiffness *= scale;
        self.armed *= scale;
    }

    /// Sets the friction to Coulomb's for the push `push` [N] and the pair's velocities
    /// `v`, lagged (as in IPC): a damper that brakes the pair's tangential speed at `v`
    /// with `μ push`, or, below [`STATIC_SPEED`], holds it like a stiff damper.
    pub fn lag_friction(&mut self, push: f32, v: &[Vec3]) {
        self.drag = self.friction * push / self.sliding(v);
    }

    /// Whether the spring is armed, not engaged, and its pair is within its gap at `x`.
    fn engages(&self, x: &[Vec3]) -> bool {
        self.stiffness == 0.0 && self.armed > 0.0 && self.relative_position(x).dot(self.normal) < self.gap
    }

    /// The spring lagged from the end `(x, v)` of a step solved with it: its friction
    /// from the push it gave there, the normal force its friction should have resisted
    /// with; released (no stiffness, no friction) where it pulled, as contact does not;
    /// engaged (its armed stiffness) where it was armed and its pair came within its gap.
    fn lagged(&self, x: &[Vec3], v: &[Vec3]) -> ContactSpring {
        let mut lagged = *self;
        if self.engages(x) {
            lagged.stiffness = self.armed;
        }
        let push = lagged.push(x);
        if push <= 0.0 {
            lagged.stiffness = 0.0;
            lagged.drag = 0.0;
        } else {
            lagged.lag_friction(push, v);
        }
        lagged
    }
}

/// Change in the springs' total friction, as a fraction of it, below which lagging them
/// again is not worth another solve.
const LAG_TOLERANCE: f32 = 0.05;

/// Whether lagging `springs` from the end `(x, v)` of a step solved with them
/// ([`ContactSpring::lagged`]) would release one or change their total friction force at
/// `v` by more than [`LAG_TOLERANCE`] of it.
///
/// The friction first lagged from the start of the step can be far from what the springs
/// give: a pair that has just come closer than its gap will be pushed apart by a fraction
/// of its push at the start, and a layer sliding over another keeps landing on it (on
/// `scenes/layer_slope.ron` the pushes at the start summed two to nine times the layer's
/// weight, and held it fast where it should slide). A spring that pulls at the end holds
/// the pair together and the pushes of its neighbours grow by as much, and with them their
/// friction.
pub fn lag_changes(springs: &[ContactSpring], x: &[Vec3], v: &[Vec3]) -> bool {
    if springs.iter().any(|s| s.engages(x)) {
        return true;
    }
    let (mut change, mut total) = (0.0, 0.0);
    for s in springs.iter().filter(|s| s.stiffness > 0.0) {
        let lagged = s.lagged(x, v);
        if lagged.stiffness == 0.0 {
            return true;
        }
        let sliding = s.sliding(v);
        change += (lagged.drag - s.drag).abs() * sliding;
        total += lagged.drag * sliding;
    }
    change > LAG_TOLERANCE * total
}

/// Lags each of `springs` from the end `(x, v)` of a step solved with them
/// ([`ContactSpring::lagged`]).
pub fn lag(springs: &mut [ContactSpring], x: &[Vec3], v: &[Vec3]) {
    for s in springs {
        *s = s.lagged(x, v);
    }
}

/// Whether any of the springs has friction, or is armed: a solve with them is lagged
/// from ([`lag`]).
pub fn lagged_from_solves(springs: &[ContactSpring]) -> bool {
    springs.iter().any(|s| s.friction > 0.0 || s.armed > 0.0)
}

/// The springs that act: all but those with neither stiffness nor friction (armed, not
/// engaged, or released). Armed springs are most of a heap's (fold_64: its products took
/// 23 % longer over all of them).
fn acting(springs: &[ContactSpring]) -> impl Iterator<Item = &ContactSpring> {
    springs.iter().filter(|s| s.acts())
}

/// What each spring adds to each of its four vertices in a product or a force
/// ([`add_terms`]): a buffer kept from product to product, so that a warm step does not
/// allocate it.
#[derive(Debug, Clone, Default)]
pub struct SpringTerms(Vec<[Vec3; 4]>);

/// Adds `term(spring)[k]` to `out` at each acting spring's weighted vertex `k`: the terms
/// formed in parallel, then added spring by spring in order, so that each vertex sums
/// them in the order the serial loop did, the same bits on any number of threads. Formed
/// serially, the springs' products held a heap of two cloths (`untangle_layers`, some
/// 2 700 springs on 1 250 particles) on one thread for a fifth of its run while the
/// other waited.
fn add_terms(
    springs: &[ContactSpring],
    terms: &mut SpringTerms,
    out: &mut [Vec3],
    term: impl Fn(&ContactSpring) -> [Vec3; 4] + Sync,
) {
    let terms = &mut terms.0;
    // Grown as the springs' list is ([`reserve_floored`]): contact beginning in a warm
    // frame takes the floor at once, not four doublings.
    reserve_floored(terms, springs.len().saturating_sub(terms.len()));
    terms.resize(springs.len(), [Vec3::ZERO; 4]);
    springs.par_iter().zip(terms.par_iter_mut()).with_min_len(PARALLEL_MIN_LEN).for_each(|(s, t)| {
        if s.acts() {
            *t = term(s);
        }
    });
    for (s, t) in springs.iter().zip(terms.iter()).filter(|(s, _)| s.acts()) {
        for (k, vertex, _) in s.stencil.weighted() {
            out[vertex] += t[k];
        }
    }
}

/// `f(weight)` at each of the stencil's weighted slots, zero at the others.
fn per_slot(stencil: &Stencil, f: impl Fn(f32) -> Vec3) -> [Vec3; 4] {
    let mut slots = [Vec3::ZERO; 4];
    for (k, _, weight) in stencil.weighted() {
        slots[k] = f(weight);
    }
    slots
}

/// Adds the springs' forces at `(x, v)` to `force`.
pub fn add_forces(springs: &[ContactSpring], terms: &mut SpringTerms, x: &[Vec3], v: &[Vec3], force: &mut [Vec3]) {
    add_terms(springs, terms, force, |s| {
        let push = s.force(x, v);
        per_slot(&s.stencil, |weight| weight * push)
    });
}

/// How much of the springs' stiffness `K = Σ k (w wᵀ) ⊗ (n nᵀ)` (`−∂f/∂x`) and of their
/// friction `C = Σ c (w wᵀ) ⊗ (I − n nᵀ)` (`−∂f/∂v`) a product or matrix takes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Weights {
    /// Of the stiffness.
    pub stiffness: f32,
    /// Of the friction.
    pub drag: f32,
}

impl ContactSpring {
    /// Whether the spring has stiffness or friction ([`acting`]).
    pub fn acts(&self) -> bool {
        self.stiffness != 0.0 || self.drag != 0.0
    }

    /// The pair's block `(w_a w_b)`-free part: `a k n nᵀ + b c (I − n nᵀ)`.
    pub(crate) fn block(&self, weights: Weights) -> Mat3 {
        let normal = outer(self.normal, self.normal);
        (weights.stiffness * self.stiffness) * normal + (weights.drag * self.drag) * (Mat3::IDENTITY - normal)
    }
}

/// `out += (a K + b C) y` for `weights` `(a, b)`, pair by pair in order ([`add_terms`]):
/// a product of the assembly. The solve's products take the off-diagonal blocks alone, the
/// diagonal ones being in its matrix ([`super::spring_couplings::SpringCouplings`]).
pub fn add_product(springs: &[ContactSpring], terms: &mut SpringTerms, weights: Weights, y: &[Vec3], out: &mut [Vec3]) {
    add_terms(springs, terms, out, |s| {
        // Every vertex takes the same product of the whole pair.
        let whole = s.block(weights) * s.stencil.relative(y);
        per_slot(&s.stencil, |weight| weight * whole)
    });
}

/// Adds the diagonal blocks of `a K + b C`, `w_k² (a k n nᵀ + b c (I − n nᵀ))`, to `matrix`.
pub fn add_diagonal(
    springs: &[ContactSpring],
    weights: Weights,
    pattern: &BlockPattern,
    matrix: &mut SymmetricBlockMatrix,
) {
    for_diagonal(springs, weights, |i, block| *matrix.diagonal_mut(pattern, i) += block);
}

/// Calls `visit(vertex, block)` with each diagonal block of `a K + b C` (as
/// [`add_diagonal`] adds them), spring by spring in order.
pub fn for_diagonal(springs: &[ContactSpring], weights: Weights, mut visit: impl FnMut(usize, Mat3)) {
    for s in acting(springs) {
        let block = s.block(weights);
        for (_, vertex, weight) in s.stencil.weighted() {
            visit(vertex, weight * weight * block);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vertex 1 mm above the middle of a triangle's edge, with a 2 mm gap.
    fn spring() -> (ContactSpring, Vec<Vec3>) {
        let x = vec![Vec3::new(0.5, 0.001, 0.2), Vec3::ZERO, Vec3::X, Vec3::Z];
        let s = ContactSpring {
            stencil: Stencil { vertices: [0, 1, 2, 3], weights: [1.0, -0.3, -0.5, -0.2] },
            normal: Vec3::Y,
            gap: 0.002,
            stiffness: 50.0,
            friction: 0.5,
            drag: 0.3,
            armed: 0.0,
            outside: Outside::default(),
        };
        (s, x)
    }

    #[test]
    fn the_forces_push_the_sides_apart_and_rub_against_sliding_with_no_net_force() {
        let (s, x) = spring();
        // The vertex slides at 0.5 m/s along x over the resting triangle, and approaches it.
        let v = vec![Vec3::new(0.5, -0.2, 0.0), Vec3::ZERO, Vec3::ZERO, Vec3::ZERO];
        let mut force = vec![Vec3::ZERO; 4];
        add_forces(&[s], &mut SpringTerms::default(), &x, &v, &mut force);
        // k (δ − d) = 50 · 0.001 = 0.05 N on the vertex, up; friction −c v_t = −0.15 N along
        // x; no damping along the normal.
        assert!((force[0] - Vec3::new(-0.15, 0.05, 0.0)).length() < 1e-6, "{}", force[0]);
        assert!(force[1..].iter().all(|f| f.y < 0.0 && f.x > 0.0));
        assert!(force.iter().sum::<Vec3>().length() < 1e-7);
    }

    #[test]
    fn an_armed_spring_engages_where_the_solution_brings_its_pair_within_its_gap() {
        let (s, x) = spring();
        let armed = ContactSpring { stiffness: 0.0, drag: 0.0, armed: s.stiffness, ..s };
        let v = vec![Vec3::ZERO; 4];
        // 2.5 mm up, beyond the 2 mm gap: it stays armed and gives no force.
        let mut apart = x.clone();
        apart[0].y = 0.0025;
        let mut springs = [armed];
        assert!(!lag_changes(&springs, &apart, &v));
        let mut force = vec![Vec3::ZERO; 4];
        add_forces(&springs, &mut SpringTerms::default(), &apart, &v, &mut force);
        assert!(force.iter().all(|f| *f == Vec3::ZERO));
        // 1.5 mm up, within it: it engages, pushing k · 0.5 mm, with friction from that push.
        let mut pressed = x.clone();
        pressed[0].y = 0.0015;
        assert!(lag_changes(&springs, &pressed, &v));
        lag(&mut springs, &pressed, &v);
        assert_eq!(springs[0].stiffness, s.stiffness);
        assert!((springs[0].push(&pressed) - 0.025).abs() < 1e-6);
        assert!(springs[0].drag > 0.0);
    }

    #[test]
    fn lagging_takes_the_push_and_sliding_at_the_solution_and_releases_a_spring_that_pulls() {
        let (s, x) = spring();
        // Slides at 0.5 m/s along x; 1.5 mm up, the spring pushes k · 0.5 mm = 0.025 N.
        let v = vec![Vec3::new(0.5, 0.0, 0.0), Vec3::ZERO, Vec3::ZERO, Vec3::ZERO];
        let mut pressed = x.clone();
        pressed[0].y = 0.0015;
        let mut springs = [s];
        lag(&mut springs, &pressed, &v);
        assert!((springs[0].drag - 0.5 * 0.025 / 0.5).abs() < 1e-6, "drag {}", springs[0].drag);
        assert_eq!(springs[0].stiffness, s.stiffness);
        // 2.5 mm up, beyond the 2 mm gap, it would pull.
        let mut apart = x.clone();
        apart[0].y = 0.0025;
        assert!(lag_changes(&springs, &apart, &v));
        lag(&mut springs, &apart, &v);
        assert_eq!((springs[0].stiffness, springs[0].drag), (0.0, 0.0));
        let mut force = vec![Vec3::ZERO; 4];
        add_forces(&springs, &mut SpringTerms::default(), &apart, &v, &mut force);
        assert!(force.iter().all(|f| *f == Vec3::ZERO));
    }

    #[test]
    fn stiffness_and_friction_are_minus_the_derivatives_of_the_forces() {
        let (s, x) = spring();
        let y = vec![Vec3::new(0.3, -1.0, 0.2), Vec3::new(0.1, 0.4, 0.0), Vec3::new(-0.2, 0.7, 1.0), Vec3::Y];
        let v = vec![Vec3::ZERO; 4];
        // −(f(x + εy) − f(x)) / ε and −(f(v + εy) − f(v)) / ε: the forces are linear.
        let eps = 1e-3;
        let moved: Vec<Vec3> = x.iter().zip(&y).map(|(x, y)| *x + eps * *y).collect();
        let (mut f0, mut fx, mut fv) = (vec![Vec3::ZERO; 4], vec![Vec3::ZERO; 4], vec![Vec3::ZERO; 4]);
        add_forces(&[s], &mut SpringTerms::default(), &x, &v, &mut f0);
        add_forces(&[s], &mut SpringTerms::default(), &moved, &v, &mut fx);
        add_forces(
            &[s],
            &mut SpringTerms::default(),
            &x,
            &moved.iter().zip(&x).map(|(m, x)| *m - *x).collect::<Vec<_>>(),
            &mut fv,
        );
        let weights = Weights { stiffness: 0.7, drag: 0.2 };
        let mut product = vec![Vec3::ZERO; 4];
        add_product(&[s], &mut SpringTerms::default(), weights, &y, &mut product);
        for k in 0..4 {
            let numeric = -(0.7 * (fx[k] - f0[k]) + 0.2 * (fv[k] - f0[k])) / eps;
            assert!((product[k] - numeric).length() < 1e-3 * numeric.length().max(1.0), "{k}");
        }
    }
}
