//! How a free rigid body (a prop) and the cloth resting on it move together: strong
//! coupling inside the cloth's implicit step.
//!
//! The rigid world steps first and gives each body a predicted velocity `V₀`. The implicit
//! step holds the particles resting on a body to the body's velocity at their places, and
//! needs impulses `λᵢ` to do it; the body takes their opposites. Taking them only after the
//! step (staggered coupling) is explicit in the cloth's stiffness: a velocity error `e` of
//! the body comes back as an impulse `S e`, with `S` the cloth's apparent inertia, which on
//! a stiff hammock is many times a light box's mass, and the box is thrown off.
//!
//! So the body's velocity `V` is an unknown of the step: the step is solved again with the
//! constraints following `V` until the body is in balance with what they needed,
//!
//! `R(V) = (V − V₀) + W Gᵀ λ(V) = 0`,
//!
//! `W` the body's inverse mass and inertia and `G` the map from its velocity to the
//! particles' (`Gᵢ V = v + ω × rᵢ`). `λ` is affine in `V` (the step's system is linear),
//! so `R` is too, with Jacobian `1 + W S`. The iteration is Broyden's quasi-Newton method,
//! started from `1 + W D`, `D ≥ S` the step's system restricted to the constrained
//! directions of the touching particles moving rigidly with the body (the rest of the
//! cloth giving way makes `S` smaller). After the step the body takes exactly the opposite
//! of the impulses the cloth got, `V = V₀ − W Gᵀ λ`, so momentum balances, and the body's
//! pose is moved to where that velocity takes it over the step, where the cloth was held.

use glam::{Mat3, Quat, Vec3};

use super::body_contact::Touch;
use crate::solver::elements::spring::{outer, skew};
use crate::solver::implicit::{ConstraintBodies, StepSystem, VelocityConstraint};

/// A free body as the cloth's steps see it: its state after the rigid world's step, with
/// the velocity the cloths' solves have settled on so far.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BodyCoupling {
    /// Velocity of the centre of mass and angular velocity [m/s, rad/s].
    pub velocity: (Vec3, Vec3),
    /// Centre of mass [m].
    pub centre: Vec3,
    /// Inverse mass along each world axis, zero where locked [1/kg].
    pub inv_mass: Vec3,
    /// Inverse inertia about the centre of mass, in the world frame [1/(kg·m²)].
    pub inv_inertia: Mat3,
}

impl BodyCoupling {
    /// The body's state as the rigid world left it.
    pub fn of_body(body: &rapier3d::prelude::RigidBody) -> Self {
        let properties = body.mass_properties();
        BodyCoupling {
            velocity: (body.linvel(), body.angvel()),
            centre: body.center_of_mass(),
            inv_mass: properties.effective_inv_mass,
            inv_inertia: properties.effective_world_inv_inertia.mul_mat(Mat3::IDENTITY),
        }
    }

    /// The velocity change `(Δv, Δω)` that `impulse` and `moment` [N·s, N·m·s] about the
    /// centre of mass give the body.
    pub fn velocity_change(&self, impulse: Vec3, moment: Vec3) -> (Vec3, Vec3) {
        (self.inv_mass * impulse, self.inv_inertia * moment)
    }

    /// Sets `body` to the velocity settled on, and moves its pose by what that velocity
    /// changes over a step of `h` [s] against the velocity the rigid world stepped it with.
    pub fn settle(&self, body: &mut rapier3d::prelude::RigidBody, h: f32) {
        let (linear, angular) = self.velocity;
        let (dv, dw) = (linear - body.linvel(), angular - body.angvel());
        if dv == Vec3::ZERO && dw == Vec3::ZERO {
            return;
        }
        let mut pose = *body.position();
        let turn = Quat::from_scaled_axis(h * dw);
        let centre = self.centre + h * dv;
        pose.rotation = (turn * pose.rotation).normalize();
        pose.translation = centre + turn * (pose.translation - self.centre);
        body.set_position(pose, true);
        body.set_linvel(linear, true);
        body.set_angvel(angular, true);
    }
}

/// The largest change of a body's velocity at its touching particles [m/s] below which
/// [`PropCoupling`] counts the body as balanced: 4.2 µm over a 1/240 s step.
const BALANCE_TOLERANCE: f64 = 1e-3;

/// A body's 6 velocity unknowns, `(v, L ω)`, and residuals in the same scaling.
type Vector6 = [f64; 6];
/// A 6 × 6 matrix, by rows.
type Matrix6 = [[f64; 6]; 6];

