//! Block descent: the linear solve of an implicit step by per-particle 3×3 Newton steps,
//! particles graph-coloured so that each colour updates in parallel, accelerated by
//! Chebyshev's semi-iterative method (Wang 2015, as in vertex block descent, Chen et al.
//! 2024).
//!
//! The implicit-Euler step minimises the incremental potential; linearised, its Newton
//! system is `A Δv = b` with `A` symmetric positive definite. A per-particle Newton step
//! holds every other particle fixed and minimises over one particle's 3 velocities: that
//! is block Gauss–Seidel, which descends the quadratic energy at every row, so a sweep
//! stopped early is still a stable, softer step rather than garbage. Particles of one
//! colour share no element, so their rows are independent and run in parallel; the
//! colours run in a fixed order, which makes the result the same for any thread count.
//!
//! Constraints (pins, contact normals) enter as per-particle filters `S`, as in the
//! conjugate gradients of [`super::implicit`]: a particle's Newton step is taken within
//! the directions its filter leaves free, `c = (S A_ii S + I − S)⁻¹ S r`.
//!
//! Contact with the cloth itself and with solid bodies bounds every iteration
//! ([`BoundedMotion`]): each particle keeps within its [`Bound`] of a configuration free of
//! crossings and of bodies ([`MotionBounds`], [`body_bounds`]), so no sweep carries a
//! vertex through a triangle, an edge through an edge, or a vertex into a body. A Newton
//! step that would leave the bound's ball is cut short on its own line; one that would
//! cross its plane (a body's tangent plane) is first projected onto it, the minimum of the
//! particle's energy on its side (the contact force the body gives it), so a particle
//! landing on a body slides along it within the sweeps. Bounds that cut steps short are
//! measured again from where the particles are after sweeps 1, 4, 16…, so a particle
//! stopped at its bound goes on in the sweeps after.
//!
//! [`MotionBounds`]: crate::collision::motion_bounds::MotionBounds
//! [`body_bounds`]: crate::collision::body_bounds

use glam::{Mat3, Vec3, Vec4};
use rayon::prelude::*;

use super::elements::BlockPattern;
use super::filter::Filters;
use super::floating::FloatingPieces;
use super::implicit::StepSystem;
use crate::collision::motion_bounds::{Bound, Mobility};

/// Rows per parallel task in a colour: a row is a few hundred flops, and colours are a
/// fraction of the cloth, so the cut-off is lower than the crate's.
const ROWS_PER_TASK: usize = 64;

/// Sweeps before the Chebyshev acceleration starts.
const PLAIN_SWEEPS: u32 = 2;

/// The particles grouped by colour: no two particles of one colour share a block of the
/// pattern (an element).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Colouring {
    /// Particles, colour after colour, ascending within a colour.
    pub order: Vec<u32>,
    /// Colour `c` is `order[offsets[c]..offsets[c + 1]]`.
    pub offsets: Vec<u32>,
}

impl Colouring {
    /// Greedy colouring in particle order: each particle takes the lowest colour none of
    /// its pattern neighbours has. A grid with bending stencils needs about a dozen.
    pub fn greedy(pattern: &BlockPattern) -> Self {
        let rows = pattern.rows();
        let mut colour = vec![u32::MAX; rows];
        let mut taken: Vec<bool> = Vec::new();
        for i in 0..rows {
            taken.clear();
            for &j in pattern.row(i) {
                let c = colour[j as usize];
                if c != u32::MAX {
                    if taken.len() <= c as usize {
                        taken.resize(c as usize + 1, false);
                    }
                    taken[c as usize] = true;
                }
            }
            colour[i] = taken.iter().position(|t| !t).unwrap_or(taken.len()) as u32;
        }
        let count = colour.iter().max().map_or(0, |c| c + 1) as usize;
        let mut offsets = vec![0u32; count + 1];
        for &c in &colour {
            offsets[c as usize + 1] += 1;
        }
        for c in 0..count {
            offsets[c + 1] += offsets[c];
        }
        let mut next = offsets.clone();
        let mut order = vec![0u32; rows];
        for (i, &c) in colour.iter().enumerate() {
            order[next[c as usize] as usize] = i as u32;
            next[c as usize] += 1;
        }
        Self { order, offsets }
    }

