//! The membrane element: St. Venant–Kirchhoff on a triangle, anisotropic in the warp/weft
//! frame with Zheng's four constants (eq. 2.13):
//! `S = 𝔻 ε`, `𝔻 = [[d₁, d₃, 0], [d₃, d₂, 0], [0, 0, d₄]]`, `ε = (E₁₁, E₂₂, 2E₁₂)` for the
//! Green strain `E = ½(FᵀF − I)`, axis 1 along the warp. The constants are stress resultants
//! per unit strain [N/m] (modulus times thickness).

use glam::{Mat2, Mat3, Mat3A, Vec2, Vec3};

use super::block::upper_map;
use super::spring::outer;

/// Zheng's membrane constants [N/m].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MembraneMaterial {
    /// Warp stiffness 𝔻₁₁.
    pub d1: f32,
    /// Weft stiffness 𝔻₂₂.
    pub d2: f32,
    /// Coupling 𝔻₁₂ (ν times the stiffness, for an isotropic sheet).
    pub d3: f32,
    /// Shear stiffness 𝔻₃₃.
    pub d4: f32,
}

impl MembraneMaterial {
    /// The isotropic plane-stress constants of a sheet with 2-D Young's modulus `e` [N/m]
    /// and Poisson ratio `nu`.
    pub fn isotropic(e: f32, nu: f32) -> Self {
        let c = e / (1.0 - nu * nu);
        Self { d1: c, d2: c, d3: nu * c, d4: 0.5 * (1.0 - nu) * c }
    }

    /// Second Piola–Kirchhoff stress `(S₁₁, S₂₂, S₁₂)` [N/m] for Green strain `(E₁₁, E₂₂, E₁₂)`.
    pub fn stress(&self, e11: f32, e22: f32, e12: f32) -> (f32, f32, f32) {
        (self.d1 * e11 + self.d3 * e22, self.d3 * e11 + self.d2 * e22, self.d4 * 2.0 * e12)
    }
}

/// One triangle's rest state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MembraneElement {
    /// Inverse of the rest edge matrix in warp/weft coordinates [1/m].
    pub rest_inverse: Mat2,
    /// Rest area [m²].
    pub rest_area: f32,
}

/// The deformation of a triangle: the two columns of `F` (the images of the warp and
/// weft unit vectors).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Deformation {
    /// Image of the warp direction.
    pub warp: Vec3,
    /// Image of the weft direction.
    pub weft: Vec3,
}

impl Deformation {
    /// Green strain `(E₁₁, E₂₂, E₁₂)`.
    pub fn green_strain(&self) -> (f32, f32, f32) {
        (
            0.5 * (self.warp.length_squared() - 1.0),
            0.5 * (self.weft.length_squared() - 1.0),
            0.5 * self.warp.dot(self.weft),
        )
    }
}

impl MembraneElement {
    /// The rest state of triangle `x` whose warp runs along `warp` (projected onto the
    /// triangle's plane). `None` for a degenerate triangle or a warp along its normal.
    pub fn from_rest(x: [Vec3; 3], warp: Vec3) -> Option<Self> {
        let (e1, e2) = (x[1] - x[0], x[2] - x[0]);
        let normal = e1.cross(e2);
        let rest_area = 0.5 * normal.length();
        let n = normal.try_normalize()?;
        let u = (warp - warp.dot(n) * n).try_normalize()?;
        let v = n.cross(u);
        let rest = Mat2::from_cols(Vec2::new(e1.dot(u), e1.dot(v)), Vec2::new(e2.dot(u), e2.dot(v)));
        (rest.determinant().abs() > 0.0).then(|| Self { rest_inverse: rest.inverse(), rest_area })
    }

    /// `F` at positions `x`.
    pub fn deformation(&self, x: [Vec3; 3]) -> Deformation {
        let (e1, e2) = (x[1] - x[0], x[2] - x[0]);
        let m = self.rest_inverse;
        Deformation { warp: e1 * m.x_axis.x + e2 * m.x_axis.y, weft: e1 * m.y_axis.x + e2 * m.y_axis.y }
    }