/// One free body in a cloth's step.
#[derive(Debug, Clone, Default)]
struct CoupledBody {
    /// Whether the body is free (a prop); the rest are never moved.
    free: bool,
    /// Its state before this cloth's step.
    start: BodyCoupling,
    /// The velocity the constraints now follow.
    velocity: (Vec3, Vec3),
    /// The unknowns and residual of the last rebalance.
    last: Option<(Vector6, Vector6)>,
}

/// A constraint held on a free body.
#[derive(Debug, Clone, Copy)]
struct Link {
    /// The body's index.
    body: usize,
    /// The particle's place relative to the body's centre [m].
    lever: Vec3,
    /// The velocity along the normal that closes the gap the last step left [m/s].
    closing: Vec3,
}

/// The free bodies of one cloth's step and the constraints that hold particles on them:
/// the [`ConstraintBodies`] of [`crate::solver::implicit::implicit_step`] for props.
#[derive(Debug, Clone, Default)]
pub struct PropCoupling {
    bodies: Vec<CoupledBody>,
    /// Per constraint, in order, the body it is held on if that body is free.
    links: Vec<Option<Link>>,
    /// The cloth being stepped.
    cloth: usize,
    /// Per cloth and body, Broyden's estimate of the residual's Jacobian, scaled, with its
    /// scale: the length [m] that turns angular velocities into the unknowns (the furthest
    /// touching particle from the centre when it was first made). Kept from step to step,
    /// since the cloth resting on a body changes little, so that a step starts from what
    /// the last one learnt; dropped when the body is not touched.
    learned: Vec<Option<(f32, Matrix6)>>,
}

impl PropCoupling {
    /// Starts the step of cloth number `cloth` (counting from 0 every step) with the
    /// bodies in contact order: `Some` state for the free ones; `touching` particles of
    /// the cloth may be constrained.
    pub fn begin(
        &mut self,
        cloth: usize,
        bodies: impl ExactSizeIterator<Item = Option<BodyCoupling>>,
        touching: usize,
    ) {
        if bodies.len() != self.bodies.len() {
            self.learned.clear();
        }
        self.cloth = cloth;
        let needed = (cloth + 1) * bodies.len();
        if self.learned.len() < needed {
            self.learned.resize(needed, None);
        }
        self.bodies.clear();
        self.bodies.extend(bodies.map(|state| CoupledBody {
            free: state.is_some(),
            start: state.unwrap_or_default(),
            velocity: state.map_or((Vec3::ZERO, Vec3::ZERO), |s| s.velocity),
            ..CoupledBody::default()
        }));
        self.links.clear();
        // Room for a link a touching particle at once, rather than by doubling.
        self.links.reserve(touching);
    }

    /// Whether any body is free.
    pub fn has_free_bodies(&self) -> bool {
        self.bodies.iter().any(|b| b.free)
    }

    /// The constraint keeping the particle at `x` on the body it touches, after a step of
    /// `h` that left it `touch`: on a free body it follows the body's velocity (and is
    /// linked to it), on any other the surface velocity the contact saw. Either way it
    /// also closes the gap the last step left. Constraints are taken in particle order.
    pub fn constrain(&mut self, touch: &Touch, x: Vec3, h: f32) -> VelocityConstraint {
        let closing = -touch.gap / h * touch.normal;
        let body = touch.body as usize;
        let link = self.bodies.get(body).filter(|b| b.free).map(|b| Link { body, lever: x - b.start.centre, closing });
        self.links.push(link);
        let velocity = match link {
            Some(link) => self.velocity_at(&link),
            None => touch.surface_velocity + closing,
        };
        VelocityConstraint { particle: touch.particle, normal: touch.normal, velocity, stick: touch.sticking }
    }

    fn velocity_at(&self, link: &Link) -> Vec3 {
        let (linear, angular) = self.bodies[link.body].velocity;
        linear + angular.cross(link.lever) + link.closing
    }

    /// Free body `b`'s state after the step, if some constraint held particles on it,
    /// given the impulses the constraints gave the cloth: their opposites applied to its
    /// state before the step.
    pub fn settled(&self, b: usize, impulses: &[Vec3]) -> Option<BodyCoupling> {
        let body = self.bodies.get(b).filter(|body| body.free)?;
        self.links.iter().flatten().any(|l| l.body == b).then(|| {
            let (impulse, moment) = self.load(b, impulses);
            let (dv, dw) = body.start.velocity_change(-impulse, -moment);
            let (v, w) = body.start.velocity;
            BodyCoupling { velocity: (v + dv, w + dw), ..body.start }
        })
    }

