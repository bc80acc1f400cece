//! The bending element: a hinge over an interior edge with the dihedral angle θ between
//! its two triangles (discrete shells), and a moment–curvature law: linear `m = B κ` or
//! Zheng's nonlinear law (eq. 2.14). Curvature is `κ = (θ − θ₀) / d` where `d` is the
//! hinge's width `(A₁ + A₂) / |e|`, and the energy is `(A₁ + A₂) W(κ)`, so that a grid bent
//! into a cylinder stores exactly `½ B κ²` per unit area.
//!
//! Vertex order `[o₁, o₂, i, j]`: `o₁` opposite the edge in the triangle that runs `i → j`
//! counter-clockwise, `o₂` in the other one.

use glam::{Mat3, Vec3};

use super::dual::{Dual, Real, V3};
use super::spring::outer;

/// A moment–curvature law `m(κ)` per unit width, through its energy density `W(κ)`
/// [J/m²] with `W′ = m`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BendingLaw {
    /// `m = B κ`: linear elastic bending with rigidity `B` [N·m] (per hinge, below).
    Linear,
    /// Zheng's law (eq. 2.14, after Abbott): `m = 2 B₀ √(κ₀ |κ|)` up to `κ₀`, then
    /// `B₀ (|κ| + κ₀)`. Its slope is infinite at zero, so below `κ_r` it is replaced by the
    /// linear law that meets it there (`B_r = 2 B₀ √(κ₀ / κ_r)`), keeping `m` continuous.
    Zheng {
        /// Knee curvature κ₀ [1/m] (30 in all of Zheng's examples).
        kappa0: f32,
        /// Regularisation curvature κ_r [1/m], below which the law is linear.
        kappa_r: f32,
    },
}

impl BendingLaw {
    /// `(W, W′, W″)` at curvature `kappa` for rigidity `b` (B for linear, B₀ for Zheng).
    pub fn density(self, b: f32, kappa: f32) -> (f32, f32, f32) {
        match self {
            BendingLaw::Linear => (0.5 * b * kappa * kappa, b * kappa, b),
            BendingLaw::Zheng { kappa0, kappa_r } => {
                let (k, sign) = (kappa.abs(), kappa.signum());
                let b_r = 2.0 * b * (kappa0 / kappa_r).sqrt();
                let w_r = 0.5 * b_r * kappa_r * kappa_r;
                let root_part = |k: f32| 4.0 / 3.0 * b * kappa0.sqrt() * k.powf(1.5);
                if k <= kappa_r {
                    (0.5 * b_r * k * k, b_r * kappa, b_r)
                } else if k <= kappa0 {
                    let w = w_r + root_part(k) - root_part(kappa_r);
                    (w, sign * 2.0 * b * (kappa0 * k).sqrt(), b * (kappa0 / k).sqrt())
                } else {
                    let w0 = w_r + root_part(kappa0) - root_part(kappa_r);
                    let w = w0 + b * (0.5 * (k * k - kappa0 * kappa0) + kappa0 * (k - kappa0));
                    (w, sign * b * (k + kappa0), b)
                }
            }
        }
    }
}

/// One hinge's constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HingeElement {
    /// Rest dihedral angle θ₀ [rad].
    pub rest_angle: f32,
    /// Rigidity across this hinge [N·m]: `B` (linear) or `B₀` (Zheng), interpolated
    /// between warp and weft by the direction of bending.
    pub rigidity: f32,
    /// Summed rest area of the two triangles [m²].
    pub area: f32,
    /// Rest width `area / |e|` [m].
    pub width: f32,
}

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

impl HingeElement {
    fn curvature(&self, theta: f32) -> f32 {
        (theta - self.rest_angle) / self.width
    }

    /// Bending energy [J].
    pub fn energy(&self, law: BendingLaw, x: [Vec3; 4]) -> f32 {
        let kappa = self.curvature(dihedral_angle(x.map(to_v3)));
        self.area * law.density(self.rigidity, kappa).0
    }

    /// Forces on the four vertices [N].
    pub fn forces(&self, law: BendingLaw, x: [Vec3; 4]) -> [Vec3; 4] {
        let p = x.map(to_v3);
        let kappa = self.curvature(dihedral_angle(p));
        let moment = law.density(self.rigidity, kappa).1;
        let scale = -self.area * moment / self.width;
        dihedral_gradient(p).map(|g| scale * from_v3(g))
    }