    /// Elastic energy [J].
    pub fn energy(&self, material: &MembraneMaterial, x: [Vec3; 3]) -> f32 {
        let (e11, e22, e12) = self.deformation(x).green_strain();
        let (s11, s22, s12) = material.stress(e11, e22, e12);
        0.5 * self.rest_area * (s11 * e11 + s22 * e22 + s12 * 2.0 * e12)
    }

    /// Gradient of the energy for a first Piola–Kirchhoff stress with columns `p` (warp,
    /// weft), spread to the three vertices.
    fn spread(&self, p: [Vec3; 2]) -> [Vec3; 3] {
        let [_, gamma1, gamma2] = self.shape_gradients();
        let spread = |gamma: Vec2| self.rest_area * (p[0] * gamma.x + p[1] * gamma.y);
        let (g1, g2) = (spread(gamma1), spread(gamma2));
        // The first vertex's share from the other two, as its shape gradient is theirs negated.
        [-(g1 + g2), g1, g2]
    }

    /// Forces on the three vertices [N].
    pub fn forces(&self, material: &MembraneMaterial, x: [Vec3; 3]) -> [Vec3; 3] {
        let f = self.deformation(x);
        self.forces_at(&f, Self::stress_at(material, &f))
    }

    /// [`MembraneElement::forces`] and [`MembraneElement::position_jacobian`] from one
    /// deformation and stress, the same bits as each: what an implicit step's assembly
    /// needs of every triangle.
    pub fn forces_and_jacobian(
        &self,
        material: &MembraneMaterial,
        x: [Vec3; 3],
        definite: bool,
    ) -> ([Vec3; 3], [Mat3; 6]) {
        let f = self.deformation(x);
        let stress = Self::stress_at(material, &f);
        (self.forces_at(&f, stress), self.jacobian_at(material, &f, stress, definite))
    }

    /// The second Piola–Kirchhoff stress `(S₁₁, S₂₂, S₁₂)` at deformation `f`.
    fn stress_at(material: &MembraneMaterial, f: &Deformation) -> (f32, f32, f32) {
        let (e11, e22, e12) = f.green_strain();
        material.stress(e11, e22, e12)
    }

    /// The forces at deformation `f` under `stress`.
    fn forces_at(&self, f: &Deformation, (s11, s22, s12): (f32, f32, f32)) -> [Vec3; 3] {
        let p = [f.warp * s11 + f.weft * s12, f.warp * s12 + f.weft * s22];
        self.spread(p).map(|g| -g)
    }

    /// The gradients `γ_a` of the three linear shape functions in warp/weft coordinates
    /// [1/m]: `F = Σ_a x_a γ_aᵀ`.
    fn shape_gradients(&self) -> [Vec2; 3] {
        let m = self.rest_inverse;
        let (g1, g2) = (m.row(0), m.row(1));
        [-(g1 + g2), g1, g2]
    }

    /// The 3×3 blocks `∂f_a/∂x_b` [N/m], exact when `definite` is false. When `definite`,
    /// the stress in the geometric term is replaced by its positive part, which makes the
    /// blocks negative semi-definite (the material term already is for a positive 𝔻).
    ///
    /// In closed form, `∂f_a/∂x_b = −A ((γ_aᵀ S γ_b) I + F C_ab Fᵀ)`, where the material
    /// term's 2×2 `C_ab` maps `Fᵀ δx` to the change of `S γ_a` that moving `x_b` by `δx`
    /// causes through `𝔻`. Block `(b, a)` is block `(a, b)` transposed, so only the blocks
    /// on and above the diagonal are formed, in [`upper_pairs`](super::block::upper_pairs) order.
    pub fn position_jacobian(&self, material: &MembraneMaterial, x: [Vec3; 3], definite: bool) -> [Mat3; 6] {
        let f = self.deformation(x);
        self.jacobian_at(material, &f, Self::stress_at(material, &f), definite)
    }

