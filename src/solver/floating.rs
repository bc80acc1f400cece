//! The floating pieces of a step's system: sets of free particles coupled to one another
//! and to no pinned or constrained particle, such as a layer lying loose on another or a
//! cloth in the air. Their stiffness resists no translation, so each piece's translation
//! is a mode of the system held by its mass alone, and where the stiffness outweighs the
//! masses (`h² k / m` in the thousands at a frame-sized step) it is block Gauss–Seidel's
//! slowest: each particle's Newton step is held by its neighbours, which have not moved.
//! Block descent at one step a frame gave a loose layer on a 30° slope 0.0037 m/s of the
//! 0.082 m/s a step its pull asks for along the slope.
//!
//! [`FloatingPieces::correct`] adds to each piece the translation that minimises the
//! step's energy along the piece's three translations, the exact solution of the system
//! restricted to them (a two-level method whose coarse space is those translations): on a
//! piece free of planes it never raises the energy error. A piece pressed against planes
//! (a still layer's or a body's, which bound block descent's sweeps) takes its translation
//! along them only, and the planes' pushes are not residual for it to undo: its
//! translation's part into them is the planes' to bear, within the sweeps. Pieces that
//! touch a pin or a constraint are left out. There a uniform move is not a soft mode, and
//! moving the whole piece would stretch it at what holds it: block descent started from a
//! uniform translation of a pinned sheet peaked at 4.3 % strain against 2.9 %.

use glam::{DMat3, DVec3, Mat3, Vec3};

use super::filter::Filters;
use super::implicit::StepSystem;

/// A piece whose planes' normals all lie within 3° of their mean rests on one plane, and
/// its translations along it are soft; on a curved body (a sheet landing on a sphere) or
/// a crumpled layer they are not, and such a piece is left to the sweeps. (With the
/// planes' pushes in the residual sums, sphere_64 at one step a frame peaked at 0.43
/// strain as it landed, against 0.11, with or without this test; without them, as now,
/// it does not.)
const LEVEL: f64 = 0.9986;

/// No piece: a particle that is not free or whose piece is held.
const NONE: u32 = u32::MAX;

/// The floating pieces of a system and, per piece, what its translation needs, in
/// buffers kept from solve to solve.
#[derive(Debug, Clone, Default)]
pub struct FloatingPieces {
    /// Per particle, its parent in the union of free particles that share a block.
    parent: Vec<u32>,
    /// Per particle, whether its piece touches a particle that is not free (read at the
    /// piece's root).
    held: Vec<bool>,
    /// Per particle, its floating piece, or [`NONE`].
    piece: Vec<u32>,
    /// Per piece, the sum of its blocks (`Σ_ij A_ij`: its translations' matrix), the sum
    /// of its residual, then its translation, and the fraction of it its bounds allow.
    /// The sums are in double precision: a piece's stiffness blocks cancel in them to
    /// leave its mass, some 10⁻⁴ of each at a frame-sized step.
    sums: Vec<(DMat3, DVec3, f32)>,
    /// Per piece, the sum of its particles' planes' normals.
    normals: Vec<DVec3>,
    /// Per piece, whether every particle of it keeps to a plane.
    resting: Vec<bool>,
    /// Per particle of a piece, its column's sum `Σ_i A_ij`, summed in double precision:
    /// a piece's residual sum is `Σ_j (rhs_j − (Σ_i A_ij) delta_j)`, one product a
    /// particle rather than a row's.
    columns: Vec<Mat3>,
}

impl FloatingPieces {
    /// Finds the floating pieces of `system` under `filter`, and sums their blocks.
    pub fn find(&mut self, system: StepSystem<'_>, filter: &Filters) {
        let n = filter.len();
        self.parent.clear();
        self.parent.extend(0..n as u32);
        self.held.clear();
        self.held.resize(n, false);
        for i in 0..n {
            if !filter.is_free(i) {
                continue;
            }
            let (parent, mut held) = (&mut self.parent, false);
            system.for_row(i, |j, _| match filter.is_free(j as usize) {
                true => union(parent, i as u32, j),
                false => held = true,
            });
            self.held[i] |= held;
        }
        for i in 0..n as u32 {
            if self.held[i as usize] {
                let root = root(&mut self.parent, i);
                self.held[root as usize] = true;
            }
        }
        self.piece.clear();
        self.piece.resize(n, NONE);
        self.sums.clear();
        for i in 0..n {
            let root = root(&mut self.parent, i as u32) as usize;
            if !filter.is_free(i) || self.held[root] {
                continue;
            }
            if self.piece[root] == NONE {
                self.piece[root] = self.sums.len() as u32;
                self.sums.push((DMat3::ZERO, DVec3::ZERO, 1.0));
            }
            self.piece[i] = self.piece[root];
        }
        self.columns.clear();
        self.columns.resize(n, Mat3::ZERO);
        for (i, &p) in self.piece.iter().enumerate().filter(|(_, p)| **p != NONE) {
            let mut row = DMat3::ZERO;
            system.for_row(i, |_, block| row += block.as_dmat3());
            self.sums[p as usize].0 += row;
            // The symmetric matrix's column `i` is its row `i` transposed.
            self.columns[i] = row.transpose().as_mat3();
        }
    }

