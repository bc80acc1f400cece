//! Anisotropic bending of a triangle surface from per-triangle shape operators (Gingold et
//! al. 2004, after Grinspun's discrete shells). Each triangle estimates its curvature from
//! the dihedral angles of its interior edges,
//! `κ = Σₑ (θₑ − θ₀ₑ) ℓₑ / (2A) · mₑ ⊗ mₑ` (mₑ the in-plane normal of edge e),
//! written in the warp/weft frame as `(κ₁₁, κ₂₂, 2κ₁₂)`, and stores `A W(κ)` with
//! `W = W_warp(κ₁₁) + W_weft(κ₂₂) + ½ D_t (2κ₁₂)²`. Because the hinges of a triangle are
//! coupled through κ, a fold along a diagonal pays for the curvature it really makes in
//! every direction, which keeps grids with diagonals from bending too easily (independent
//! hinges made a cantilever strip 25 % too soft). A cylinder bent on any mesh whose edges
//! follow its generators stores exactly `½ B κ² A`.

use glam::{Mat3, Vec3};
use rayon::prelude::*;

use super::block::upper_map;
use super::hinge::{dihedral_hessian, hinge_angle, hinge_gradient};
use super::spring::outer;
use crate::solver::PARALLEL_MIN_LEN;

/// No hinge on this side of a face (a boundary edge).
pub const NO_HINGE: u32 = u32::MAX;

/// A moment–curvature law `m(κ)` per unit width, through its energy density `W(κ)`
/// [J/m²] with `W′ = m`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BendingLaw {
    /// `m = B κ`: linear elastic bending with rigidity `B` [N·m] (per hinge, below).
    Linear,
    /// Zheng's law (eq. 2.14, after Abbott): `m = 2 B₀ √(κ₀ |κ|)` up to `κ₀`, then
    /// `B₀ (|κ| + κ₀)`. Its slope is infinite at zero, so below `κ_r` it is replaced by the
    /// odd cubic `m = 2.5 S κ − S κ³ / (2 κ_r²)`, `S = B₀ √(κ₀ / κ_r)`, which meets it at
    /// `κ_r` with the same moment and slope (so the Jacobian is continuous too).
    Zheng {
        /// Knee curvature κ₀ [1/m] (30 in all of Zheng's examples).
        kappa0: f32,
        /// Regularisation curvature κ_r [1/m], below which the law is the cubic.
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
                let slope = b * (kappa0 / kappa_r).sqrt();
                let cubic = |k: f32| 1.25 * slope * k * k - slope * k.powi(4) / (8.0 * kappa_r * kappa_r);
                let root_part = |k: f32| 4.0 / 3.0 * b * kappa0.sqrt() * k.powf(1.5);
                if k <= kappa_r {
                    let moment = 2.5 * slope * k - slope * k.powi(3) / (2.0 * kappa_r * kappa_r);
                    (cubic(k), sign * moment, 2.5 * slope - 1.5 * slope * k * k / (kappa_r * kappa_r))
                } else if k <= kappa0 {
                    let w = cubic(kappa_r) + root_part(k) - root_part(kappa_r);
                    (w, sign * 2.0 * b * (kappa0 * k).sqrt(), b * (kappa0 / k).sqrt())
                } else {
                    let w0 = cubic(kappa_r) + root_part(kappa0) - root_part(kappa_r);
                    let w = w0 + b * (0.5 * (k * k - kappa0 * kappa0) + kappa0 * (k - kappa0));
                    (w, sign * b * (k + kappa0), b)
                }
            }
        }
    }
}

/// Bending rigidities per unit width [N·m] (`B₀` for Zheng's law).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BendingRigidity {
    /// For curvature along the warp.
    pub warp: f32,
    /// For curvature along the weft.
    pub weft: f32,
    /// Twist rigidity D_t for `½ D_t (2κ₁₂)²`; `½ √(B_warp B_weft)` makes an isotropic
    /// sheet (Poisson 0) rotation invariant.
    pub twist: f32,
}

impl BendingRigidity {
    /// `(W, ∂W/∂κ, ∂²W/∂κ²)` at curvature `kappa = (κ₁₁, κ₂₂, 2κ₁₂)`; the second
    /// derivative is diagonal.
    pub fn density(&self, law: BendingLaw, kappa: Vec3) -> (f32, Vec3, Vec3) {
        let (w1, m1, t1) = law.density(self.warp, kappa.x);
        let (w2, m2, t2) = law.density(self.weft, kappa.y);
        let twist = self.twist * kappa.z;
        (w1 + w2 + 0.5 * twist * kappa.z, Vec3::new(m1, m2, twist), Vec3::new(t1, t2, self.twist))
    }
}