    /// The blocks at deformation `f` under `stress`.
    fn jacobian_at(
        &self,
        material: &MembraneMaterial,
        f: &Deformation,
        (s11, s22, s12): (f32, f32, f32),
        definite: bool,
    ) -> [Mat3; 6] {
        let (g11, g22, g12) = if definite { positive_part(s11, s22, s12) } else { (s11, s22, s12) };
        let MembraneMaterial { d1, d2, d3, d4 } = *material;
        // F C Fᵀ = c₀₀ w wᵀ + c₀₁ w fᵀ + c₁₀ f wᵀ + c₁₁ f fᵀ, w and f the warp's and weft's images.
        // In SIMD lanes (`Mat3A`): the same sums in the same order, so the same bits, and
        // the products of the sum below each three lanes wide.
        let (ww, wf, ff) = (outer(f.warp, f.warp), outer(f.warp, f.weft), outer(f.weft, f.weft));
        let (ww, wf, ff) = (Mat3A::from(ww), Mat3A::from(wf), Mat3A::from(ff));
        let fw = wf.transpose();
        let gamma = self.shape_gradients();
        upper_map::<3, 6, _>(|a, b| {
            let (p, q) = (gamma[a], gamma[b]);
            let geometric = p.x * (g11 * q.x + g12 * q.y) + p.y * (g12 * q.x + g22 * q.y);
            let c = [
                d1 * p.x * q.x + d4 * p.y * q.y,
                d3 * p.x * q.y + d4 * p.y * q.x,
                d4 * p.x * q.y + d3 * p.y * q.x,
                d4 * p.x * q.x + d2 * p.y * q.y,
            ];
            let material_term = c[0] * ww + c[1] * wf + c[2] * fw + c[3] * ff;
            Mat3::from(-self.rest_area * (Mat3A::from_diagonal(Vec3::splat(geometric)) + material_term))
        })
    }
}

