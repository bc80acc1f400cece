//! The contact springs' couplings in a system's products, prepared once for the system.
//!
//! Each product of a system with contact springs adds their off-diagonal blocks, spring
//! by spring: the pair's relative motion `Σ_j w_j y_j`, and at each vertex `k` the block
//! `B` times that motion less the vertex's own part, `w_k B (Σ_j w_j y_j − w_k y_k)` (the
//! diagonal blocks `w_k² B` are in the matrix). Formed that way in every product, the
//! springs' blocks were formed again each time from their normals, and their terms were
//! added to the vertices on one thread, spring by spring, while the other waited: a heap
//! of two cloths (`untangle_layers`, some 3 000 springs on 1 250 particles) spent a
//! sixth of its run there.
//!
//! Prepared with the system, the blocks are kept, with each vertex's sum of its diagonal
//! blocks `D_k = Σ w_k² B`, and each vertex knows its springs in spring order. A product
//! forms each spring's push `B Σ_j w_j y_j` in parallel, one block product a spring; then
//! each vertex adds its springs' pushes, weighted, in that order, less `D_k y_k`, the
//! vertices in parallel parts. That is one block product a spring and one a vertex, where
//! the product formed one for each of a vertex's terms (three or four a spring): on the
//! bench's folded 65 k sheet (`kernels/springs_product`, 32 768 springs) it takes 0.59 to
//! 0.64 ms against 0.87 to 0.89, and on smaller heaps it is the same within the noise.
//! Each vertex sums the same terms in the same order on any number of threads: the same
//! bits.

use glam::{Mat3, Vec3};
use rayon::prelude::*;

use super::contact_springs::{ContactSpring, Stencil, Weights};
use super::elements::block::{by_parts, cut_parts};
use super::gather::reserve_floored;

/// The most parts the vertices are cut into, each adding its vertices' terms on a task of
/// its own.
const MAX_PARTS: usize = 8;

/// The terms a part adds at least, so that a task outweighs its scheduling: a few
/// microseconds of block products.
const PART_TERMS: usize = 1024;

/// The acting springs from which their pushes are formed in parallel.
const PARALLEL_SPRINGS: usize = 256;

/// The acting springs of a system with their blocks, indexed by vertex for its products.
#[derive(Debug, Clone, Default)]
pub struct SpringCouplings {
    /// Per acting spring (in the springs' order), its stencil and its block `B`, the
    /// stiffness and friction at the system's weights ([`ContactSpring::block`]).
    stencils: Vec<Stencil>,
    blocks: Vec<Mat3>,
    /// The vertices the acting springs weigh, ascending: vertex `reached[r]` has the terms
    /// `terms[offsets[r]..offsets[r + 1]]`, each an acting spring and the vertex's weight in
    /// it, in the springs' order.
    reached: Vec<u32>,
    offsets: Vec<u32>,
    terms: Vec<(u32, f32)>,
    /// Per reached vertex, the sum of its diagonal blocks `Σ w² B`, in its terms' order.
    diagonal: Vec<Mat3>,
    /// The parts of the vertices added in parallel: part `p` holds the reached vertices
    /// `reached[part_rows[p]..part_rows[p + 1]]`, the vertices from `bounds[p]` to
    /// `bounds[p + 1]`.
    part_rows: Vec<usize>,
    bounds: Vec<usize>,
    /// Per vertex, its count of terms and then its next place in `terms` while they are
    /// indexed; zero between preparations.
    count: Vec<u32>,
}

impl SpringCouplings {
    /// Prepares the products of a system over `vertices` vertices whose contact `springs`
    /// take the `weights` of stiffness and friction in it: `None` where the system can
    /// have none (its cloth does not collide with itself), which keeps nothing for them.
    /// Where it can, the lists take their room at once, so that springs beginning to act
    /// in a warm step allocate nothing.
    pub fn prepare(&mut self, springs: Option<&[ContactSpring]>, weights: Weights, vertices: usize) {
        self.stencils.clear();
        self.blocks.clear();
        let Some(springs) = springs else {
            self.index(0);
            self.cut(0);
            return;
        };
        reserve_floored(&mut self.stencils, springs.len());
        reserve_floored(&mut self.blocks, springs.len());
        for s in springs.iter().filter(|s| s.acts()) {
            self.stencils.push(s.stencil);
            self.blocks.push(s.block(weights));
        }
        self.index(vertices);
        self.cut(vertices);
    }

    /// Whether no spring acts.
    pub fn is_empty(&self) -> bool {
        self.stencils.is_empty()
    }

    /// The acting springs' count.
    pub fn len(&self) -> usize {
        self.stencils.len()
    }

    /// The stencils and blocks of the acting springs `range`, in the springs' order.
    pub fn springs_in(&self, range: std::ops::Range<usize>) -> impl Iterator<Item = (&Stencil, Mat3)> {
        self.stencils[range.clone()].iter().zip(self.blocks[range].iter().copied())
    }