    /// The impulse and moment about the centre [N·s, N·m·s] that body `b`'s constraints
    /// gave the cloth.
    fn load(&self, b: usize, impulses: &[Vec3]) -> (Vec3, Vec3) {
        self.links
            .iter()
            .zip(impulses)
            .filter_map(|(link, impulse)| link.filter(|l| l.body == b).map(|l| (l, impulse)))
            .fold((Vec3::ZERO, Vec3::ZERO), |(total, moment), (link, impulse)| {
                (total + *impulse, moment + link.lever.cross(*impulse))
            })
    }

    /// `1 + W D`, scaled: `D` the step's system between the constrained directions of the
    /// particles on body `b`, moved rigidly with it.
    fn initial_jacobian(
        &self,
        b: usize,
        scale: f32,
        system: StepSystem<'_>,
        constraints: &[VelocityConstraint],
    ) -> Matrix6 {
        let body = &self.bodies[b];
        let directions = |c: &VelocityConstraint| if c.stick { Mat3::IDENTITY } else { outer(c.normal, c.normal) };
        // D = Σ Gᵢᵀ Pᵢ Aᵢⱼ Pⱼ Gⱼ, Gₖ = (1, −[rₖ]×), in blocks (translation, coupling, rotation).
        let (mut t, mut c, mut r) = (Mat3::ZERO, Mat3::ZERO, Mat3::ZERO);
        for (ci, link_i) in constraints.iter().zip(&self.links) {
            let Some(link_i) = link_i.filter(|l| l.body == b) else {
                continue;
            };
            let i = ci.particle as usize;
            system.for_row(i, |j, block| {
                let Ok(k) = constraints.binary_search_by_key(&j, |c| c.particle) else {
                    return;
                };
                let Some(link_j) = self.links[k].filter(|l| l.body == b) else {
                    return;
                };
                let block = directions(ci) * block * directions(&constraints[k]);
                let (skew_i, skew_j) = (skew(link_i.lever), skew(link_j.lever));
                t += block;
                c -= block * skew_j;
                r -= skew_i * block * skew_j;
            });
        }
        let inv_mass = Mat3::from_diagonal(body.start.inv_mass);
        let inv_inertia = body.start.inv_inertia;
        // 1 + W D with W = diag(M⁻¹, I⁻¹), then scaled by (1, L) on the left and (1, 1/L) on
        // the right.
        let blocks = [
            [Mat3::IDENTITY + inv_mass * t, inv_mass * c / scale],
            [scale * inv_inertia * c.transpose(), Mat3::IDENTITY + inv_inertia * r],
        ];
        let mut jacobian = [[0.0; 6]; 6];
        for (row, out) in jacobian.iter_mut().enumerate() {
            for (col, value) in out.iter_mut().enumerate() {
                *value = f64::from(blocks[row / 3][col / 3].col(col % 3)[row % 3]);
            }
        }
        jacobian
    }
}

impl ConstraintBodies for PropCoupling {
    fn rebalance(&mut self, system: StepSystem<'_>, constraints: &mut [VelocityConstraint], impulses: &[Vec3]) -> bool {
        let mut changed = false;
        for b in 0..self.bodies.len() {
            if !self.bodies[b].free {
                continue;
            }
            let key = self.cloth * self.bodies.len() + b;
            let levers = self.links.iter().flatten().filter(|l| l.body == b).map(|l| l.lever.length());
            let Some(furthest) = levers.reduce(f32::max) else {
                self.learned[key] = None;
                continue;
            };
            let (impulse, moment) = self.load(b, impulses);
            if self.learned[key].is_none() {
                let scale = furthest.max(1e-3);
                self.learned[key] = Some((scale, self.initial_jacobian(b, scale, system, constraints)));
            }
            let (scale, jacobian) = self.learned[key].as_mut().expect("set above");
            let body = &mut self.bodies[b];
            let (dv, dw) = body.start.velocity_change(impulse, moment);
            let (v, w) = body.velocity;
            let (v0, w0) = body.start.velocity;
            let unknowns = pack(v, w, *scale);
            let residual = pack(v - v0 + dv, w - w0 + dw, *scale);
            if let Some((last_unknowns, last_residual)) = body.last {
                broyden_update(jacobian, sub(unknowns, last_unknowns), sub(residual, last_residual));
            }
            let Some(step) = solve6(*jacobian, residual.map(|r| -r)) else {
                continue;
            };
            if step.iter().map(|s| s * s).sum::<f64>().sqrt() <= BALANCE_TOLERANCE {
                continue;
            }
            body.last = Some((unknowns, residual));
            let (sv, sw) = unpack(step, *scale);
            body.velocity = (v + sv, w + sw);
            changed = true;
        }
        if changed {
            for (c, link) in constraints.iter_mut().zip(&self.links) {
                if let Some(link) = link {
                    c.velocity = self.velocity_at(link);
                }
            }
        }
        changed
    }
}