/// The positive semi-definite part of the symmetric 2×2 tensor `[[a, c], [c, b]]`.
fn positive_part(a: f32, b: f32, c: f32) -> (f32, f32, f32) {
    let mean = 0.5 * (a + b);
    let radius = (0.25 * (a - b) * (a - b) + c * c).sqrt();
    let (l1, l2) = (mean + radius, mean - radius);
    if l2 >= 0.0 {
        return (a, b, c);
    }
    if l1 <= 0.0 {
        return (0.0, 0.0, 0.0);
    }
    // Keep only λ₁ along its eigenvector.
    let v = if c.abs() > f32::EPSILON * radius.max(f32::MIN_POSITIVE) {
        Vec2::new(l1 - b, c).normalize()
    } else if a >= b {
        Vec2::X
    } else {
        Vec2::Y
    };
    (l1 * v.x * v.x, l1 * v.y * v.y, l1 * v.x * v.y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::elements::testing::{assert_close, central_difference, full_blocks};

    const MATERIAL: MembraneMaterial = MembraneMaterial { d1: 300.0, d2: 120.0, d3: 40.0, d4: 60.0 };

    fn element() -> (MembraneElement, [Vec3; 3]) {
        let rest = [Vec3::ZERO, Vec3::new(0.1, 0.0, 0.0), Vec3::new(0.02, 0.09, 0.0)];
        let warp = Vec3::new(1.0, 0.3, 0.0);
        let deformed = [Vec3::new(0.0, 0.01, 0.0), Vec3::new(0.11, -0.01, 0.02), Vec3::new(0.03, 0.085, -0.01)];
        (MembraneElement::from_rest(rest, warp).expect("a proper triangle"), deformed)
    }

    #[test]
    fn a_triangle_at_rest_has_identity_deformation_and_no_energy() {
        let rest = [Vec3::ZERO, Vec3::new(0.1, 0.0, 0.0), Vec3::new(0.02, 0.09, 0.0)];
        let e = MembraneElement::from_rest(rest, Vec3::X).expect("a proper triangle");
        let f = e.deformation(rest);
        assert!((f.warp - Vec3::X).length() < 1e-6 && (f.weft - Vec3::Y).length() < 1e-6);
        assert!(e.energy(&MATERIAL, rest).abs() < 1e-9);
        assert!((e.rest_area - 0.0045).abs() < 1e-7);
    }

    #[test]
    fn uniaxial_warp_stretch_gives_the_warp_stress() {
        // Stretch 1 % along the warp with the weft held: S₁₁ = d₁ E₁₁, S₂₂ = d₃ E₁₁.
        let rest = [Vec3::ZERO, Vec3::new(0.1, 0.0, 0.0), Vec3::new(0.0, 0.1, 0.0)];
        let e = MembraneElement::from_rest(rest, Vec3::X).expect("a proper triangle");
        let stretched = rest.map(|p| Vec3::new(1.01 * p.x, p.y, p.z));
        let (e11, e22, e12) = e.deformation(stretched).green_strain();
        assert!((e11 - 0.5 * (1.01f32 * 1.01 - 1.0)).abs() < 1e-6 && e22.abs() < 1e-7 && e12.abs() < 1e-7);
        let (s11, s22, _) = MATERIAL.stress(e11, e22, e12);
        assert!((s11 - 300.0 * e11).abs() < 1e-4 && (s22 - 40.0 * e11).abs() < 1e-4);
    }

    #[test]
    fn forces_are_minus_the_gradient_of_the_energy() {
        let (e, x) = element();
        let forces = e.forces(&MATERIAL, x);
        for v in 0..3 {
            let numeric = -central_difference(
                |p| {
                    let mut y = x;
                    y[v] = p;
                    e.energy(&MATERIAL, y)
                },
                x[v],
            );
            assert_close(forces[v], numeric, 2e-3, "membrane force");
        }
    }

    #[test]
    fn exact_jacobian_blocks_match_differences_of_the_forces() {
        let (e, x) = element();
        let blocks: [[Mat3; 3]; 3] = full_blocks(&e.position_jacobian(&MATERIAL, x, false));
        for a in 0..3 {
            for b in 0..3 {
                for axis in 0..3 {
                    let numeric = central_difference(
                        |p| {
                            let mut y = x;
                            y[b] = p;
                            e.forces(&MATERIAL, y)[a][axis]
                        },
                        x[b],
                    );
                    assert_close(blocks[a][b].row(axis), numeric, 5e-3, &format!("∂f{a}/∂x{b}"));
                }
            }
        }
    }

    #[test]
    fn the_definite_jacobian_is_negative_semi_definite_under_compression() {
        let rest = [Vec3::ZERO, Vec3::new(0.1, 0.0, 0.0), Vec3::new(0.0, 0.1, 0.0)];
        let e = MembraneElement::from_rest(rest, Vec3::X).expect("a proper triangle");
        let squeezed = rest.map(|p| Vec3::new(0.8 * p.x, 1.05 * p.y, 0.01 * p.x));
        let blocks: [[Mat3; 3]; 3] = full_blocks(&e.position_jacobian(&MATERIAL, squeezed, true));
        // Test random directions in the 9-dimensional space.
        let mut seed = 12345u32;
        let mut random = || {
            seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
            (seed >> 8) as f32 / (1u32 << 24) as f32 - 0.5
        };
        for _ in 0..200 {
            let d: [Vec3; 3] = std::array::from_fn(|_| Vec3::new(random(), random(), random()));
            let quadratic: f32 =
                (0..3).flat_map(|a| (0..3).map(move |b| (a, b))).map(|(a, b)| d[a].dot(blocks[a][b] * d[b])).sum();
            assert!(quadratic <= 1e-4, "positive curvature {quadratic}");
        }
    }
}
