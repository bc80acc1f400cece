//! The geometry of a bending hinge: the signed dihedral angle θ between the two triangles
//! sharing an interior edge, 0 when flat, with its gradient (Bridson et al. 2003) and
//! second derivatives.
//!
//! Vertex order `[o₁, o₂, i, j]`: `o₁` opposite the edge in the triangle that runs `i → j`
//! counter-clockwise, `o₂` in the other one. The sign of θ does not depend on which of the
//! two triangles is taken first, so it is intrinsic to a consistently oriented surface.

use glam::{Mat3, Vec3};

use super::dual::{Dual, Real, V3};

/// Signed dihedral angle of a hinge at `x = [o₁, o₂, i, j]` [rad], 0 when flat.
pub fn dihedral_angle<R: Real>(x: [V3<R>; 4]) -> R {
    let [o1, o2, i, j] = x;
    let e = j - i;
    let n1 = (o1 - i).cross(o1 - j);
    let n2 = (o2 - j).cross(o2 - i);
    let e_length = e.length_squared().sqrt();
    let sin = n2.cross(n1).dot(e) / e_length;
    sin.atan2(n1.dot(n2))
}

/// Gradient of the dihedral angle with respect to the four vertices (Bridson et al.
/// 2003): the bending modes.
pub fn dihedral_gradient<R: Real>(x: [V3<R>; 4]) -> [V3<R>; 4] {
    let [o1, o2, i, j] = x;
    let e = j - i;
    let n1 = (o1 - i).cross(o1 - j);
    let n2 = (o2 - j).cross(o2 - i);
    let e_length = e.length_squared().sqrt();
    let u1 = n1.scale(R::constant(1.0) / n1.length_squared());
    let u2 = n2.scale(R::constant(1.0) / n2.length_squared());
    let along = |p: V3<R>| p.dot(e) / e_length;
    [
        u1.scale(e_length),
        u2.scale(e_length),
        u1.scale(along(o1 - j)) + u2.scale(along(o2 - j)),
        -(u1.scale(along(o1 - i)) + u2.scale(along(o2 - i))),
    ]
}

fn to_v3(p: Vec3) -> V3<f32> {
    V3(p.to_array())
}

fn from_v3(p: V3<f32>) -> Vec3 {
    Vec3::from_array(p.0)
}

/// Second derivatives of the dihedral angle, `∂²θ/∂x_a∂x_b` as 4×4 blocks, by forward
/// differentiation of [`dihedral_gradient`] (the closed form is long).
pub fn dihedral_hessian(x: [Vec3; 4]) -> [[Mat3; 4]; 4] {
    let mut blocks = [[Mat3::ZERO; 4]; 4];
    for b in 0..4 {
        for k in 0..3 {
            let seeded = std::array::from_fn(|v| {
                V3(std::array::from_fn(|c| Dual::new(x[v][c], if v == b && c == k { 1.0 } else { 0.0 })))
            });
            for (a, g) in dihedral_gradient::<Dual>(seeded).iter().enumerate() {
                *blocks[a][b].col_mut(k) = Vec3::new(g.0[0].derivative, g.0[1].derivative, g.0[2].derivative);
            }
        }
    }
    blocks
}

/// The dihedral angle of a hinge at `x` [rad].
pub fn hinge_angle(x: [Vec3; 4]) -> f32 {
    dihedral_angle(x.map(to_v3))
}

/// The gradient of the dihedral angle of a hinge at `x` [1/m].
pub fn hinge_gradient(x: [Vec3; 4]) -> [Vec3; 4] {
    dihedral_gradient(x.map(to_v3)).map(from_v3)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::elements::testing::{assert_close, central_difference};

    /// A bent, skewed hinge: edge along roughly +X, wings at different heights.
    fn hinge_positions() -> [Vec3; 4] {
        [Vec3::new(0.4, 0.9, 0.2), Vec3::new(0.6, -0.8, 0.5), Vec3::new(0.0, 0.05, 0.0), Vec3::new(1.0, -0.05, 0.1)]
    }

    #[test]
    fn a_flat_hinge_has_zero_angle_and_a_folded_one_the_fold_angle() {
        let flat = [Vec3::Y, -Vec3::Y, Vec3::ZERO, Vec3::X].map(to_v3);
        assert!(dihedral_angle(flat).abs() < 1e-6);
        let folded = [Vec3::Y, Vec3::new(0.0, -1.0, 1.0).normalize(), Vec3::ZERO, Vec3::X].map(to_v3);
        assert!((dihedral_angle(folded).abs() - std::f32::consts::FRAC_PI_4).abs() < 1e-5);
    }

    #[test]
    fn the_gradient_matches_differences_of_the_angle() {
        let x = hinge_positions();
        let gradient = dihedral_gradient(x.map(to_v3)).map(from_v3);
        for v in 0..4 {
            let numeric = central_difference(
                |p| {
                    let mut y = x;
                    y[v] = p;
                    dihedral_angle(y.map(to_v3))
                },
                x[v],
            );
            assert_close(gradient[v], numeric, 2e-3, "∂θ/∂x");
        }
    }

    #[test]
    fn the_hessian_matches_differences_of_the_gradient() {
        let x = hinge_positions();
        let hessian = dihedral_hessian(x);
        for a in 0..4 {
            for b in 0..4 {
                for axis in 0..3 {
                    let numeric = central_difference(
                        |p| {
                            let mut y = x;
                            y[b] = p;
                            hinge_gradient(y)[a][axis]
                        },
                        x[b],
                    );
                    assert_close(hessian[a][b].row(axis), numeric, 5e-3, &format!("∂²θ/∂x{a}∂x{b}"));
                }
            }
        }
    }
}
