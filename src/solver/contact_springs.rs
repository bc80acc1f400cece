//! Cloth–cloth contact inside the implicit solve: each pair of primitives closer than its
//! separation at the start of a step pushes its sides apart with a spring along the pair's
//! normal, whose stiffness enters the step's matrix and couples the pair's four vertices.
//!
//! Friction enters the same solve, as a damper across the normal whose coefficient is
//! lagged from the step before (IPC's lagged friction): Coulomb's force where the pair
//! slides, a stiff damper that holds it where it barely moves.
//!
//! The contact stage after the step ([`crate::collision::self_contact`]) stops a vertex
//! that the solve carried into another layer, but the solve moved it there together with
//! its neighbours, and stopping that vertex alone stores the work it undid as strain,
//! which the next step releases: a stiff heap gained energy step after step. A spring in
//! the solve stops the pair while the membrane is solved for, and passes each layer's
//! weight to the layer below within the step (a velocity held along the normal did not,
//! and propped piles up). The contact stage stays as the backstop.

use glam::{Mat3, Vec3};

use super::elements::spring::outer;
use super::elements::{BlockMatrix, BlockPattern};

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

/// A pair of primitives of one cloth held apart in the implicit step: its distance along
/// `normal` is pushed towards `gap`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSpring {
    /// The pair.
    pub stencil: Stencil,
    /// Unit normal from the second side to the first at the start of the step.
    pub normal: Vec3,
    /// The separation the pair keeps [m].
    pub gap: f32,
    /// Stiffness [N/m].
    pub stiffness: f32,
    /// Friction, as a damping coefficient of the pair's relative velocity across the
    /// normal [N·s/m].
    pub drag: f32,
}

impl ContactSpring {
    /// The force on the pair's first side at `(x, v)`: the spring's push, `k (gap − d) n`,
    /// and friction, `−c (I − n nᵀ) v_rel`. Vertex `k` takes `w_k` times it.
    fn force(&self, x: &[Vec3], v: &[Vec3]) -> Vec3 {
        let velocity = self.stencil.relative(v);
        self.stiffness * (self.gap - self.stencil.relative(x).dot(self.normal)) * self.normal
            - self.drag * (velocity - velocity.dot(self.normal) * self.normal)
    }
}

/// Adds the springs' forces at `(x, v)` to `force`.
pub fn add_forces(springs: &[ContactSpring], x: &[Vec3], v: &[Vec3], force: &mut [Vec3]) {
    for s in springs {
        let push = s.force(x, v);
        for k in 0..4 {
            force[s.stencil.vertices[k] as usize] += s.stencil.weights[k] * push;
        }
    }
}

/// Which blocks of the springs' stiffness a product uses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Blocks {
    /// All of them.
    All,
    /// Those off the diagonal: the diagonal ones are in the matrix ([`add_diagonal`]).
    OffDiagonal,
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
    /// The pair's block `(w_a w_b)`-free part: `a k n nᵀ + b c (I − n nᵀ)`.
    fn block(&self, weights: Weights) -> Mat3 {
        let normal = outer(self.normal, self.normal);
        (weights.stiffness * self.stiffness) * normal + (weights.drag * self.drag) * (Mat3::IDENTITY - normal)
    }
}

/// `out += (a K + b C) y` for `weights` `(a, b)`, or its off-diagonal blocks alone.
/// Serial, pair by pair in order: the same sums on any number of threads.
pub fn add_product(springs: &[ContactSpring], weights: Weights, blocks: Blocks, y: &[Vec3], out: &mut [Vec3]) {
    for s in springs {
        let block = s.block(weights);
        let total = s.stencil.relative(y);
        for k in 0..4 {
            let i = s.stencil.vertices[k] as usize;
            let others = if blocks == Blocks::OffDiagonal { total - s.stencil.weights[k] * y[i] } else { total };
            out[i] += s.stencil.weights[k] * (block * others);
        }
    }
}

/// Adds the diagonal blocks of `a K + b C`, `w_k² (a k n nᵀ + b c (I − n nᵀ))`, to `matrix`.
pub fn add_diagonal(springs: &[ContactSpring], weights: Weights, pattern: &BlockPattern, matrix: &mut BlockMatrix) {
    for s in springs {
        let block = s.block(weights);
        for k in 0..4 {
            matrix.blocks[pattern.diagonal_slot(s.stencil.vertices[k] as usize)] +=
                s.stencil.weights[k] * s.stencil.weights[k] * block;
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
            drag: 0.3,
        };
        (s, x)
    }

    #[test]
    fn the_forces_push_the_sides_apart_and_rub_against_sliding_with_no_net_force() {
        let (s, x) = spring();
        // The vertex slides at 0.5 m/s along x over the resting triangle, and approaches it.
        let v = vec![Vec3::new(0.5, -0.2, 0.0), Vec3::ZERO, Vec3::ZERO, Vec3::ZERO];
        let mut force = vec![Vec3::ZERO; 4];
        add_forces(&[s], &x, &v, &mut force);
        // k (δ − d) = 50 · 0.001 = 0.05 N on the vertex, up; friction −c v_t = −0.15 N along
        // x; no damping along the normal.
        assert!((force[0] - Vec3::new(-0.15, 0.05, 0.0)).length() < 1e-6, "{}", force[0]);
        assert!(force[1..].iter().all(|f| f.y < 0.0 && f.x > 0.0));
        assert!(force.iter().sum::<Vec3>().length() < 1e-7);
    }

    #[test]
    fn stiffness_and_friction_are_minus_the_derivatives_of_the_forces_and_split_into_diagonal_and_rest() {
        let (s, x) = spring();
        let y = vec![Vec3::new(0.3, -1.0, 0.2), Vec3::new(0.1, 0.4, 0.0), Vec3::new(-0.2, 0.7, 1.0), Vec3::Y];
        let v = vec![Vec3::ZERO; 4];
        // −(f(x + εy) − f(x)) / ε and −(f(v + εy) − f(v)) / ε: the forces are linear.
        let eps = 1e-3;
        let moved: Vec<Vec3> = x.iter().zip(&y).map(|(x, y)| *x + eps * *y).collect();
        let (mut f0, mut fx, mut fv) = (vec![Vec3::ZERO; 4], vec![Vec3::ZERO; 4], vec![Vec3::ZERO; 4]);
        add_forces(&[s], &x, &v, &mut f0);
        add_forces(&[s], &moved, &v, &mut fx);
        add_forces(&[s], &x, &moved.iter().zip(&x).map(|(m, x)| *m - *x).collect::<Vec<_>>(), &mut fv);
        let weights = Weights { stiffness: 0.7, drag: 0.2 };
        let mut product = vec![Vec3::ZERO; 4];
        add_product(&[s], weights, Blocks::All, &y, &mut product);
        for k in 0..4 {
            let numeric = -(0.7 * (fx[k] - f0[k]) + 0.2 * (fv[k] - f0[k])) / eps;
            assert!((product[k] - numeric).length() < 1e-3 * numeric.length().max(1.0), "{k}");
        }
        // Diagonal blocks in a matrix plus the off-diagonal product give the whole.
        let pattern = BlockPattern::from_stencils(4, std::iter::empty());
        let mut matrix = BlockMatrix::default();
        matrix.reset(&pattern);
        add_diagonal(&[s], weights, &pattern, &mut matrix);
        let mut split = vec![Vec3::ZERO; 4];
        matrix.multiply(&pattern, &y, &mut split);
        add_product(&[s], weights, Blocks::OffDiagonal, &y, &mut split);
        for k in 0..4 {
            assert!((split[k] - product[k]).length() < 1e-5, "{k}");
        }
    }
}