/// A triangle of the surface that bends: the hinges on its sides and how their angles
/// make its curvature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BendingFace {
    /// Hinge on each side, or [`NO_HINGE`].
    pub hinges: [u32; 3],
    /// `ℓₑ / (2A) · (m₁², m₂², 2m₁m₂)` for each side [1/m].
    pub coefficients: [Vec3; 3],
    /// Rest area [m²].
    pub area: f32,
    /// The particles its hinges touch (at most 6), padded with the first.
    pub vertices: [u32; 6],
    /// For each side's hinge, where its four vertices are in `vertices`.
    pub corners: [[u8; 4]; 3],
}

impl BendingFace {
    /// Curvature `(κ₁₁, κ₂₂, 2κ₁₂)` [1/m] from the hinges' angles away from rest.
    pub fn curvature(&self, delta: &[f32]) -> Vec3 {
        (0..3)
            .filter(|&k| self.hinges[k] != NO_HINGE)
            .map(|k| self.coefficients[k] * delta[self.hinges[k] as usize])
            .sum()
    }
}

/// The hinges and faces of a bending surface, borrowed for evaluation.
#[derive(Debug, Clone, Copy)]
pub struct BendingSurface<'a> {
    /// `[o₁, o₂, i, j]` of each hinge.
    pub hinges: &'a [[u32; 4]],
    /// Rest angle of each hinge [rad].
    pub rest_angle: &'a [f32],
    /// The faces.
    pub faces: &'a [BendingFace],
    /// The law and rigidities.
    pub law: BendingLaw,
    /// Rigidities.
    pub rigidity: BendingRigidity,
    /// Each hinge's [`quadratic_weights`] while quadratic bending's faces give their
    /// constant Jacobian ([`super::QuadraticBending::assemble`]), else empty.
    pub quadratic: &'a [[f32; 4]],
}