fn pack(v: Vec3, w: Vec3, scale: f32) -> Vector6 {
    let w = scale * w;
    [v.x, v.y, v.z, w.x, w.y, w.z].map(f64::from)
}

fn unpack(z: Vector6, scale: f32) -> (Vec3, Vec3) {
    let z = z.map(|z| z as f32);
    (Vec3::new(z[0], z[1], z[2]), Vec3::new(z[3], z[4], z[5]) / scale)
}

fn sub(a: Vector6, b: Vector6) -> Vector6 {
    std::array::from_fn(|k| a[k] - b[k])
}

/// Broyden's ("good") update of `jacobian` from a step `s` that changed the residual by
/// `y`: the least change that makes `jacobian · s = y`.
fn broyden_update(jacobian: &mut Matrix6, s: Vector6, y: Vector6) {
    let ss: f64 = s.iter().map(|s| s * s).sum();
    if ss == 0.0 {
        return;
    }
    for (row, y) in jacobian.iter_mut().zip(y) {
        let miss = y - row.iter().zip(&s).map(|(a, s)| a * s).sum::<f64>();
        for (a, s) in row.iter_mut().zip(&s) {
            *a += miss * s / ss;
        }
    }
}

/// Solves `a z = b` by Gaussian elimination with partial pivoting; none if `a` is singular.
fn solve6(mut a: Matrix6, mut b: Vector6) -> Option<Vector6> {
    for k in 0..6 {
        let pivot = (k..6).max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))?;
        if a[pivot][k] == 0.0 {
            return None;
        }
        a.swap(k, pivot);
        b.swap(k, pivot);
        for i in k + 1..6 {
            let factor = a[i][k] / a[k][k];
            for j in k..6 {
                a[i][j] -= factor * a[k][j];
            }
            b[i] -= factor * b[k];
        }
    }
    let mut z = [0.0; 6];
    for k in (0..6).rev() {
        let rest: f64 = (k + 1..6).map(|j| a[k][j] * z[j]).sum();
        z[k] = (b[k] - rest) / a[k][k];
    }
    Some(z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_elimination_solves_a_pivoting_system() {
        let mut a = [[0.0; 6]; 6];
        for k in 0..6 {
            a[k][(k + 1) % 6] = 1.0 + k as f64;
            a[k][k] = 0.1 * k as f64;
        }
        let z = [1.0, -2.0, 3.0, -4.0, 5.0, -6.0];
        let b = std::array::from_fn(|i| (0..6).map(|j| a[i][j] * z[j]).sum());
        let solved = solve6(a, b).expect("regular");
        assert!(solved.iter().zip(&z).all(|(s, z)| (s - z).abs() < 1e-12), "{solved:?}");
        assert!(solve6([[0.0; 6]; 6], b).is_none());
    }

    #[test]
    fn broyden_finds_a_linear_root_within_twice_the_dimension() {
        // R(z) = A z − c with A far from the initial identity: Broyden's method ends on the
        // root of a linear map in at most 2n steps (Gay, 1979).
        let a: Matrix6 = std::array::from_fn(|i| std::array::from_fn(|j| if i == j { 5.0 + i as f64 } else { 0.7 }));
        let c = [1.0, 0.0, -1.0, 2.0, 0.5, -0.5];
        let residual = |z: Vector6| sub(std::array::from_fn(|i| (0..6).map(|j| a[i][j] * z[j]).sum()), c);
        let mut jacobian: Matrix6 = std::array::from_fn(|i| std::array::from_fn(|j| f64::from(u8::from(i == j))));
        let mut z = [0.0; 6];
        let mut last: Option<(Vector6, Vector6)> = None;
        for _ in 0..12 {
            let r = residual(z);
            if let Some((lz, lr)) = last {
                broyden_update(&mut jacobian, sub(z, lz), sub(r, lr));
            }
            let step = solve6(jacobian, r.map(|r| -r)).expect("regular");
            last = Some((z, r));
            z = std::array::from_fn(|k| z[k] + step[k]);
        }
        let r = residual(z);
        assert!(r.iter().all(|r| r.abs() < 1e-9), "{r:?}");
    }
}
