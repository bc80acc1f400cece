//! Caches derived from a cloth's structure, and per-cloth scratch space.

use std::sync::OnceLock;

use bevy_ecs::prelude::*;
use glam::Vec3;

use super::{BendingHinges, MembraneTriangles, Springs};
use crate::collision::self_contact::ContactMesh;
use crate::memory::release;
use crate::solver::descent::Colouring;
use crate::solver::elements::{BlockPattern, ElementPositions};
use crate::solver::forces::ForceScratch;
use crate::solver::implicit::VelocityConstraint;
use crate::solver::integrate::IntegratorWorkspace;
use crate::solver::multigrid::Hierarchy;

/// Compressed rows: for each particle, the list of items (springs, triangles) touching it,
/// in ascending item order so that sums over them are deterministic.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Csr {
    /// Row `i` is `items[offsets[i]..offsets[i + 1]]`.
    pub offsets: Vec<u32>,
    /// Item indices, grouped by row.
    pub items: Vec<u32>,
}

/// The row of particle `p` in rows by particle: its own, none for the entry `u32::MAX`
/// (an element's unused corner).
fn own_row(p: u32) -> Option<u32> {
    (p != u32::MAX).then_some(p)
}

impl Csr {
    /// Frees lists that were made for a while, as [`release`] frees them (as
    /// `BlockPattern::release` does a pattern's).
    pub fn release(self) {
        let Self { offsets, items } = self;
        release(offsets);
        release(items);
    }

    /// Builds the rows of `row_count` particles from items that each touch a few
    /// particles; a row lists item indices.
    pub fn from_items<const N: usize>(row_count: usize, items: &[[u32; N]]) -> Self {
        Self::build(row_count, items, own_row, |item, _| item)
    }

    /// Like [`Csr::from_items`], but a row lists corners `item · N + slot`, so a gather
    /// can pick the force an element puts on that particle.
    pub fn from_corners<const N: usize>(row_count: usize, items: &[[u32; N]]) -> Self {
        Self::build(row_count, items, own_row, |item, slot| item * N as u32 + slot)
    }

    /// For each of `rows` (particles, a particle listed twice making two rows), the
    /// corners `N i + c` of the `items` at it, items in order: [`Csr::from_corners`] for
    /// some particles only.
    pub fn at_rows_of<const N: usize>(rows: &[u32], items: &[[u32; N]]) -> Self {
        // The rows by particle, so that a corner finds its rows by a binary search.
        let mut by_particle: Vec<u32> = (0..rows.len() as u32).collect();
        by_particle.sort_by_key(|&r| rows[r as usize]);
        let rows_at = |p: u32| {
            let start = by_particle.partition_point(|&r| rows[r as usize] < p);
            by_particle[start..].iter().copied().take_while(move |&r| rows[r as usize] == p)
        };
        Self::build(rows.len(), items, rows_at, |item, slot| item * N as u32 + slot)
    }