impl BendingSurface<'_> {
    /// Each hinge's angle away from rest [rad], written to `delta`, in parallel.
    pub fn angles(&self, x: &[Vec3], delta: &mut [f32]) {
        delta.par_iter_mut().with_min_len(PARALLEL_MIN_LEN).enumerate().for_each(|(h, d)| {
            *d = self.angle(h, x);
        });
    }

    /// Hinge `h`'s angle away from rest at positions `x` [rad].
    pub fn angle(&self, h: usize, x: &[Vec3]) -> f32 {
        hinge_angle(self.hinges[h].map(|p| x[p as usize])) - self.rest_angle[h]
    }

    /// Energy of face `f` [J].
    pub fn face_energy(&self, f: usize, delta: &[f32]) -> f32 {
        let face = &self.faces[f];
        face.area * self.rigidity.density(self.law, face.curvature(delta)).0
    }

    /// `∂E_f/∂θₑ` for the three sides of face `f` [N·m].
    pub fn face_moments(&self, f: usize, delta: &[f32]) -> [f32; 3] {
        let face = &self.faces[f];
        let (_, moment, _) = self.rigidity.density(self.law, face.curvature(delta));
        std::array::from_fn(|k| face.area * moment.dot(face.coefficients[k]))
    }

    /// Each hinge's angle gradient `∂θ_h/∂x` over its four vertices [1/m], written to
    /// `gradients`, in parallel.
    pub fn gradients(&self, x: &[Vec3], gradients: &mut [[Vec3; 4]]) {
        gradients.par_iter_mut().with_min_len(PARALLEL_MIN_LEN).enumerate().for_each(|(h, g)| {
            *g = hinge_gradient(self.hinges[h].map(|p| x[p as usize]));
        });
    }

    /// Forces of hinge `h` on its four vertices [N] for the summed moment `moment`
    /// `∂E/∂θ_h`.
    pub fn hinge_forces(&self, h: usize, x: &[Vec3], moment: f32) -> [Vec3; 4] {
        hinge_gradient(self.hinges[h].map(|p| x[p as usize])).map(|g| -moment * g)
    }

    /// The Gauss–Newton blocks `−A ∇κᵀ W″ ∇κ` of face `f` over its (up to six) vertices
    /// [N/m], from the hinges' angles away from rest `delta` and their `gradients` (see
    /// [`BendingSurface::gradients`]; each hinge serves two faces, and the forces need them
    /// too): negative semi-definite for any law with `W″ ≥ 0`. Those on and above the
    /// diagonal, in [`upper_pairs`](super::block::upper_pairs) order, are all the symmetric matrix takes; each one
    /// below is its mirror transposed.
    pub fn face_jacobian(&self, f: usize, gradients: &[[Vec3; 4]], delta: &[f32]) -> [Mat3; 21] {
        let face = &self.faces[f];
        let (_, _, tangent) = self.rigidity.density(self.law, face.curvature(delta));
        // ∇κ by vertex: column c of `gradient[a]` is ∂κ_c/∂x_a.
        let mut gradient = [Mat3::ZERO; 6];
        for k in (0..3).filter(|&k| face.hinges[k] != NO_HINGE) {
            let g = gradients[face.hinges[k] as usize];
            for (corner, &local) in face.corners[k].iter().enumerate() {
                gradient[local as usize] += outer(g[corner], face.coefficients[k]);
            }
        }
        // Block (a, b) is −A ∇ₐκ W″ ∇_bκᵀ, and block (b, a) its transpose.
        let weight = Mat3::from_diagonal(-face.area * tangent);
        let weighted = gradient.map(|g| g * weight);
        upper_map::<6, 21, _>(|a, b| weighted[a] * gradient[b].transpose())
    }

    /// The curvature term `−M_h ∂²θ_h/∂x²` of hinge `h` [N/m], which with the faces'
    /// Gauss–Newton blocks makes the exact Jacobian.
    pub fn hinge_curvature_jacobian(&self, h: usize, x: &[Vec3], moment: f32) -> [[Mat3; 4]; 4] {
        dihedral_hessian(self.hinges[h].map(|p| x[p as usize])).map(|row| row.map(|block| -moment * block))
    }

    /// Face `f`'s quadratic weights `wᶜ_v` over its six vertices, `c` = 11, 22 and 2·12
    /// in the warp/weft frame: the face's `κ = Σₑ θₑ cₑ` with each hinge's angle taken as
    /// the vector its [`quadratic_weights`] give, so that `kᶜ = Σ_v wᶜ_v x_v ≈ ±κ_c n`.
    /// The first vertex's weight is minus the others' sum, so that the blocks of a row of
    /// the Jacobian sum to zero (up to their rounding) and a translated cloth feels no
    /// force.
    fn face_weights(&self, f: usize) -> [[f32; 6]; 3] {
        let face = &self.faces[f];
        let mut weights = [[0.0; 6]; 3];
        for k in (0..3).filter(|&k| face.hinges[k] != NO_HINGE) {
            let hinge = self.quadratic[face.hinges[k] as usize];
            for (&slot, w) in face.corners[k].iter().zip(hinge) {
                for (c, row) in weights.iter_mut().enumerate() {
                    row[slot as usize] += face.coefficients[k][c] * w;
                }
            }
        }
        for row in &mut weights {
            row[0] = -row[1..].iter().sum::<f32>();
        }
        weights
    }

    /// The rigidities times the area of face `f`, one to a curvature component [N·m³].
    fn quadratic_stiffness(&self, f: usize) -> Vec3 {
        let r = self.rigidity;
        self.faces[f].area * Vec3::new(r.warp, r.weft, r.twist)
    }

    /// The constant Jacobian of face `f` under quadratic bending, the Hessian of minus its
    /// energy `½ A Σ_c B_c |kᶜ|²` (`kᶜ = Σ_v wᶜ_v x_v`): each block a multiple
    /// `−A Σ_c B_c wᶜ_a wᶜ_b` of the identity for vertices `a` and `b`, those on and above
    /// the diagonal in [`upper_pairs`](super::block::upper_pairs) order; negative
    /// semi-definite, and exact.
    pub fn quadratic_jacobian(&self, f: usize) -> [f32; 21] {
        let (w, b) = (self.face_weights(f), self.quadratic_stiffness(f));
        upper_map::<6, 21, _>(|p, q| -b.dot(Vec3::new(w[0][p] * w[0][q], w[1][p] * w[1][q], w[2][p] * w[2][q])))
    }
}