    /// Each reached vertex with the sum of its diagonal blocks from the springs' couplings,
    /// `Σ w_k² B`, kept from the indexing: the blocks that are in the system's matrix
    /// ([`super::contact_springs::add_diagonal`]).
    pub fn diagonals(&self) -> impl Iterator<Item = (usize, Mat3)> + '_ {
        self.reached.iter().map(|&vertex| vertex as usize).zip(self.diagonal.iter().copied())
    }

    /// Indexes the springs' weighted vertices by vertex, each vertex's in spring order
    /// (and slot order within a spring), as the serial loop added them.
    fn index(&mut self, vertices: usize) {
        self.reached.clear();
        self.offsets.clear();
        self.offsets.push(0);
        self.terms.clear();
        self.diagonal.clear();
        if vertices == 0 {
            return;
        }
        // Room for four weighted vertices a spring of the room the springs have, so that
        // the lists grow with the springs', not at every few springs more.
        let room = 4 * self.stencils.capacity();
        reserve_floored(&mut self.reached, room);
        reserve_floored(&mut self.offsets, room);
        reserve_floored(&mut self.terms, room);
        reserve_floored(&mut self.diagonal, room);
        self.count.resize(vertices, 0);
        for stencil in &self.stencils {
            for (_, vertex, _) in stencil.weighted() {
                self.count[vertex] += 1;
            }
        }
        // Each count becomes its vertex's first place in `terms`.
        for (vertex, count) in self.count.iter_mut().enumerate().filter(|(_, count)| **count > 0) {
            let start = *self.offsets.last().expect("begins at zero");
            self.reached.push(vertex as u32);
            self.offsets.push(start + *count);
            *count = start;
        }
        self.terms.resize(*self.offsets.last().expect("begins at zero") as usize, (0, 0.0));
        for (s, stencil) in self.stencils.iter().enumerate() {
            for (_, vertex, weight) in stencil.weighted() {
                let place = &mut self.count[vertex];
                self.terms[*place as usize] = (s as u32, weight);
                *place += 1;
            }
        }
        for &vertex in &self.reached {
            self.count[vertex as usize] = 0;
        }
        let (terms, blocks) = (&self.terms, &self.blocks);
        self.diagonal.extend(self.offsets.windows(2).map(|at| {
            terms[at[0] as usize..at[1] as usize]
                .iter()
                .fold(Mat3::ZERO, |sum, &(s, w)| sum + w * w * blocks[s as usize])
        }));
    }

    /// Cuts the reached vertices into parts of about equal terms, at most [`MAX_PARTS`]
    /// and none under [`PART_TERMS`] but the only one.
    fn cut(&mut self, vertices: usize) {
        let offsets = &self.offsets;
        let terms = |r: usize| (offsets[r + 1] - offsets[r]) as usize;
        cut_parts(
            &self.reached,
            vertices,
            self.terms.len(),
            PART_TERMS,
            MAX_PARTS,
            terms,
            &mut self.part_rows,
            &mut self.bounds,
        );
    }

    /// Adds the springs' off-diagonal blocks times `y` to `out`, with `pushes` as
    /// scratch: at each vertex `i`, `w_i B (Σ_j w_j y_j − w_i y_i)` for each spring at it.
    pub fn add_product(&self, y: &[Vec3], pushes: &mut Vec<Vec3>, out: &mut [Vec3]) {
        self.product(y, pushes, out, false);
    }

    /// Sets the rows of `out` at the vertices the springs weigh to the springs'
    /// off-diagonal blocks times `y` ([`SpringCouplings::add_product`]), leaving the others
    /// as they are.
    pub fn set_product(&self, y: &[Vec3], pushes: &mut Vec<Vec3>, out: &mut [Vec3]) {
        self.product(y, pushes, out, true);
    }

    /// Makes room in `pushes`, a product's scratch, for as many springs as these have
    /// room for: springs that begin to act in a warm step then find it.
    pub fn reserve(&self, pushes: &mut Vec<Vec3>) {
        reserve_floored(pushes, self.stencils.capacity().saturating_sub(pushes.len()));
    }

    fn product(&self, y: &[Vec3], pushes: &mut Vec<Vec3>, out: &mut [Vec3], set: bool) {
        self.reserve(pushes);
        if self.is_empty() {
            return;
        }
        debug_assert_eq!(out.len(), *self.bounds.last().expect("cut"));
        pushes.resize(self.len(), Vec3::ZERO);
        let springs = self.stencils.par_iter().zip(&self.blocks);
        springs.zip(pushes.par_iter_mut()).with_min_len(PARALLEL_SPRINGS).for_each(|((s, block), push)| {
            *push = *block * s.relative(y);
        });
        let pushes = &*pushes;
        by_parts(out, &self.bounds, |p, rows, out| {
            for r in self.part_rows[p]..self.part_rows[p + 1] {
                let i = self.reached[r] as usize;
                let out = &mut out[i - rows.start];
                let mut pushed = Vec3::ZERO;
                for &(s, weight) in &self.terms[self.offsets[r] as usize..self.offsets[r + 1] as usize] {
                    pushed += weight * pushes[s as usize];
                }
                let coupled = pushed - self.diagonal[r] * y[i];
                *out = if set { coupled } else { *out + coupled };
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::contact_springs::{Outside, SpringTerms, add_diagonal, add_product};
    use crate::solver::elements::{BlockPattern, SymmetricBlockMatrix};

    /// `count` springs over the first `vertices` vertices, many sharing vertices, every fifth
    /// against another cloth (its triangle's weights zero) and every seventh released.
    fn springs(count: u32, vertices: u32) -> Vec<ContactSpring> {
        (0..count)
            .map(|k| {
                let (p, q) = ((k * 7) % vertices, (k * 13 + 5) % (vertices - 2));
                let mut stencil = Stencil::point_triangle(p, [q, q + 1, q + 2], [0.2, 0.5, 0.3]);
                if k % 5 == 0 {
                    stencil.weights[1..].fill(0.0);
                }
                ContactSpring {
                    stencil,
                    normal: Vec3::new(0.3, 1.0, -0.1 * (k % 5) as f32).normalize(),
                    gap: 0.002,
                    stiffness: if k % 7 == 0 { 0.0 } else { 400.0 + k as f32 },
                    friction: 0.3,
                    drag: if k % 7 == 0 { 0.0 } else { 20.0 },
                    armed: 0.0,
                    outside: Outside::default(),
                }
            })
            .collect()
    }

    fn irregular(i: usize) -> Vec3 {
        let f = |k: usize| ((i * 2_654_435_761 + k * 40_503) % 1000) as f32 / 500.0 - 1.0;
        Vec3::new(f(0), f(1), f(2))
    }

    #[test]
    fn the_prepared_couplings_and_the_diagonal_blocks_make_the_springs_whole_product() {
        let (vertices, weights) = (600, Weights { stiffness: 0.5, drag: 0.1 });
        // The last hundred vertices no spring weighs.
        let springs = springs(2_000, vertices as u32 - 100);
        let mut couplings = SpringCouplings::default();
        couplings.prepare(Some(&springs), weights, vertices);
        assert_eq!(couplings.len(), springs.iter().filter(|s| s.acts()).count());
        assert!(couplings.bounds.len() > 3, "the vertices cut into parts: {:?}", couplings.bounds);
        let y: Vec<Vec3> = (0..vertices).map(irregular).collect();
        // The whole product, spring by spring, against the diagonal blocks in a matrix
        // and the couplings added to their product.
        let mut whole = vec![Vec3::ZERO; vertices];
        add_product(&springs, &mut SpringTerms::default(), weights, &y, &mut whole);
        let pattern = BlockPattern::from_stencils(vertices, std::iter::empty()).with_upper();
        let mut matrix = SymmetricBlockMatrix::default();
        matrix.reset(&pattern);
        add_diagonal(&springs, weights, &pattern, &mut matrix);
        let mut split = vec![Vec3::ZERO; vertices];
        matrix.multiply(&pattern, &y, &mut split);
        let mut pushes = Vec::new();
        couplings.add_product(&y, &mut pushes, &mut split);
        let scale = whole.iter().map(|p| p.length()).fold(0.0, f32::max);
        for i in 0..vertices {
            assert!((split[i] - whole[i]).length() < 1e-5 * scale, "vertex {i}: {} against {}", split[i], whole[i]);
        }
        // The diagonal blocks it gives are those in the matrix.
        let mut diagonal = vec![Mat3::ZERO; vertices];
        for (i, block) in couplings.diagonals() {
            diagonal[i] = block;
        }
        for (i, block) in diagonal.iter().enumerate() {
            assert_eq!(*block, matrix.diagonal(&pattern, i), "vertex {i}");
        }
        // Set, the rows the springs weigh take the product alone, and the rest stay.
        let mut set = vec![Vec3::splat(7.0); vertices];
        couplings.set_product(&y, &mut pushes, &mut set);
        let mut added = vec![Vec3::ZERO; vertices];
        couplings.add_product(&y, &mut pushes, &mut added);
        let weighed: Vec<bool> = (0..vertices).map(|i| couplings.reached.contains(&(i as u32))).collect();
        assert!(weighed.iter().any(|w| !w), "some vertex no spring weighs");
        for i in 0..vertices {
            assert_eq!(set[i], if weighed[i] { added[i] } else { Vec3::splat(7.0) }, "vertex {i}");
        }
    }

    #[test]
    fn no_acting_spring_leaves_the_product_as_it_is() {
        let mut springs = springs(10, 50);
        springs.iter_mut().for_each(|s| (s.stiffness, s.drag) = (0.0, 0.0));
        let mut couplings = SpringCouplings::default();
        couplings.prepare(Some(&springs), Weights { stiffness: 1.0, drag: 1.0 }, 50);
        assert!(couplings.is_empty());
        let mut out = vec![Vec3::ONE; 50];
        couplings.add_product(&vec![Vec3::X; 50], &mut Vec::new(), &mut out);
        assert!(out.iter().all(|o| *o == Vec3::ONE));
    }
}