    /// Number of colours.
    pub fn colours(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// The particles of colour `c`.
    pub fn colour(&self, c: usize) -> &[u32] {
        &self.order[self.offsets[c] as usize..self.offsets[c + 1] as usize]
    }
}

/// How block descent runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DescentSettings {
    /// Sweeps over all colours per solve, at most: the cost of a step. Too few leave the
    /// slow modes of a stiff cloth unsolved, and it then hangs as if partly held (a
    /// 32 × 32 sheet of 10⁴ N/m at 1/60 s: its pins carried a fifth of its weight after
    /// 20 sweeps, all of it after 60).
    pub sweeps: u32,
    /// Estimated spectral radius ρ ∈ [0, 1) of a Gauss–Seidel sweep, which sets the
    /// Chebyshev weights; 0 turns the acceleration off. Too high a value overshoots.
    pub spectral_radius: f32,
    /// Whether a self-colliding cloth's contact with itself and with the other
    /// self-colliding cloths, and every cloth's contact with the solid bodies, bounds every
    /// sweep ([`BoundedMotion`]).
    pub contact_bounds: bool,
}

impl Default for DescentSettings {
    fn default() -> Self {
        Self { sweeps: 60, spectral_radius: 0.98, contact_bounds: true }
    }
}

/// Buffers of [`descend`], reused from solve to solve.
#[derive(Debug, Clone, Default)]
pub struct DescentWorkspace {
    /// Per particle, `(S A_ii S + I − S)⁻¹ S`: its filtered Newton step.
    step: Vec<Mat3>,
    /// The iterate before the last sweep, for the Chebyshev extrapolation.
    previous: Vec<Vec3>,
    before: Vec<Vec3>,
    /// Per row of the colour being swept: its correction, squared residual and whether
    /// its bound cut the correction short.
    update: Vec<(Vec3, f64, bool)>,
    /// Per particle, where it may move from the anchor.
    bounds: Vec<Bound>,
    /// Per particle, how it moves in the sweeps, for the bounds.
    mobility: Vec<Mobility>,
    /// The system's floating pieces, whose translations a coarse correction solves.
    floating: FloatingPieces,
}

/// Where block descent's iterate puts the particles, and where they may move: particle
/// `i` is at `base[i] + scale · delta[i]`, and keeps within `bounds[i]` about
/// `anchor[i]`, bounds that `bound` measures at a configuration, knowing which particles
/// the sweeps leave still there ([`Mobility`]).
pub struct BoundedMotion<'a> {
    /// Positions at `delta = 0` [m].
    pub base: &'a [Vec3],
    /// How far a unit of `delta` moves a particle [m per unit].
    pub scale: f32,
    /// A configuration free of crossings and outside the bodies; on return, where the
    /// particles end, which is one too.
    pub anchor: &'a mut [Vec3],
    /// Fills, for the particles at the given positions, where each may move, asked for
    /// moves as long as the second argument [m] where the geometry allows them; the third
    /// says how each moves.
    pub bound: &'a mut dyn FnMut(&[Vec3], f32, &[Mobility], &mut [Bound]),
}

impl BoundedMotion<'_> {
    fn frame(&self) -> Frame<'_> {
        Frame { base: self.base, scale: self.scale, anchor: self.anchor }
    }

    /// Makes where `delta` puts the particles the anchor.
    fn settle(&mut self, delta: &[Vec3]) {
        let (base, scale) = (self.base, self.scale);
        self.anchor
            .par_iter_mut()
            .zip(delta.par_iter())
            .enumerate()
            .with_min_len(super::PARALLEL_MIN_LEN)
            .for_each(|(i, (anchor, d))| *anchor = position(base, scale, i, *d));
    }
}

/// Where particle `i` is at `delta`: `base[i] + scale · delta`.
fn position(base: &[Vec3], scale: f32, i: usize, delta: Vec3) -> Vec3 {
    base[i] + scale * delta
}

/// The positions of a [`BoundedMotion`], shared by the threads of a sweep.
#[derive(Clone, Copy)]
struct Frame<'a> {
    base: &'a [Vec3],
    scale: f32,
    anchor: &'a [Vec3],
}