    /// Builds `row_count` rows from items that each touch up to `N` particles, an item's
    /// particle `p` going to the rows `rows_at(p)`.
    fn build<const N: usize, R: IntoIterator<Item = u32>>(
        row_count: usize,
        items: &[[u32; N]],
        rows_at: impl Fn(u32) -> R,
        entry: impl Fn(u32, u32) -> u32,
    ) -> Self {
        let mut offsets = vec![0u32; row_count + 1];
        for &p in items.iter().flatten() {
            for r in rows_at(p) {
                offsets[r as usize + 1] += 1;
            }
        }
        for i in 0..row_count {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut rows = vec![0u32; offsets[row_count] as usize];
        for (index, item) in items.iter().enumerate() {
            for (slot, &p) in item.iter().enumerate() {
                for r in rows_at(p) {
                    rows[fill[r as usize] as usize] = entry(index as u32, slot as u32);
                    fill[r as usize] += 1;
                }
            }
        }
        release(fill);
        Self { offsets, items: rows }
    }

    /// Where row `row` lies in `items`.
    pub fn range(&self, row: usize) -> std::ops::Range<usize> {
        self.offsets[row] as usize..self.offsets[row + 1] as usize
    }

    /// The items of row `row`.
    pub fn row(&self, row: usize) -> &[u32] {
        &self.items[self.range(row)]
    }
}

/// Structure derived from a cloth's springs, triangles, hinges, membrane triangles and
/// pins: rebuilt only when change detection says one of them changed.
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct ClothTopology {
    /// Springs touching each particle.
    pub particle_springs: Csr,
    /// Triangles touching each particle, found when wind first asks for them
    /// ([`ClothTopology::particle_triangles`]): only wind reads them, and a cloth out of the
    /// wind (every bench scene) kept 28 bytes a particle for nothing.
    particle_triangles: OnceLock<Csr>,
    /// Edges of the triangles, each once, smaller particle first, sorted: found when
    /// contact first asks for them ([`ClothTopology::edges`]), since only contact reads
    /// them: a cloth that touches nothing (the hang bench scenes) kept 24 bytes a particle
    /// for nothing.
    edges: OnceLock<Vec<[u32; 2]>>,
    /// Hinge corners `4 h + c` at each particle; empty where the bending is quadratic,
    /// whose forces are rows of its Jacobian (72 bytes a particle on a regular sheet,
    /// with `hinge_faces`).
    pub particle_hinges: Csr,
    /// Face sides `3 f + k` at each hinge: where a hinge's moment comes from; empty where
    /// the bending is quadratic.
    pub hinge_faces: Csr,
    /// The pinned particles, in the order the topology was given them.
    pub pinned: Vec<u32>,
    /// Membrane corners `3 t + c` at each of `pinned`, row by row: only the pins'
    /// reaction asks for the membranes at a particle ([`crate::solver::forces::ForceModel::pin_forces`]),
    /// and kept for every particle they were 28 bytes a particle.
    pub pinned_membranes: Csr,
    /// Which 3×3 blocks the derivatives ∂f/∂x and ∂f/∂v have: every coupling, or under
    /// quadratic bending those within a spring or a triangle (its couplings across an
    /// edge are scalars, `ConstantCouplings`, found with its Jacobian).
    pub pattern: BlockPattern,
    /// Where each spring's local blocks go in the pattern, as positions within their rows
    /// ([`BlockPattern::upper_positions`]).
    pub spring_positions: ElementPositions<3>,
    /// Where each bending face's local blocks go (and, through its `corners`, each of its
    /// hinges': the exact Jacobian's hinge blocks are among a face's); empty where the
    /// bending is quadratic, whose constant Jacobian finds them once.
    pub face_positions: ElementPositions<21>,
    /// Where each membrane triangle's local blocks go.
    pub membrane_positions: ElementPositions<6>,
    /// The particles in groups that share no element, for block descent's parallel sweeps:
    /// built with the topology where block descent solves the step ([`SolverParts`]),
    /// else when first asked for ([`ClothTopology::colouring`]): 4 bytes a particle that
    /// the conjugate gradients never read.
    colouring: OnceLock<Colouring>,
    /// The particles grouped level by level, for the multigrid preconditioner: built with
    /// the topology where the solver preconditions with it ([`SolverParts`]), else when
    /// first asked for ([`ClothTopology::hierarchy`]). Built with every topology, it held
    /// 122 bytes a particle of sphere_64, whose block Jacobi never reads it.
    hierarchy: OnceLock<Hierarchy>,
    /// Inverse mass with pinned particles at zero [1/kg]: what the integrators accelerate.
    pub free_inv_mass: Vec<f32>,
    /// How many times this cache was built; lets tests see it is not rebuilt every step.
    pub builds: u32,
}

impl ClothTopology {
    /// Derives the topology of a cloth of `elements`, with the `parts` its solver will use.
    /// `builds` counts how often this was done.
    pub fn build(
        inv_mass: &[f32],
        elements: ClothElements<'_>,
        pinned: &[u32],
        builds: u32,
        parts: SolverParts,
    ) -> Self {
        let count = inv_mass.len();
        let ClothElements { springs, hinges, membranes, .. } = elements;
        let couplings = elements.couplings(count);
        let (whole, near) = (&couplings.whole, &couplings.near);
        // Hinge forces and face blocks gathered from their angles, unless the bending is
        // quadratic, whose couplings across an edge are constant and kept apart.
        let by_angles = !hinges.is_quadratic();
        let pattern = match by_angles {
            true => whole.clone().with_upper(),
            false => near.clone().with_upper(),
        };
        // Made from the patterns at hand, not found again by the accessors.
        let colouring = parts.colouring.then(|| Colouring::greedy(whole));
        let hierarchy = parts.hierarchy.then(|| Hierarchy::build(whole, near, &pattern));
        let mut free_inv_mass = inv_mass.to_vec();
        for &p in pinned {
            free_inv_mass[p as usize] = 0.0;
        }
        Self {
            particle_springs: Csr::from_items(count, &springs.pairs),
            particle_triangles: OnceLock::new(),
            edges: OnceLock::new(),
            particle_hinges: match by_angles {
                true => Csr::from_corners(count, &hinges.vertices),
                false => Csr::default(),
            },
            hinge_faces: match by_angles {
                true => {
                    Csr::from_corners(hinges.vertices.len(), &hinges.faces.iter().map(|f| f.hinges).collect::<Vec<_>>())
                }
                false => Csr::default(),
            },
            pinned_membranes: Csr::at_rows_of(pinned, &membranes.indices),
            pinned: pinned.to_vec(),
            spring_positions: ElementPositions::new(&pattern, springs.pairs.iter().copied()),
            face_positions: match by_angles {
                true => ElementPositions::new(&pattern, hinges.faces.iter().map(|f| f.vertices)),
                false => ElementPositions::default(),
            },
            membrane_positions: ElementPositions::new(&pattern, membranes.indices.iter().copied()),
            colouring: colouring.map_or_else(OnceLock::new, OnceLock::from),
            hierarchy: hierarchy.map_or_else(OnceLock::new, OnceLock::from),
            pattern,
            free_inv_mass,
            builds,
        }
    }