/// Bergou et al.'s weights of a hinge `[o₁, o₂, i, j]` at rest positions `x` flat across
/// it (2006, eq. 7), divided by the edge's length: for a motion that keeps the two
/// triangles' shapes, `Σ wᵥ xᵥ` is the hinge's angle along the surface normal to second
/// order (its sign that of the crease, whichever triangle comes first), and zero for any
/// motion of the plane. The cotangents of the angles at `i` and `j` each triangle makes
/// with the edge make them. `None` for a degenerate triangle.
pub fn quadratic_weights(x: [Vec3; 4]) -> Option<[f32; 4]> {
    let [o1, o2, i, j] = x;
    let edge = j - i;
    let cot = |u: Vec3, v: Vec3| {
        let sine = u.cross(v).length();
        (sine > 0.0).then(|| u.dot(v) / sine)
    };
    let (at_i1, at_i2) = (cot(edge, o1 - i)?, cot(edge, o2 - i)?);
    let (at_j1, at_j2) = (cot(-edge, o1 - j)?, cot(-edge, o2 - j)?);
    let length = edge.length();
    Some([-at_i1 - at_j1, -at_i2 - at_j2, at_j1 + at_j2, at_i1 + at_i2].map(|w| w / length))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builders::surface::build_bending;
    use crate::components::{BendingDesc, BendingLawDesc};
    use crate::solver::elements::testing::{assert_close, central_difference, full_blocks};

    /// The triangles of a 3 × 3 grid.
    const TRIANGLES: [[u32; 3]; 8] =
        [[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [3, 4, 7], [3, 7, 6], [4, 5, 8], [4, 8, 7]];

    /// The 3 × 3 grid flat at rest, 10 cm cells in the XY plane.
    fn rest() -> Vec<Vec3> {
        (0..9).map(|i| Vec3::new((i % 3) as f32 * 0.1, (i / 3) as f32 * 0.1, 0.0)).collect()
    }

    /// The bending of the grid at `rest` by `law`, the warp a little off X.
    fn bending_of(rest: &[Vec3], law: BendingLawDesc) -> Result<crate::components::BendingHinges, String> {
        let desc = BendingDesc { warp: 2e-3, weft: 1e-3, twist: None, law };
        build_bending(rest, &TRIANGLES, &desc, Vec3::new(1.0, 0.2, 0.0))
    }

    /// The 3 × 3 grid folded and twisted a little, and its bending.
    fn surface(law: BendingLawDesc) -> (Vec<Vec3>, crate::components::BendingHinges) {
        let rest = rest();
        let bending = bending_of(&rest, law).expect("flat");
        let bent = rest
            .iter()
            .enumerate()
            .map(|(i, p)| {
                // A dome (curvatures about 10 and 6 /m, inside Zheng's root branch) with a
                // ripple and a twist, so every hinge and curvature component is engaged.
                let dome = 5.0 * p.x * p.x + 3.0 * p.y * p.y;
                *p + Vec3::new(0.0, 0.0, dome + 0.002 * (p.x * 30.0).sin() + 0.5 * p.x * p.y + 0.0005 * i as f32)
            })
            .collect();
        (bent, bending)
    }

    fn energy(bending: &crate::components::BendingHinges, x: &[Vec3]) -> f32 {
        let view = bending.view();
        let mut delta = vec![0.0; bending.vertices.len()];
        view.angles(x, &mut delta);
        (0..bending.faces.len()).map(|f| view.face_energy(f, &delta)).sum()
    }

    /// Asserts that `forces` at `x` are minus the gradient of `energy`, by central
    /// differences particle by particle.
    fn assert_forces_descend(x: &[Vec3], forces: &[Vec3], energy: impl Fn(&[Vec3]) -> f32, what: &str) {
        for v in 0..x.len() {
            let numeric = -central_difference(
                |p| {
                    let mut y = x.to_vec();
                    y[v] = p;
                    energy(&y)
                },
                x[v],
            );
            assert_close(forces[v], numeric, 3e-3, &format!("{what} force on {v}"));
        }
    }

    /// Adds face `face`'s blocks (all 6 × 6 of them) to the full `jacobian`, each pair of
    /// its distinct vertices once.
    fn add_face(jacobian: &mut [Vec<Mat3>], face: &BendingFace, blocks: &[[Mat3; 6]; 6]) {
        let count = face.vertices.iter().collect::<std::collections::BTreeSet<_>>().len();
        for a in 0..count {
            for b in 0..count {
                jacobian[face.vertices[a] as usize][face.vertices[b] as usize] += blocks[a][b];
            }
        }
    }

    fn forces(bending: &crate::components::BendingHinges, x: &[Vec3]) -> Vec<Vec3> {
        let view = bending.view();
        let mut delta = vec![0.0; bending.vertices.len()];
        view.angles(x, &mut delta);
        let mut moments = vec![0.0; bending.vertices.len()];
        for f in 0..bending.faces.len() {
            for (k, m) in view.face_moments(f, &delta).into_iter().enumerate() {
                if bending.faces[f].hinges[k] != NO_HINGE {
                    moments[bending.faces[f].hinges[k] as usize] += m;
                }
            }
        }
        let mut out = vec![Vec3::ZERO; x.len()];
        for h in 0..bending.vertices.len() {
            for (corner, f) in view.hinge_forces(h, x, moments[h]).into_iter().enumerate() {
                out[bending.vertices[h][corner] as usize] += f;
            }
        }
        out
    }

    const LAWS: [BendingLawDesc; 2] = [BendingLawDesc::Linear, BendingLawDesc::Zheng { kappa0: 30.0 }];

    #[test]
    fn forces_are_minus_the_gradient_of_the_energy() {
        for law in LAWS {
            let (x, bending) = surface(law);
            assert_forces_descend(&x, &forces(&bending, &x), |y| energy(&bending, y), &format!("{law:?}"));
        }
    }

    #[test]
    fn the_exact_jacobian_matches_differences_of_the_forces() {
        for law in LAWS {
            let (x, bending) = surface(law);
            let view = bending.view();
            let n = x.len();
            let mut delta = vec![0.0; bending.vertices.len()];
            view.angles(&x, &mut delta);
            let mut gradients = vec![[Vec3::ZERO; 4]; bending.vertices.len()];
            view.gradients(&x, &mut gradients);
            let mut moments = vec![0.0; bending.vertices.len()];
            let mut jacobian = vec![vec![Mat3::ZERO; n]; n];
            for f in 0..bending.faces.len() {
                let face = &bending.faces[f];
                for (k, m) in view.face_moments(f, &delta).into_iter().enumerate() {
                    if face.hinges[k] != NO_HINGE {
                        moments[face.hinges[k] as usize] += m;
                    }
                }
                add_face(&mut jacobian, face, &full_blocks(&view.face_jacobian(f, &gradients, &delta)));
            }
            for h in 0..bending.vertices.len() {
                let blocks = view.hinge_curvature_jacobian(h, &x, moments[h]);
                for a in 0..4 {
                    for b in 0..4 {
                        jacobian[bending.vertices[h][a] as usize][bending.vertices[h][b] as usize] += blocks[a][b];
                    }
                }
            }
            for a in 0..n {
                for b in 0..n {
                    for axis in 0..3 {
                        let numeric = central_difference(
                            |p| {
                                let mut y = x.clone();
                                y[b] = p;
                                forces(&bending, &y)[a][axis]
                            },
                            x[b],
                        );
                        assert_close(jacobian[a][b].row(axis), numeric, 1e-2, &format!("{law:?} ∂f{a}/∂x{b}"));
                    }
                }
            }
        }
    }

    /// The gentle surface: `surface`'s dome, ripple and twist scaled by `amplitude`.
    fn gentle(law: BendingLawDesc, amplitude: f32) -> (Vec<Vec3>, crate::components::BendingHinges) {
        let (bent, bending) = surface(law);
        (rest().iter().zip(bent).map(|(r, b)| *r + amplitude * (b - *r)).collect(), bending)
    }

    /// The grid's faces (built under the linear law, which keeps them) with each hinge's
    /// quadratic weights at `rest`, as quadratic bending's builder sees them.
    fn quadratic_faces(rest: &[Vec3]) -> (crate::components::BendingHinges, Vec<[f32; 4]>) {
        let faces = bending_of(rest, BendingLawDesc::Linear).expect("flat");
        let weights =
            faces.vertices.iter().map(|h| quadratic_weights(h.map(|v| rest[v as usize])).expect("area")).collect();
        (faces, weights)
    }

    /// The faces' own quadratic energy at `x`, `Σ_f ½ A Σ_c B_c |kᶜ|²` [J], each `kᶜ`
    /// summed over its vertices' offsets from the first: the definition the assembled
    /// Jacobian is checked against.
    fn faces_quadratic_energy(surface: &BendingSurface<'_>, x: &[Vec3]) -> f64 {
        (0..surface.faces.len())
            .map(|f| {
                let (weights, vertices) = (surface.face_weights(f), surface.faces[f].vertices);
                let origin = x[vertices[0] as usize];
                let k = weights
                    .map(|row| (1..6).fold(Vec3::ZERO, |sum, v| sum + row[v] * (x[vertices[v] as usize] - origin)));
                let squares = Vec3::new(k[0].length_squared(), k[1].length_squared(), k[2].length_squared());
                f64::from(0.5 * surface.quadratic_stiffness(f).dot(squares))
            })
            .sum()
    }

    #[test]
    fn the_assembled_quadratic_jacobian_times_the_positions_is_minus_the_faces_energy_gradient() {
        // The forces are `J x` (linear, zero at rest), as the force model forms them, from
        // the builder's assembled diagonal and pairs.
        let (x, bending) = surface(BendingLawDesc::Quadratic);
        assert!(bending.is_quadratic() && bending.faces.is_empty() && bending.vertices.is_empty());
        assert_eq!(bending.hinge_count(), 8, "the 3 × 3 grid's interior edges");
        let quadratic = &bending.quadratic;
        let mut forces: Vec<Vec3> = x.iter().zip(quadratic.diagonal()).map(|(p, &s)| s * *p).collect();
        for (i, j, s) in quadratic.pairs() {
            let (i, j) = (i as usize, j as usize);
            forces[i] += s * x[j];
            forces[j] += s * x[i];
        }
        let (faces, weights) = quadratic_faces(&rest());
        let reference = BendingSurface { quadratic: &weights, ..faces.view() };
        assert_forces_descend(&x, &forces, |y| faces_quadratic_energy(&reference, y) as f32, "quadratic");
        // Its own energy is the faces'.
        let (own, theirs) = (quadratic.energy(&x), faces_quadratic_energy(&reference, &x));
        assert!((own / theirs - 1.0).abs() < 1e-5, "{own:e} J against the faces' {theirs:e} J");
    }

    #[test]
    fn a_flat_sheet_moved_rigidly_far_from_the_origin_stores_no_quadratic_bending() {
        let (rest, bending) = gentle(BendingLawDesc::Quadratic, 0.0);
        let turn = glam::Quat::from_euler(glam::EulerRot::XYZ, 0.7, -1.1, 0.4);
        let moved: Vec<Vec3> = rest.iter().map(|p| turn * *p + Vec3::new(10.0, -5.0, 3.0)).collect();
        // Against the energy of a 1 cm bend, what is left is the positions' own rounding
        // (a millionth of a metre 10 m out) times the scales': 10⁻⁷ of it. Without the
        // rest's sum taken off, the scales' rounding alone left 1.1 × 10⁻⁴.
        let (bent, _) = gentle(BendingLawDesc::Quadratic, 0.05);
        let (left, bend) = (bending.quadratic.energy(&moved), bending.quadratic.energy(&bent));
        assert!(left.abs() < 1e-6 * bend, "{left:e} J against {bend:e} J for the bend");
    }

    #[test]
    fn quadratic_bending_meets_linear_bending_at_second_order_in_the_angles() {
        // The two laws differ by the isometric approximation, so their energies' relative
        // difference falls with the square of the bend: by four when it is halved.
        let difference = |amplitude: f32| {
            let (x, quadratic) = gentle(BendingLawDesc::Quadratic, amplitude);
            let (_, linear) = gentle(BendingLawDesc::Linear, amplitude);
            quadratic.quadratic.energy(&x) / f64::from(energy(&linear, &x)) - 1.0
        };
        // (0.46, 0.11, 0.029, 0.0071 and 0.0018 at 0.4, 0.2, 0.1, 0.05 and 0.025: the
        // surface stretches as it bends, which the isometric measure leaves out.)
        let (coarse, fine) = (difference(0.05), difference(0.025));
        assert!(coarse.abs() < 0.01, "{coarse}");
        let order = (coarse / fine).log2();
        assert!((order - 2.0).abs() < 0.3, "order {order:.2} ({coarse:e} → {fine:e})");
    }

    #[test]
    fn quadratic_bending_refuses_a_curved_rest_shape() {
        let (bent, _) = surface(BendingLawDesc::Linear);
        let error = bending_of(&bent, BendingLawDesc::Quadratic).expect_err("a dome at rest");
        assert!(error.contains("flat at rest") && error.contains("law: Linear"), "{error}");
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
        assert!((above.2 / below.2 - 1.0).abs() < 1e-3, "stiffness jumps: {below:?} {above:?}");
    }
}