impl Frame<'_> {
    /// Particle `i`'s distance vector from its anchor at `delta`.
    fn offset(&self, i: usize, delta: Vec3) -> Vec3 {
        position(self.base, self.scale, i, delta) - self.anchor[i]
    }

    /// The fraction of the change `change` to particle `i`'s `delta` that keeps it within
    /// `bound` about its anchor (where it is within it): the move is cut short on its own
    /// line, so a cut Newton step still descends the energy.
    fn allowed(&self, i: usize, delta: Vec3, change: Vec3, bound: &Bound) -> f32 {
        bound.allowed(self.anchor[i], position(self.base, self.scale, i, delta), self.scale * change)
    }

    /// Particle `i`'s Newton step from `delta` for the residual `r`, `newton` its filtered
    /// inverse diagonal block, within `bound`: if the particle is `free` of constraints,
    /// projected onto the bound's plane where it would come within its slack (the minimum
    /// of the row's energy on that side, the multiple of `newton · normal` that the
    /// plane's push adds); then cut short on its line where it would leave the bound. The
    /// projection puts it the slack beyond the plane. A constrained particle is only cut:
    /// its filter may leave the plane's normal almost no room, and the projection would
    /// then throw it far along the plane. Returns the step, the part of `r` that the plane
    /// does not bear (all of it unless the plane pushes), and whether the bound cut the
    /// step: the ball did, or the plane where projecting did not do.
    fn newton_step(
        &self,
        i: usize,
        delta: Vec3,
        newton: Mat3,
        r: Vec3,
        bound: &Bound,
        free: bool,
    ) -> (Vec3, Vec3, bool) {
        let (mut correction, mut r) = (newton * r, r);
        let from = position(self.base, self.scale, i, delta);
        let normal = bound.plane.truncate();
        let beyond = bound.room(from + self.scale * correction) - bound.slack;
        let push = newton * normal;
        let stiffness = self.scale * normal.dot(push);
        let projected = free && beyond < 0.0 && stiffness > 0.0;
        if projected {
            correction -= (beyond / stiffness) * push;
            r -= normal.dot(r).min(0.0) * normal;
        }
        let step = self.scale * correction;
        let (ball, plane) = (bound.ball_allows(self.anchor[i], from, step), bound.plane_allows(from, step));
        (ball.min(plane) * correction, r, ball < 1.0 || (plane < 1.0 && !projected))
    }
}

/// Most measures of the bounds that [`advance_anchor`] makes.
const MAX_ADVANCES: u32 = 16;

/// Below this squared length of a body's plane normal through a particle's filter,
/// `|S n|²`, the filter fixes the particle's motion along the normal (the normal within
/// 0.06° of its constraint's).
const FIXED_NORMAL: f32 = 1e-6;

/// Measures the bounds at the anchor for moves as long as `wanted`, then takes the body's
/// plane out of the bound of a particle whose filter fixes the motion along the plane's
/// normal: that motion is its constraint's (a resting contact's, which keeps it on the
/// body), not the sweeps'. The sweeps' moves of such a particle lie along the plane, and
/// the normal part of one is round-off; where the particle rests on the plane with no
/// room to spare, that round-off led the plane to cut the whole move, slide and all. On
/// Zheng's slope at one step a frame every slide faster than 3.5 m/s was so cut, and the
/// cloth, sliding at 3.12 m/s², slowed at 1.2 m/s² instead.
///
/// A pinned particle at its anchor is still for the bounds: the sweeps leave it there.
fn measure(
    motion: &mut BoundedMotion<'_>,
    delta: &[Vec3],
    wanted: f32,
    filter: &Filters,
    mobility: &mut Vec<Mobility>,
    bounds: &mut [Bound],
) {
    let frame = motion.frame();
    mobility.resize(delta.len(), Mobility::Free);
    mobility.par_iter_mut().enumerate().with_min_len(super::PARALLEL_MIN_LEN).for_each(|(i, m)| {
        *m = if filter.is_free(i) {
            Mobility::Free
        } else if filter.is_pinned(i) && frame.offset(i, delta[i]) == Vec3::ZERO {
            Mobility::Still
        } else {
            Mobility::Constrained
        };
    });
    (motion.bound)(motion.anchor, wanted, mobility, bounds);
    bounds.par_iter_mut().enumerate().with_min_len(super::PARALLEL_MIN_LEN).for_each(|(i, bound)| {
        if !filter.is_free(i) && filter.apply(i, bound.plane.truncate()).length_squared() < FIXED_NORMAL {
            bound.plane = Vec4::ZERO;
        }
    });
}