    /// The multigrid's levels over this topology, built at the first call from the cloth's
    /// elements it was built from.
    pub fn hierarchy(&self, elements: ClothElements<'_>) -> &Hierarchy {
        self.hierarchy.get_or_init(|| {
            let couplings = elements.couplings(self.free_inv_mass.len());
            Hierarchy::build(&couplings.whole, &couplings.near, &self.pattern)
        })
    }

    /// The colouring of this topology's particles for block descent, found at the first
    /// call from the cloth's elements it was built from.
    pub fn colouring(&self, elements: ClothElements<'_>) -> &Colouring {
        self.colouring.get_or_init(|| Colouring::greedy(&elements.couplings(self.free_inv_mass.len()).whole))
    }

    /// The triangles of `triangles`, those this topology was built from, that touch each
    /// particle; found at the first call.
    pub fn particle_triangles(&self, triangles: &[[u32; 3]]) -> &Csr {
        self.particle_triangles.get_or_init(|| Csr::from_items(self.free_inv_mass.len(), triangles))
    }

    /// The edges of `triangles`, the triangles this topology was built from, each once,
    /// smaller particle first, sorted; found at the first call.
    pub fn edges(&self, triangles: &[[u32; 3]]) -> &[[u32; 2]] {
        self.edges.get_or_init(|| ContactMesh::edges_of(triangles))
    }
}

/// Which of a topology's parts built on demand ([`ClothTopology::hierarchy`],
/// [`ClothTopology::colouring`]) its build makes at once, from the patterns it finds
/// anyway: those of the solver that will step the cloth. Made on demand instead, their
/// patterns are found a second time (45 to 50 ms of hang_256's start).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolverParts {
    /// The multigrid's levels' structure.
    pub hierarchy: bool,
    /// Block descent's colouring.
    pub colouring: bool,
}

/// The elements a cloth's topology was built from: what its parts built on demand
/// ([`ClothTopology::hierarchy`], [`ClothTopology::colouring`]) are found from.
#[derive(Clone, Copy)]
pub struct ClothElements<'a> {
    /// Its springs.
    pub springs: &'a Springs,
    /// Its triangles' particles.
    pub triangles: &'a [[u32; 3]],
    /// Its bending.
    pub hinges: &'a BendingHinges,
    /// Its membrane triangles.
    pub membranes: &'a MembraneTriangles,
}

impl ClothElements<'_> {
    /// The patterns of `count` particles' couplings.
    fn couplings(&self, count: usize) -> Couplings {
        let springs_stencils = || self.springs.pairs.iter().map(|p| &p[..]);
        let quadratic: Vec<[u32; 2]> = self.hinges.quadratic.pairs().map(|(i, j, _)| [i, j]).collect();
        let whole = BlockPattern::from_stencils(
            count,
            springs_stencils()
                .chain(self.hinges.faces.iter().map(|f| &f.vertices[..]))
                .chain(quadratic.iter().map(|p| &p[..]))
                .chain(self.membranes.indices.iter().map(|t| &t[..])),
        );
        let near = BlockPattern::from_stencils(
            count,
            springs_stencils().chain(self.triangles.iter().chain(&self.membranes.indices).map(|t| &t[..])),
        );
        release(quadratic);
        Couplings { whole, near }
    }
}

/// A cloth's coupling patterns, found for a while (by [`ClothTopology::build`] and the
/// parts it builds on demand) and freed as [`release`] frees lists when dropped.
struct Couplings {
    /// Every coupling, the bending faces' across an edge among them (under quadratic
    /// bending its pairs).
    whole: BlockPattern,
    /// Those of particles that share a spring or a triangle: the multigrid's finest
    /// level's.
    near: BlockPattern,
}

impl Drop for Couplings {
    fn drop(&mut self) {
        std::mem::take(&mut self.whole).release();
        std::mem::take(&mut self.near).release();
    }
}

/// Per-cloth scratch buffers for integrators and force evaluation, reused every step so the
/// step path does not allocate once sized.
#[derive(Component, Debug, Default)]
pub struct SolverWorkspace {
    /// Stage buffers of the integrators.
    pub integrator: IntegratorWorkspace,
    /// Per-element force buffers of the force model.
    pub forces: ForceScratch,
    /// Positions at the start of the strain limiter's projection [m].
    pub positions: Vec<Vec3>,
    /// Positions at the start of the current step [m], for continuous contact.
    pub step_start: Vec<Vec3>,
    /// Impulse the implicit solve's contact constraints gave each particle this step [N·s].
    pub support: Vec<Vec3>,
    /// The contact constraints of the current implicit step.
    pub constraints: Vec<VelocityConstraint>,
    /// Whether the particles' force is the whole cloth's at the step's start, evaluated
    /// with `forces` and nothing else since (not only the touching particles'), so that an
    /// implicit step linearising there may take it
    /// ([`crate::solver::forces::ClothDynamics::start_force`]).
    pub whole_start_force: bool,
}

/// What an embedding renderer needs each frame: vertex normals beside the particle
/// positions, refreshed once per frame in the render schedule.
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct RenderMesh {
    /// Area-weighted unit vertex normals, parallel to the particles.
    pub normals: Vec<Vec3>,
}
