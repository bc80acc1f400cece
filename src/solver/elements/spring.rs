//! The damped spring element: energy `½ k (l − r)²`, force, and its derivative blocks.

use glam::{Mat3, Vec3};

/// One spring's state and constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpringElement {
    /// Rest length [m].
    pub rest: f32,
    /// Stiffness [N/m].
    pub stiffness: f32,
    /// Damping along the spring [N·s/m].
    pub damping: f32,
}

impl SpringElement {
    /// Elastic energy of the spring between `xi` and `xj` [J].
    #[inline]
    pub fn energy(&self, xi: Vec3, xj: Vec3) -> f32 {
        let stretch = (xi - xj).length() - self.rest;
        0.5 * self.stiffness * stretch * stretch
    }

    /// Force on `i` [N] (the force on `j` is its negative), as in Durupınar §3.1.1.1:
    /// `f_i = −[k (|d| − r) + k_d (v_i − v_j)·d̂] d̂` with `d = x_i − x_j`.
    #[inline]
    pub fn force(&self, xi: Vec3, xj: Vec3, vi: Vec3, vj: Vec3) -> Vec3 {
        let d = xi - xj;
        let length = d.length();
        if length <= f32::EPSILON * self.rest {
            return Vec3::ZERO;
        }
        let n = d / length;
        -(self.stiffness * (length - self.rest) + self.damping * (vi - vj).dot(n)) * n
    }

    /// `∂f_i/∂x_i` [N/m] of the elastic force; the local blocks are `[[K, −K], [−K, K]]`.
    /// Exact unless `definite`; then the transverse term is clamped at zero under
    /// compression (Choi & Ko), so that `−K` is positive semi-definite, as conjugate
    /// gradients need. The damping force's dependence on position, `k_d` times the
    /// relative velocity turned with the spring, is left out: it is not symmetric, and the
    /// derivatives are stored symmetric (`SymmetricBlockMatrix`); it vanishes where the
    /// two ends move alike.
    pub fn position_jacobian(&self, xi: Vec3, xj: Vec3, definite: bool) -> Mat3 {
        let d = xi - xj;
        let length = d.length();
        if length <= f32::EPSILON * self.rest {
            return Mat3::ZERO;
        }
        let n = d / length;
        let nn = outer(n, n);
        let ratio = 1.0 - self.rest / length;
        let ratio = if definite { ratio.max(0.0) } else { ratio };
        -self.stiffness * (nn + ratio * (Mat3::IDENTITY - nn))
    }

    /// `∂f_i/∂v_i` [N·s/m] = `−k_d d̂ d̂ᵀ`; the local blocks are `[[D, −D], [−D, D]]`.
    pub fn velocity_jacobian(&self, xi: Vec3, xj: Vec3) -> Mat3 {
        let n = (xi - xj).normalize_or_zero();
        -self.damping * outer(n, n)
    }
}

/// The outer product `a bᵀ`.
#[inline]
pub fn outer(a: Vec3, b: Vec3) -> Mat3 {
    Mat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// The matrix of `r ×`: `skew(r) u = r × u`.
#[inline]
pub fn skew(r: Vec3) -> Mat3 {
    Mat3::from_cols(Vec3::new(0.0, r.z, -r.y), Vec3::new(-r.z, 0.0, r.x), Vec3::new(r.y, -r.x, 0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::elements::testing::{assert_close, central_difference};

    const SPRING: SpringElement = SpringElement { rest: 0.8, stiffness: 30.0, damping: 0.7 };

    #[test]
    fn force_is_minus_the_gradient_of_the_energy() {
        let (xi, xj) = (Vec3::new(0.3, -0.2, 0.9), Vec3::new(-0.4, 0.1, 0.2));
        let numeric = -central_difference(|x| SPRING.energy(x, xj), xi);
        assert_close(SPRING.force(xi, xj, Vec3::ZERO, Vec3::ZERO), numeric, 1e-3, "elastic force");
    }

    /// ∂f/∂x where both ends move alike, so that only the elastic force depends on
    /// position; ∂f/∂v, which does not depend on velocity, where they do not.
    #[test]
    fn jacobians_match_differences_of_the_force_stretched_and_compressed() {
        let (vi, vj) = (Vec3::new(0.5, -1.0, 0.2), Vec3::new(-0.3, 0.4, 0.1));
        for xj in [Vec3::new(-0.4, 0.1, 0.2), Vec3::new(0.1, -0.1, 0.7)] {
            let xi = Vec3::new(0.3, -0.2, 0.9);
            let k = SPRING.position_jacobian(xi, xj, false);
            for axis in 0..3 {
                let numeric = central_difference(|x| SPRING.force(x, xj, vi, vi)[axis], xi);
                assert_close(k.row(axis), numeric, 1e-3, "∂f/∂x");
                let numeric = central_difference(|v| SPRING.force(xi, xj, v, vj)[axis], vi);
                assert_close(SPRING.velocity_jacobian(xi, xj).row(axis), numeric, 1e-3, "∂f/∂v");
            }
        }
    }

    #[test]
    fn the_definite_jacobian_has_no_positive_eigenvalue_under_compression() {
        let (xi, xj) = (Vec3::new(0.3, 0.0, 0.0), Vec3::ZERO);
        let k = SPRING.position_jacobian(xi, xj, true);
        for direction in [Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE.normalize()] {
            assert!(direction.dot(k * direction) <= 1e-6);
        }
        let exact = SPRING.position_jacobian(xi, xj, false);
        assert!(Vec3::Y.dot(exact * Vec3::Y) > 0.0, "the exact one is indefinite there");
    }
}