/// Moves the anchor towards where `delta` starts the particles, in steps within the
/// bounds, measuring them again after each, while that brings the farthest particle
/// closer by a quarter (a move that would not is not made, which spares the measure
/// after it), or by a tenth where every particle the bounds stop short is of a floating
/// piece ([`FloatingPieces`]) resting whole on planes: a layer sliding on a still one,
/// whose gap does not shrink as it slides, and whose balls are set by its own sheet (a
/// 40 mm slide a step against balls of 7 mm stopped after the first move). A piece
/// partly on planes is a cloth landing, which the looser rule made stretch more (the
/// fold heap peaked at 0.73 strain against 0.48). `bounds` end measured at the anchor.
/// A start outside them, which contact stopped, is then pulled back onto them for
/// particles the filters leave free; a constrained particle, whose `delta` the filter
/// fixes in part, is left unbounded until the bounds are next measured. Returns the
/// longest move the bounds were asked for.
///
/// Starting the sweeps from the bounds instead, every particle held back by them, would
/// leave the sweeps a global error to remove, which Gauss–Seidel removes last: a falling
/// strip's speed stayed at the bound per step.
fn advance_anchor(
    motion: &mut BoundedMotion<'_>,
    delta: &mut [Vec3],
    filter: &Filters,
    floating: &mut FloatingPieces,
    mobility: &mut Vec<Mobility>,
    bounds: &mut [Bound],
) -> f32 {
    let n = delta.len();
    let frame = motion.frame();
    let mut wanted = (0..n)
        .into_par_iter()
        .with_min_len(super::PARALLEL_MIN_LEN)
        .map(|i| frame.offset(i, delta[i]).length())
        .reduce(|| 0.0, f32::max);
    for advance in 1..=MAX_ADVANCES {
        measure(motion, delta, wanted, filter, mobility, bounds);
        // How many particles the bounds stop short of the start, and how far from it the
        // farthest would be left after a move.
        let frame = motion.frame();
        let (beyond, left) = (0..n)
            .into_par_iter()
            .with_min_len(super::PARALLEL_MIN_LEN)
            .map(|i| {
                let offset = frame.offset(i, delta[i]);
                let allowed = reach(&bounds[i], frame.anchor[i], offset);
                (u32::from(allowed < 1.0), offset.length() * (1.0 - allowed))
            })
            .reduce(|| (0, 0.0), |(a, x), (b, y)| (a + b, x.max(y)));
        let mut sliding = || {
            let cut = |i: usize| reach(&bounds[i], frame.anchor[i], frame.offset(i, delta[i])) < 1.0;
            floating.cut_only_where_resting(|i| bounds[i].pressed(frame.anchor[i]), cut)
        };
        if beyond == 0 || advance == MAX_ADVANCES || (left > 0.75 * wanted && (left > 0.9 * wanted || !sliding())) {
            break;
        }
        let (base, scale, delta) = (motion.base, motion.scale, &*delta);
        motion.anchor.par_iter_mut().enumerate().with_min_len(super::PARALLEL_MIN_LEN).for_each(|(i, anchor)| {
            let offset = position(base, scale, i, delta[i]) - *anchor;
            *anchor += offset * reach(&bounds[i], *anchor, offset);
        });
        wanted = left;
    }
    let frame = motion.frame();
    delta.par_iter_mut().zip(bounds.par_iter_mut()).enumerate().with_min_len(super::PARALLEL_MIN_LEN).for_each(
        |(i, (d, bound))| {
            let offset = frame.offset(i, *d);
            let allowed = reach(bound, frame.anchor[i], offset);
            if allowed < 1.0 {
                if filter.is_free(i) {
                    *d += offset * (allowed - 1.0) / frame.scale;
                } else {
                    *bound = Bound::FREE;
                }
            }
        },
    );
    wanted
}

/// The fraction of the straight move `offset` from `anchor` that keeps within `bound`:
/// the ball's part as the ratio of lengths, 1 if the move ends within it.
fn reach(bound: &Bound, anchor: Vec3, offset: Vec3) -> f32 {
    let length = offset.length();
    let ball = if length > bound.radius { bound.radius / length } else { 1.0 };
    ball.min(bound.plane_allows(anchor, offset))
}