    /// Whether every particle that `cut` picks belongs to a floating piece of which every
    /// particle keeps to a plane (`on_plane`): a piece resting whole on a layer or a body,
    /// whose gap does not shrink as it slides. Uses the pieces of the last
    /// [`FloatingPieces::find`].
    pub fn cut_only_where_resting(&mut self, on_plane: impl Fn(usize) -> bool, cut: impl Fn(usize) -> bool) -> bool {
        self.resting.clear();
        self.resting.resize(self.sums.len(), true);
        for (i, &p) in self.piece.iter().enumerate().filter(|(_, p)| **p != NONE) {
            self.resting[p as usize] &= on_plane(i);
        }
        self.piece.iter().enumerate().all(|(i, &p)| !cut(i) || (p != NONE && self.resting[p as usize]))
    }

    /// Adds to `delta` each floating piece's translation that minimises the energy of
    /// `system · delta = rhs` along it, `t = (Σ_ij A_ij)⁻¹ Σ_i (rhs − A delta)_i`, cut to
    /// the least fraction `allowed(i, delta_i, t)` of its particles allow (their bounds),
    /// so that the whole piece moves together. Where its particles are pressed against
    /// planes (`plane(i, delta_i)`, a unit normal, or zero for none), only along their
    /// mean plane, and without the planes' pushes. Serial,
    /// in particle order: the same sums on any number of threads.
    pub fn correct(
        &mut self,
        rhs: &[Vec3],
        delta: &mut [Vec3],
        plane: impl Fn(usize, Vec3) -> Vec3,
        allowed: impl Fn(usize, Vec3, Vec3) -> f32,
    ) {
        if self.sums.is_empty() {
            return;
        }
        for (_, residual, fraction) in &mut self.sums {
            (*residual, *fraction) = (DVec3::ZERO, 1.0);
        }
        self.normals.clear();
        self.normals.resize(self.sums.len(), DVec3::ZERO);
        for (i, &p) in self.piece.iter().enumerate().filter(|(_, p)| **p != NONE) {
            // A particle pressed against its plane: the residual's part into the plane is
            // the plane's push, which the translation is not to undo.
            let (normal, mut r) = (plane(i, delta[i]), rhs[i] - self.columns[i] * delta[i]);
            r -= normal.dot(r).min(0.0) * normal;
            self.sums[p as usize].1 += r.as_dvec3();
            self.normals[p as usize] += normal.as_dvec3();
        }
        for ((blocks, residual, _), normal) in self.sums.iter_mut().zip(&mut self.normals) {
            // Along the planes: `t = P (P M P + n nᵀ)⁻¹ P s`, `P = I − n nᵀ`, whose part
            // along `n` is zero.
            *normal = normal.normalize_or_zero();
            let n = *normal;
            let along = DMat3::IDENTITY - outer(n);
            let matrix = along * *blocks * along + outer(n);
            *residual =
                if matrix.determinant() > 0.0 { along * (matrix.inverse() * (along * *residual)) } else { DVec3::ZERO };
        }
        for (i, &p) in self.piece.iter().enumerate().filter(|(_, p)| **p != NONE) {
            let (_, translation, fraction) = &mut self.sums[p as usize];
            let normal = plane(i, delta[i]);
            *fraction = if normal != Vec3::ZERO && normal.as_dvec3().dot(self.normals[p as usize]) < LEVEL {
                0.0
            } else {
                fraction.min(allowed(i, delta[i], translation.as_vec3()))
            };
        }
        for (i, &p) in self.piece.iter().enumerate().filter(|(_, p)| **p != NONE) {
            let (_, translation, fraction) = self.sums[p as usize];
            delta[i] += fraction * translation.as_vec3();
        }
    }
}

/// `n nᵀ`.
fn outer(n: DVec3) -> DMat3 {
    DMat3::from_cols(n * n.x, n * n.y, n * n.z)
}

/// The root of `k`'s set, halving the path on the way.
fn root(parent: &mut [u32], mut k: u32) -> u32 {
    while parent[k as usize] != k {
        parent[k as usize] = parent[parent[k as usize] as usize];
        k = parent[k as usize];
    }
    k
}

/// Joins the sets of `a` and `b`, the larger root under the smaller.
fn union(parent: &mut [u32], a: u32, b: u32) {
    let (a, b) = (root(parent, a), root(parent, b));
    let (low, high) = if a < b { (a, b) } else { (b, a) };
    parent[high as usize] = low;
}

#[cfg(test)]
mod tests {