    /// The 4×4 blocks `∂f_a/∂x_b` [N/m]. Exact when `definite` is false (the angle's own
    /// second derivative comes from forward differentiation of its gradient); when
    /// `definite`, only the Gauss–Newton part `−A W″/d² ∇θ ∇θᵀ` is kept, which is
    /// negative semi-definite for any law with `W″ ≥ 0`.
    pub fn position_jacobian(&self, law: BendingLaw, x: [Vec3; 4], definite: bool) -> [[Mat3; 4]; 4] {
        let p = x.map(to_v3);
        let kappa = self.curvature(dihedral_angle(p));
        let (_, moment, tangent) = law.density(self.rigidity, kappa);
        let gradient = dihedral_gradient(p).map(from_v3);
        let gauss_newton = -self.area * tangent / (self.width * self.width);
        let mut blocks = [[Mat3::ZERO; 4]; 4];
        for a in 0..4 {
            for b in 0..4 {
                blocks[a][b] = gauss_newton * outer(gradient[a], gradient[b]);
            }
        }
        if definite {
            return blocks;
        }
        // The curvature term −A W′/d ∂²θ/∂x², one column (vertex b, axis k) at a time.
        let scale = -self.area * moment / self.width;
        for b in 0..4 {
            for k in 0..3 {
                let seeded = std::array::from_fn(|v| {
                    V3(std::array::from_fn(|c| Dual::new(x[v][c], if v == b && c == k { 1.0 } else { 0.0 })))
                });
                let column = dihedral_gradient::<Dual>(seeded);
                for (a, g) in column.iter().enumerate() {
                    let derivative = Vec3::new(g.0[0].derivative, g.0[1].derivative, g.0[2].derivative);
                    *blocks[a][b].col_mut(k) += scale * derivative;
                }
            }
        }
        blocks
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::elements::testing::{assert_close, central_difference};

    /// A bent, skewed hinge: edge along roughly +X, wings at different heights.
    fn hinge_positions() -> [Vec3; 4] {
        [Vec3::new(0.4, 0.9, 0.2), Vec3::new(0.6, -0.8, 0.5), Vec3::new(0.0, 0.05, 0.0), Vec3::new(1.0, -0.05, 0.1)]
    }

    fn element() -> HingeElement {
        HingeElement { rest_angle: 0.1, rigidity: 2e-3, area: 0.9, width: 0.45 }
    }

    const LAWS: [BendingLaw; 2] = [BendingLaw::Linear, BendingLaw::Zheng { kappa0: 30.0, kappa_r: 0.3 }];

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
    fn forces_are_minus_the_gradient_of_the_energy_for_both_laws() {
        let x = hinge_positions();
        for law in LAWS {
            let forces = element().forces(law, x);
            for v in 0..4 {
                let numeric = -central_difference(
                    |p| {
                        let mut y = x;
                        y[v] = p;
                        element().energy(law, y)
                    },
                    x[v],
                );
                assert_close(forces[v], numeric, 2e-3, &format!("{law:?} force"));
            }
        }
    }

    #[test]
    fn exact_jacobian_blocks_match_differences_of_the_forces() {
        let x = hinge_positions();
        for law in LAWS {
            let blocks = element().position_jacobian(law, x, false);
            for a in 0..4 {
                for b in 0..4 {
                    for axis in 0..3 {
                        let numeric = central_difference(
                            |p| {
                                let mut y = x;
                                y[b] = p;
                                element().forces(law, y)[a][axis]
                            },
                            x[b],
                        );
                        assert_close(blocks[a][b].row(axis), numeric, 5e-3, &format!("{law:?} ∂f{a}/∂x{b}"));
                    }
                }
            }
        }
    }

    #[test]
    fn zheng_law_is_continuous_with_the_published_moments() {
        let law = BendingLaw::Zheng { kappa0: 30.0, kappa_r: 0.3 };
        let b0 = 3.3e-3;
        // m(κ₀) = 2 B₀ κ₀ from both sides; m(2κ₀) = 3 B₀ κ₀; m(κ₀/4) = B₀ κ₀.
        assert!((law.density(b0, 30.0).1 - 2.0 * b0 * 30.0).abs() < 1e-6);
        assert!((law.density(b0, 30.001).1 - 2.0 * b0 * 30.0).abs() < 1e-4);
        assert!((law.density(b0, 60.0).1 - 3.0 * b0 * 30.0).abs() < 1e-6);
        assert!((law.density(b0, -7.5).1 + b0 * 30.0).abs() < 1e-6);
        // Continuous energy and moment at the regularisation point: across a step of 2δ the
        // energy changes by 2δ·m and the moment by about 2δ·W″.
        let delta = 1e-5;
        let (below, above) = (law.density(b0, 0.3 - delta), law.density(b0, 0.3 + delta));
        assert!(((above.0 - below.0) - 2.0 * delta * below.1).abs() < 1e-8, "energy jumps: {below:?} {above:?}");
        assert!((above.1 - below.1).abs() < 4.0 * delta * below.2, "moment jumps: {below:?} {above:?}");
    }
}