/// Improves `delta` towards the solution of `system · delta = rhs` within the per-particle
/// `filter`s, by at most `settings.sweeps` coloured block Gauss–Seidel sweeps with
/// Chebyshev acceleration. `delta` must already hold the prescribed part of the solution;
/// the sweeps only move it within the filters. A sweep visits the colours forward, then
/// backward. Stops once the residual met in a forward pass is at most `tolerance` times the
/// filtered right-hand side. Returns the sweeps taken.
///
/// With `motion`, every particle keeps within its bound of the anchor, which first
/// advances towards the start ([`advance_anchor`]).
#[allow(clippy::too_many_arguments)]
pub fn descend(
    system: StepSystem<'_>,
    colouring: &Colouring,
    rhs: &[Vec3],
    filter: &Filters,
    settings: &DescentSettings,
    tolerance: f32,
    mut motion: Option<BoundedMotion<'_>>,
    delta: &mut [Vec3],
    ws: &mut DescentWorkspace,
) -> u32 {
    let n = delta.len();
    ws.step.clear();
    ws.step.extend((0..n).map(|i| filter.inverse(i, system.diagonal(i))));
    ws.previous.resize(n, Vec3::ZERO);
    ws.before.resize(n, Vec3::ZERO);
    // The longest move the bounds are asked to allow: the farthest the start took a
    // particle from its anchor.
    let mut wanted = 0.0f32;
    ws.floating.find(system, filter);
    if let Some(motion) = &mut motion {
        ws.bounds.resize(n, Bound::FREE);
        wanted = advance_anchor(motion, delta, filter, &mut ws.floating, &mut ws.mobility, &mut ws.bounds);
    }
    translate_pieces(rhs, motion.as_ref(), delta, ws);
    let target: f64 = f64::from(tolerance).powi(2)
        * rhs.iter().enumerate().map(|(i, r)| f64::from(filter.apply(i, *r).length_squared())).sum::<f64>();
    let rho2 = settings.spectral_radius * settings.spectral_radius;
    let mut omega = 1.0f32;
    let mut sweeps = settings.sweeps;
    let mut cuts = 0u32;
    for sweep in 0..settings.sweeps {
        ws.before.copy_from_slice(delta);
        let mut residual = 0.0f64;
        // Forward then backward over the colours: a symmetric sweep, whose iteration
        // matrix has real eigenvalues in [0, 1) for a positive definite system, which is
        // what the Chebyshev weights assume (a one-way sweep's may be complex).
        let colours = colouring.colours();
        for (visit, c) in (0..colours).chain((0..colours).rev()).enumerate() {
            let rows = colouring.colour(c);
            ws.update.resize(rows.len(), (Vec3::ZERO, 0.0, false));
            let (step, bounds, current) = (&ws.step, &ws.bounds, &*delta);
            let frame = motion.as_ref().map(BoundedMotion::frame);
            ws.update.par_iter_mut().zip(rows.par_iter()).with_min_len(ROWS_PER_TASK).for_each(|(update, &i)| {
                let i = i as usize;
                let r = filter.apply(i, rhs[i] - system.row_product(i, current));
                let (correction, r, cut) = match frame {
                    Some(f) => f.newton_step(i, current[i], step[i], r, &bounds[i], filter.is_free(i)),
                    None => (step[i] * r, r, false),
                };
                *update = (correction, f64::from(r.length_squared()), cut);
            });
            for (&i, &(correction, r2, cut)) in rows.iter().zip(&ws.update) {
                delta[i as usize] += correction;
                cuts += u32::from(cut);
                if visit < colours {
                    residual += r2;
                }
            }
        }
        if residual <= target {
            sweeps = sweep + 1;
            break;
        }
        // Chebyshev: ω₁ = 1, ω₂ = 2 / (2 − ρ²), ω_{k+1} = 4 / (4 − ρ² ω_k), after
        // PLAIN_SWEEPS plain ones. Its polynomial ripples over the whole spectrum, so an
        // early extrapolation overshoots the stiff modes a plain sweep had already solved:
        // two sweeps at ρ = 0.9 made a swinging sheet diverge.
        omega = match sweep.checked_sub(PLAIN_SWEEPS) {
            None | Some(0) => 1.0,
            Some(1) => 2.0 / (2.0 - rho2),
            Some(_) => 4.0 / (4.0 - rho2 * omega),
        };
        if omega != 1.0 {
            let (bounds, frame) = (&ws.bounds, motion.as_ref().map(BoundedMotion::frame));
            cuts += delta
                .par_iter_mut()
                .zip(ws.previous.par_iter())
                .enumerate()
                .with_min_len(super::PARALLEL_MIN_LEN)
                .map(|(i, (d, p))| {
                    let extrapolated = omega * (*d - *p) + *p;
                    let allowed = frame.map_or(1.0, |f| f.allowed(i, *d, extrapolated - *d, &bounds[i]));
                    *d = if allowed < 1.0 { *d + allowed * (extrapolated - *d) } else { extrapolated };
                    u32::from(allowed < 1.0)
                })
                .sum::<u32>();
        }
        std::mem::swap(&mut ws.previous, &mut ws.before);
        // Bounds that cut steps short are measured again after sweeps 1, 4, 16…: a
        // particle pressed against another layer is cut at every sweep, and measuring
        // again gains it only a fraction of its shrinking gap, while a measure costs
        // about ten sweeps of a 64² sheet (after 1, 2, 4, 8…, sphere_64 at one step a
        // frame took 20 % longer for the same strain).
        if let Some(motion) = &mut motion
            && cuts > 0
            && (sweep + 1).is_power_of_two()
            && (sweep + 1).trailing_zeros() % 2 == 0
        {
            motion.settle(delta);
            measure(motion, delta, wanted, filter, &mut ws.mobility, &mut ws.bounds);
            cuts = 0;
        }
    }
    translate_pieces(rhs, motion.as_ref(), delta, ws);
    if let Some(motion) = &mut motion {
        motion.settle(delta);
    }
    sweeps
}