    use super::*;
    use crate::solver::descent::tests::spring_system;
    use crate::solver::elements::{BlockPattern, SymmetricBlockMatrix};

    /// Two chains of three particles of mass `m`, joined by springs of stiffness `k`
    /// along x, y and z alike: particles 0 to 2 and 3 to 5.
    fn two_chains(m: f32, k: f32) -> (BlockPattern, SymmetricBlockMatrix) {
        spring_system(6, &[[0, 1], [1, 2], [3, 4], [4, 5]], m, k)
    }

    #[test]
    fn a_loose_chain_takes_the_translation_its_pull_asks_for_and_a_pinned_one_none() {
        let (pattern, matrix) = two_chains(1e-3, 10.0);
        let system = StepSystem::new(&pattern, &matrix);
        // Particle 3 is pinned.
        let mut filter = Filters::free(6);
        filter.reset(6, |i| i != 3);
        // The same pull on every particle: the loose chain's exact solution is the
        // uniform `pull / m`, which a sweep from zero would reach only slowly.
        let pull = Vec3::new(2e-3, -1e-3, 0.5e-3);
        let rhs: Vec<Vec3> = (0..6).map(|i| if i == 3 { Vec3::ZERO } else { pull }).collect();
        let mut delta = vec![Vec3::ZERO; 6];
        let mut pieces = FloatingPieces::default();
        pieces.find(system, &filter);
        pieces.correct(&rhs, &mut delta, |_, _| Vec3::ZERO, |_, _, _| 1.0);
        // Within a thousandth: the matrix holds each mass beside 10⁴ times as much
        // stiffness in single precision, and the sum of the blocks keeps the mass only to
        // about 2⁻²⁴ · 10⁴.
        let expected = pull / 1e-3;
        for d in &delta[0..3] {
            assert!((*d - expected).length() < 1e-3 * expected.length(), "the loose chain moves by {d}");
        }
        // The pinned chain is held: a uniform move is not its soft mode.
        assert!(delta[3..].iter().all(|d| *d == Vec3::ZERO), "{:?}", &delta[3..]);
        // Pressed against a plane of normal y, the loose chain moves along it only: its
        // pull's part into the plane is the plane's to bear.
        let mut along = vec![Vec3::ZERO; 6];
        let down = Vec3::new(pull.x, -pull.length(), pull.z);
        let rhs_down: Vec<Vec3> = rhs.iter().map(|r| if *r == Vec3::ZERO { *r } else { down }).collect();
        pieces.correct(&rhs_down, &mut along, |i, _| if i < 3 { Vec3::Y } else { Vec3::ZERO }, |_, _, _| 1.0);
        for d in &along[0..3] {
            let expected = Vec3::new(pull.x, 0.0, pull.z) / 1e-3;
            assert!((*d - expected).length() < 1e-3 * expected.length(), "the chain on the plane moves by {d}");
        }
        // On planes that disagree by more than 3°, not at all.
        let tilted = Vec3::new(0.1, 1.0, 0.0).normalize();
        let mut held = vec![Vec3::ZERO; 6];
        pieces.correct(&rhs_down, &mut held, |i, _| if i == 0 { tilted } else { Vec3::Y }, |_, _, _| 1.0);
        assert!(held.iter().all(|d| *d == Vec3::ZERO), "{held:?}");
        // Where the bounds allow a particle half the move, the whole piece takes half.
        let mut delta = vec![Vec3::ZERO; 6];
        pieces.correct(&rhs, &mut delta, |_, _| Vec3::ZERO, |i, _, _| if i == 1 { 0.5 } else { 1.0 });
        for d in &delta[0..3] {
            assert!((*d - 0.5 * expected).length() < 1e-3 * expected.length(), "the loose chain moves by {d}");
        }
    }

    #[test]
    fn only_particles_of_a_loose_piece_resting_whole_on_planes_count_as_sliding() {
        let (pattern, matrix) = two_chains(1e-3, 10.0);
        let mut filter = Filters::free(6);
        filter.reset(6, |i| i != 3);
        let mut pieces = FloatingPieces::default();
        pieces.find(StepSystem::new(&pattern, &matrix), &filter);
        let (all, loose_only) = (|_: usize| true, |i: usize| i < 3);
        // The loose chain on planes, cut anywhere: sliding.
        assert!(pieces.cut_only_where_resting(all, loose_only));
        assert!(pieces.cut_only_where_resting(all, |i| i == 1));
        // Nothing cut: nothing to hold the advance back.
        assert!(pieces.cut_only_where_resting(|_| false, |_| false));
        // One of its particles off its plane: a cloth landing, not sliding.
        assert!(!pieces.cut_only_where_resting(|i| i != 2, |i| i == 1));
        // A particle of the pinned chain cut, on a plane or not: not a loose piece.
        assert!(!pieces.cut_only_where_resting(all, |i| i == 4));
    }
}