/// Corrects the floating pieces' translations ([`FloatingPieces::correct`]), along the
/// planes of their bounds that they are pressed against, and within the bounds.
fn translate_pieces(rhs: &[Vec3], motion: Option<&BoundedMotion<'_>>, delta: &mut [Vec3], ws: &mut DescentWorkspace) {
    let (bounds, frame) = (&ws.bounds, motion.map(BoundedMotion::frame));
    let plane = |i: usize, d: Vec3| match frame {
        Some(f) if bounds[i].pressed(position(f.base, f.scale, i, d)) => bounds[i].plane.truncate(),
        _ => Vec3::ZERO,
    };
    let allowed = |i: usize, d: Vec3, t: Vec3| frame.map_or(1.0, |f| f.allowed(i, d, t, &bounds[i]));
    ws.floating.correct(rhs, delta, plane, allowed);
}

#[cfg(test)]
pub(crate) mod tests {
    use parry3d::shape::SharedShape;

    use super::*;
    use crate::collision::body_bounds;
    use crate::collision::body_bounds::tests::{THICKNESS, body};
    use crate::collision::motion_bounds::tests::{Lcg, any_crossing, two_layers};
    use crate::collision::motion_bounds::{MotionBounds, Surface};
    use crate::collision::self_contact::ContactMesh;
    use crate::solver::elements::SymmetricBlockMatrix;

    /// `n` particles of mass `m` joined at `pairs` by springs of stiffness `k` along x, y
    /// and z alike, as the system `M + k L` of an implicit step.
    pub(crate) fn spring_system(n: usize, pairs: &[[u32; 2]], m: f32, k: f32) -> (BlockPattern, SymmetricBlockMatrix) {
        let pattern = BlockPattern::from_stencils(n, pairs.iter().map(|p| &p[..])).with_upper();
        let mut system = SymmetricBlockMatrix::default();
        system.reset(&pattern);
        system.add_diagonal(&pattern, |_| m);
        let stiffness = Mat3::from_diagonal(Vec3::splat(k));
        for p in pairs {
            system.add_local(*p, &pattern.upper_slots::<2, 3>(*p), &[[stiffness, -stiffness], [-stiffness, stiffness]]);
        }
        (pattern, system)
    }

    /// A chain of `n` particles joined by springs of stiffness `k`, mass `m`.
    fn chain(n: usize, m: f32, k: f32) -> (BlockPattern, SymmetricBlockMatrix) {
        let pairs: Vec<[u32; 2]> = (0..n as u32 - 1).map(|i| [i, i + 1]).collect();
        spring_system(n, &pairs, m, k)
    }

    /// `n` particles of 1 g joined along `edges` by springs of 10 N/m, as the system
    /// `M + h² K` of an implicit step of `h` [s].
    fn edge_springs(n: usize, edges: &[[u32; 2]], h: f32) -> (BlockPattern, SymmetricBlockMatrix) {
        let pattern = BlockPattern::from_stencils(n, edges.iter().map(|e| &e[..])).with_upper();
        let mut system = SymmetricBlockMatrix::default();
        system.reset(&pattern);
        system.add_diagonal(&pattern, |_| 1e-3);
        let k = Mat3::from_diagonal(Vec3::splat(h * h * 10.0));
        for e in edges {
            system.add_local(*e, &pattern.upper_slots::<2, 3>(*e), &[[k, -k], [-k, k]]);
        }
        (pattern, system)
    }

    /// Where the particles at `x0`, joined by [`edge_springs`] along `edges`, are after
    /// `sweeps` sweeps from rest of the step of `h` [s] whose solution is `solution` (Δv),
    /// each sweep within `bound` if given.
    fn swept(
        x0: &[Vec3],
        edges: &[[u32; 2]],
        h: f32,
        solution: &[Vec3],
        sweeps: u32,
        bound: Option<&mut dyn FnMut(&[Vec3], f32, &[Mobility], &mut [Bound])>,
    ) -> Vec<Vec3> {
        let n = x0.len();
        let (pattern, system) = edge_springs(n, edges, h);
        let mut rhs = vec![Vec3::ZERO; n];
        system.multiply(&pattern, solution, &mut rhs);
        let settings = DescentSettings { sweeps, ..DescentSettings::default() };
        let (mut delta, mut ws, mut anchor) = (vec![Vec3::ZERO; n], DescentWorkspace::default(), x0.to_vec());
        let motion = bound.map(|bound| BoundedMotion { base: x0, scale: h, anchor: &mut anchor, bound });
        descend(
            StepSystem::new(&pattern, &system),
            &Colouring::greedy(&pattern),
            &rhs,
            &Filters::free(n),
            &settings,
            0.0,
            motion,
            &mut delta,
            &mut ws,
        );
        x0.iter().zip(&delta).map(|(x, d)| *x + h * *d).collect()
    }

    #[test]
    fn a_grid_pattern_gets_a_proper_colouring() {
        // A 5 × 5 grid with both diagonals in every cell: the 8-neighbourhood needs 4.
        let index = |i: u32, j: u32| i * 5 + j;
        let mut stencils = Vec::new();
        for i in 0..4 {
            for j in 0..4 {
                stencils.push([index(i, j), index(i + 1, j), index(i, j + 1), index(i + 1, j + 1)]);
            }
        }
        let pattern = BlockPattern::from_stencils(25, stencils.iter().map(|s| &s[..]));
        let colouring = Colouring::greedy(&pattern);
        assert_eq!(colouring.colours(), 4);
        let mut seen = colouring.order.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..25).collect::<Vec<_>>());
        for c in 0..colouring.colours() {
            for &i in colouring.colour(c) {
                for &j in colouring.colour(c) {
                    assert!(i == j || pattern.slot(i, j).is_none(), "{i} and {j} share colour {c}");
                }
            }
        }
    }

    #[test]
    fn sweeps_converge_to_the_direct_solution_with_pins_and_a_normal_filter() {
        // 40 particles, stiff springs (k/m = 1e3, like cloth at frame-sized steps), end 0
        // pinned, particle 39 free only across x, loaded by gravity-like forces.
        let n = 40;
        let (pattern, system) = chain(n, 1.0, 1.0e3);
        let mut filter = Filters::free(n);
        filter.pin(0);
        filter.constrain(n - 1, Mat3::IDENTITY - Mat3::from_diagonal(Vec3::X));
        let rhs: Vec<Vec3> = (0..n).map(|i| Vec3::new(0.5, -1.0, 0.1 * i as f32)).collect();
        // Exact solution of the filtered system: along each axis, the chain is a
        // tridiagonal system with the pinned end fixed at zero; x at particle 39 is fixed
        // at 0.25 (its prescribed part).
        let mut exact = vec![Vec3::ZERO; n];
        for axis in 0..3 {
            let fixed_end = (axis == 0).then_some(0.25f64);
            let unknowns: Vec<usize> = (1..n).filter(|&i| !(i == n - 1 && fixed_end.is_some())).collect();
            let size = unknowns.len();
            let (mut a, mut b, mut c, mut d) = (vec![0.0f64; size], vec![0.0; size], vec![0.0; size], vec![0.0; size]);
            for (r, &i) in unknowns.iter().enumerate() {
                let block = |j: usize| f64::from(system.block(&pattern, i as u32, j as u32).col(axis)[axis]);
                b[r] = block(i);
                d[r] = f64::from(rhs[i][axis]);
                if i > 1 {
                    a[r] = block(i - 1);
                }
                if r + 1 < size {
                    c[r] = block(i + 1);
                } else if let Some(value) = fixed_end {
                    d[r] -= block(n - 1) * value;
                }
            }
            // Thomas algorithm.
            for r in 1..size {
                let w = a[r] / b[r - 1];
                b[r] -= w * c[r - 1];
                d[r] -= w * d[r - 1];
            }
            let mut solution = vec![0.0f64; size];
            solution[size - 1] = d[size - 1] / b[size - 1];
            for r in (0..size - 1).rev() {
                solution[r] = (d[r] - c[r] * solution[r + 1]) / b[r];
            }
            for (r, &i) in unknowns.iter().enumerate() {
                exact[i][axis] = solution[r] as f32;
            }
            if let Some(value) = fixed_end {
                exact[n - 1][axis] = value as f32;
            }
        }
        let colouring = Colouring::greedy(&pattern);
        assert_eq!(colouring.colours(), 2);
        let error_after = |sweeps: u32, spectral_radius: f32| {
            let mut delta = vec![Vec3::ZERO; n];
            delta[n - 1] = Vec3::new(0.25, 0.0, 0.0);
            let settings = DescentSettings { sweeps, spectral_radius, contact_bounds: false };
            let mut ws = DescentWorkspace::default();
            descend(
                StepSystem::new(&pattern, &system),
                &colouring,
                &rhs,
                &filter,
                &settings,
                0.0,
                None,
                &mut delta,
                &mut ws,
            );
            assert_eq!(delta[0], Vec3::ZERO, "the pin moved");
            assert_eq!(delta[n - 1].x, 0.25, "the prescribed normal part moved");
            delta.iter().zip(&exact).map(|(d, e)| (*d - *e).length()).fold(0.0f32, f32::max)
        };
        let scale = exact.iter().map(|e| e.length()).fold(0.0f32, f32::max);
        let plain = error_after(400, 0.0);
        let accelerated = error_after(400, 0.999);
        assert!(accelerated < 1e-4 * scale, "Chebyshev: error {accelerated} against {scale}");
        assert!(accelerated < 0.01 * plain, "Chebyshev {accelerated} is no faster than plain {plain}");
        // Plain Gauss–Seidel descends: more sweeps, less error.
        assert!(error_after(100, 0.0) < error_after(10, 0.0));
    }

    #[test]
    fn bounded_sweeps_never_carry_a_sheet_into_a_body_and_let_it_slide_on_it() {
        // Two sheets 4 mm apart over the top of a sphere 4 mm below them, one step of
        // 1/60 s whose solution moves them 12 mm down, into it.
        let (x0, triangles) = two_layers(&mut Lcg(5));
        let (n, h, thickness) = (x0.len(), 1.0f32 / 60.0, THICKNESS);
        let (radius, centre) = (0.1f32, Vec3::new(0.025, -0.104, 0.025));
        let sphere = body(SharedShape::ball(radius), centre);
        let (edges, solution) = (ContactMesh::edges_of(&triangles), vec![-0.012 / h * Vec3::Y; n]);
        let after = |sweeps: u32, bounded: bool| {
            let mut bound = |x: &[Vec3], _: f32, _: &[Mobility], out: &mut [Bound]| {
                out.fill(Bound::FREE);
                body_bounds::limit(std::slice::from_ref(&sphere), x, out);
            };
            swept(&x0, &edges, h, &solution, sweeps, bounded.then_some(&mut bound))
        };
        let clearance = |x: &[Vec3]| x.iter().map(|p| p.distance(centre) - radius).fold(f32::INFINITY, f32::min);
        for sweeps in 1..=30 {
            let nearest = clearance(&after(sweeps, true));
            assert!(nearest >= 0.995 * thickness - 1e-6, "sweep {sweeps}: {nearest} m from the sphere");
        }
        // The lower sheet comes to rest on the sphere, at the thickness, and its sides
        // slide down along it: they end lower than the top of the sphere.
        let last = after(30, true);
        assert!(clearance(&last) < 1.01 * thickness);
        let top = centre.y + radius + thickness;
        assert!(last[..36].iter().any(|p| p.y < top - 0.001), "nothing slid down the sphere");
        // Unbounded, the sweeps carry it into the sphere.
        assert!(clearance(&after(30, false)) < -0.005);
    }

    #[test]
    fn bounded_sweeps_never_carry_a_layer_through_another() {
        // Two sheets 4 mm apart, springs along their edges, one step of 1/60 s whose
        // solution moves the upper sheet 12 mm down, through the lower one.
        let (x0, triangles) = two_layers(&mut Lcg(7));
        let edges = ContactMesh::edges_of(&triangles);
        let (n, h) = (x0.len(), 1.0f32 / 60.0);
        let solution: Vec<Vec3> = (0..n).map(|i| if i >= 36 { -0.012 / h * Vec3::Y } else { Vec3::ZERO }).collect();
        let surface = Surface { triangles: &triangles, edges: &edges };
        // Where the particles are after `sweeps` sweeps, with or without the bounds: the
        // sweeps of a longer run begin as a shorter run's did.
        let after = |sweeps: u32, bounded: bool| {
            let mut search = MotionBounds::default();
            let mut bound = |x: &[Vec3], wanted: f32, _: &[Mobility], out: &mut [Bound]| {
                search.compute(surface, None, None, x, wanted, out);
            };
            swept(&x0, &edges, h, &solution, sweeps, bounded.then_some(&mut bound))
        };
        let path = |bounded: bool| -> Vec<Vec<Vec3>> {
            std::iter::once(x0.clone()).chain((1..=30).map(|sweeps| after(sweeps, bounded))).collect()
        };
        let gaps = |x: &[Vec3]| (0..36).map(|i| x[i + 36].y - x[i].y).fold(f32::INFINITY, f32::min);
        let bounded = path(true);
        for (k, pair) in bounded.windows(2).enumerate() {
            assert!(!any_crossing(&triangles, &edges, &pair[0], &pair[1]), "sweep {} crossed", k + 1);
        }
        // The upper sheet comes down onto the lower one, but stays above it.
        let last = &bounded[30];
        assert!((0.0..0.001).contains(&gaps(last)), "gap left {}", gaps(last));
        // Unbounded, the sweeps carry it through.
        let free = path(false);
        assert!(free.windows(2).any(|pair| any_crossing(&triangles, &edges, &pair[0], &pair[1])));
        assert!(gaps(&free[30]) < -0.005);
    }
}
