//! The force model: gravity, air drag, per-triangle wind, damped springs and user forces,
//! as a pure function of the state `(x, v, t)` that every integrator evaluates.

use glam::{Mat3, Vec3};
use rayon::prelude::*;

use super::PARALLEL_MIN_LEN;
use super::contact_springs::ContactSpring;
use super::descent::Colouring;
use super::elements::block::{by_parts, oriented, upper_map, upper_pair, upper_pairs};
use super::elements::{
    BlockPattern, ConstantCouplings, NO_HINGE, SpringElement, SymmetricBlockMatrix, VelocityJacobian,
};
use super::implicit::LinearDynamics;
use super::integrate::Dynamics;
use super::multigrid::Hierarchy;
use super::reduce;
use crate::collision::body_contact::ContactBody;
use crate::collision::motion_bounds::{LayerContact, Others, Surface};
use crate::components::{BendingHinges, ClothElements, ClothTopology, Csr, MembraneTriangles, Springs};
use crate::memory::release;

/// Air around the cloth.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Air {
    /// Linear drag rate [1/s]: each particle feels `−drag · m · v`, so the damping does not
    /// depend on how finely the cloth is sampled.
    pub drag: f32,
    /// Mean wind velocity [m/s].
    pub wind: Vec3,
    /// Normal drag coefficient of the cloth surface [kg/m³] (about ½ ρ_air C_d): a triangle
    /// of area A feels `wind_drag · A · |u| (n·u) n` for the wind relative to it `u`
    /// (Meyer et al., as in Durupınar §3.1.2.3). With no wind it still damps flapping.
    pub wind_drag: f32,
    /// Optional periodic gusts on top of the mean wind.
    pub gust: Option<Gust>,
    /// Linear air damping per unit area η [kg/(m²·s)] (Zheng §2.2.3): each particle feels
    /// `−η a v` for the area `a` it represents.
    pub area_damping: f32,
}

/// A sinusoidal modulation of the wind speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gust {
    /// Relative amplitude: the wind is `wind · (1 + amplitude · sin(2π t / period_s))`.
    pub amplitude: f32,
    /// Period of the gusts [s], > 0.
    pub period_s: f32,
}

impl Air {
    /// Wind velocity at time `t` [s].
    pub fn wind_at(&self, t: f32) -> Vec3 {
        match self.gust {
            Some(gust) => self.wind * (1.0 + gust.amplitude * (std::f32::consts::TAU * t / gust.period_s).sin()),
            None => self.wind,
        }
    }
}

/// Wind force on each vertex of a triangle [N]: a third of the normal drag on the triangle.
#[inline]
pub fn triangle_wind_force(x: [Vec3; 3], v: [Vec3; 3], wind: Vec3, wind_drag: f32) -> Vec3 {
    let normal = (x[1] - x[0]).cross(x[2] - x[0]);
    let twice_area = normal.length();
    if twice_area == 0.0 {
        return Vec3::ZERO;
    }
    let n = normal / twice_area;
    let relative = wind - (v[0] + v[1] + v[2]) / 3.0;
    let force = wind_drag * 0.5 * twice_area * relative.length() * relative.dot(n) * n;
    force / 3.0
}

/// Buffers the force model writes per element before gathering per particle, so that each
/// particle's sum runs over its elements in a fixed order whatever the thread count (the
/// membranes, the most numerous, are added by parts of the rows instead, see
/// [`ForceModel::eval`]).
#[derive(Debug, Clone, Default)]
pub struct ForceScratch {
    spring: Vec<Vec3>,
    triangle: Vec<Vec3>,
    /// Each hinge's angle gradient, for its forces and for the faces' derivatives.
    hinge_gradient: Vec<[Vec3; 4]>,
    hinge_delta: Vec<f32>,
    hinge_moment: Vec<f32>,
    face_moment: Vec<[f32; 3]>,
    /// Which elements each part of the rows assembles.
    row_parts: RowParts,
    /// Quadratic bending's constant Jacobian.
    quadratic: QuadraticBlocks,
}

/// Quadratic bending's Jacobian, constant: for each block the topology's pattern stores
/// (those within a triangle: the pattern leaves out the faces' couplings across an edge)
/// the `s` of its `s I`, which the derivatives start from instead of zero, and the
/// couplings across an edge as [`ConstantCouplings`]; placed from the cloth's
/// [`QuadraticBending`](crate::solver::elements::QuadraticBending) once per topology.
/// Added face by face in every step, its 21 blocks a face took 0.5 ms of the 64² hang
/// scene's 1.5 ms assembly.
#[derive(Debug, Clone, Default)]
struct QuadraticBlocks {
    /// The topology's build and the number of pairs the scales were found for.
    key: Option<(u32, usize)>,
    scales: Vec<f32>,
    couplings: ConstantCouplings,
}

impl QuadraticBlocks {
    /// The scales for `model`'s topology, found unless they were found for it already;
    /// none where the bending is not quadratic.
    fn refresh(&mut self, model: &ForceModel<'_>) -> &[f32] {
        let (hinges, topology) = (model.hinges, model.topology);
        if !hinges.is_quadratic() {
            return &[];
        }
        let bending = &hinges.quadratic;
        let key = Some((topology.builds, bending.pair_count()));
        if self.key != key {
            self.key = key;
            let pattern = &topology.pattern;
            self.scales.clear();
            self.scales.resize(pattern.upper.last().map_or(0, |&size| size as usize), 0.0);
            for (i, &scale) in bending.diagonal().iter().enumerate() {
                let slot = pattern.upper_index(i as u32, i as u32).expect("the pattern has every diagonal block");
                self.scales[slot as usize] += scale;
            }
            for (p, q, scale) in bending.pairs() {
                if let Some(slot) = pattern.upper_index(p, q) {
                    self.scales[slot as usize] += scale;
                }
            }
            let across = || bending.pairs().filter(|&(p, q, _)| pattern.upper_index(p, q).is_none());
            self.couplings = ConstantCouplings::new(pattern.rows(), across);
        }
        &self.scales
    }

    /// The couplings across an edge last found for `model`, if its bending is quadratic.
    fn couplings(&self, model: &ForceModel<'_>) -> Option<&ConstantCouplings> {
        let current = model.hinges.is_quadratic()
            && self.key == Some((model.topology.builds, model.hinges.quadratic.pair_count()));
        current.then_some(&self.couplings)
    }
}

/// The rows of a cloth's matrices cut into parts that assemble in parallel, and the
/// elements of each kind with a particle in each part, in element order: found once per
/// topology and number of parts. An element beside a cut is computed by both parts, each
/// adding the blocks of its own rows.
#[derive(Debug, Clone, Default)]
struct RowParts {
    /// The topology's build, the number of parts, and the counts of rows, springs, faces,
    /// hinges and membranes they were found for.
    key: Option<(u32, usize, [usize; 5])>,
    /// Where each part's rows begin, and after the last, the number of rows.
    bounds: Vec<usize>,
    springs: Csr,
    faces: Csr,
    hinges: Csr,
    membranes: Csr,
}

impl RowParts {
    /// Finds the parts for `model`'s topology, unless they were found for it already, and
    /// the hinges' lists too if `hinges` (only the exact, indefinite assembly adds the
    /// hinges' own blocks; the lists are some 12 bytes a particle).
    fn refresh(&mut self, model: &ForceModel<'_>, hinges: bool) {
        let rows = model.inv_mass.len();
        let parts = row_part_count(rows);
        let counts = [
            rows,
            model.springs.len(),
            model.hinges.faces.len(),
            model.hinges.vertices.len(),
            model.membranes.indices.len(),
        ];
        let key = Some((model.topology.builds, parts, counts));
        if self.key != key {
            self.key = key;
            self.bounds = (0..=parts).map(|k| k * rows / parts).collect();
            self.springs = self.members(model.springs.pairs.iter().copied());
            self.faces = self.members(model.hinges.faces.iter().map(|f| f.vertices));
            self.membranes = self.members(model.membranes.indices.iter().copied());
            self.hinges = Csr::default();
        }
        // A built list has a row offset for each part and one more.
        if hinges && self.hinges.offsets.is_empty() {
            self.hinges = self.members(model.hinges.vertices.iter().copied());
        }
    }

    /// Each part's elements, from the elements' particles.
    fn members<const N: usize>(&self, stencils: impl Iterator<Item = [u32; N]>) -> Csr {
        let part_of = |p: u32| self.bounds.partition_point(|&b| b <= p as usize) as u32 - 1;
        let parts: Vec<[u32; N]> = stencils
            .map(|stencil| {
                let mut parts = stencil.map(part_of);
                // Each part once (an entry of u32::MAX is skipped).
                for k in 1..N {
                    if parts[..k].contains(&parts[k]) {
                        parts[k] = u32::MAX;
                    }
                }
                parts
            })
            .collect();
        let members = Csr::from_items(self.bounds.len() - 1, &parts);
        release(parts);
        members
    }
}

/// Parts of the rows an assembly is cut into: two per thread, so that a thread held up
/// elsewhere leaves a part to the other; one on one thread. Parts of equal rows hold about
/// equal elements, and more parts compute more elements twice (on the 64² hang scene,
/// with two threads, 2 and 4 parts assembled in 2.77 and 2.76 ms a frame, 8 in 2.96).
fn row_part_count(rows: usize) -> usize {
    let threads = rayon::current_num_threads();
    let parts = if threads == 1 { 1 } else { 2 * threads };
    parts.clamp(1, rows.max(1))
}

/// The forces of a cloth's elements, element by element.
trait ElementForces {
    /// Force of spring `s` on its first particle (the second feels the opposite).
    fn spring(&self, s: usize) -> Vec3;
    /// Forces of hinge `h` on its four vertices.
    fn hinge(&self, h: usize) -> [Vec3; 4];
    /// Wind force on each vertex of triangle `t`.
    fn wind(&self, t: usize) -> Vec3;
}

/// All elements' forces, as [`ForceModel::eval`] computed them.
impl ElementForces for ForceScratch {
    fn spring(&self, s: usize) -> Vec3 {
        self.spring[s]
    }
    fn hinge(&self, h: usize) -> [Vec3; 4] {
        self.hinge_gradient[h].map(|g| -self.hinge_moment[h] * g)
    }
    fn wind(&self, t: usize) -> Vec3 {
        self.triangle[t]
    }
}

/// Elements' forces computed one at a time when asked for ([`ForceModel::pin_forces`]).
struct LocalForces<'a> {
    model: &'a ForceModel<'a>,
    x: &'a [Vec3],
    v: &'a [Vec3],
    wind: Vec3,
    /// Every hinge's angle away from rest [rad].
    delta: &'a [f32],
}

impl ElementForces for LocalForces<'_> {
    fn spring(&self, s: usize) -> Vec3 {
        let [i, j] = self.model.springs.pairs[s].map(|p| p as usize);
        self.model.spring(s).force(self.x[i], self.x[j], self.v[i], self.v[j])
    }
    fn hinge(&self, h: usize) -> [Vec3; 4] {
        let bending = self.model.hinges.view();
        let moment = self.model.hinge_moment(h, |f| bending.face_moments(f, self.delta));
        bending.hinge_forces(h, self.x, moment)
    }
    fn wind(&self, t: usize) -> Vec3 {
        let tri = self.model.triangles[t].map(|p| p as usize);
        triangle_wind_force(tri.map(|p| self.x[p]), tri.map(|p| self.v[p]), self.wind, self.model.air.wind_drag)
    }
}

/// Adds the local blocks `local(e)` of each element (the `M` of its `N × N` on and above
/// the diagonal, in [`upper_pairs`] order) to `matrix` (over `pattern`) at the storage of
/// `stencil(e)` found by `positions(e)`: each part of the rows (at `bounds`) in parallel,
/// from the elements with a particle in it (`members`), adding the blocks of its own rows
/// in element order, so every sum is the same on any number of threads and parts. Cutting
/// the rows instead of the elements needs no buffer, no join between chunks and no
/// serial additions: the earlier pipeline (chunks of elements computed in parallel while
/// the last chunk was added by two tasks) held the 64² hang scene's assembly to 3.74 ms a
/// frame where the parts take 2.76, the 256² scene's to 59 ms where they take 48.
fn add_elements<const N: usize, const M: usize>(
    matrix: &mut SymmetricBlockMatrix,
    pattern: &BlockPattern,
    parts: (&[usize], &Csr),
    positions: impl Fn(usize) -> [u16; M] + Sync,
    stencil: impl Fn(usize) -> [u32; N] + Sync,
    local: impl Fn(usize) -> [Mat3; M] + Sync,
) {
    let (bounds, members) = parts;
    matrix.add_by_parts(pattern, bounds, |part, rows, target, first| {
        let (low, count) = (rows.start as u32, rows.len() as u32);
        for &e in members.row(part) {
            let e = e as usize;
            add_part_blocks(pattern, stencil(e), &positions(e), local(e), (low, count), target, first);
        }
    });
}

/// Adds an element's local blocks (`local`, in [`upper_pairs`] order) over `particles`,
/// stored at `positions`, to the part of the matrix whose rows are `low` and the `count`
/// after it (`target`, its storage from slot `first`): those of its own rows alone.
#[inline]
fn add_part_blocks<const N: usize, const M: usize>(
    pattern: &BlockPattern,
    particles: [u32; N],
    positions: &[u16; M],
    local: [Mat3; M],
    (low, count): (u32, u32),
    target: &mut [Mat3],
    first: usize,
) {
    let slots = pattern.upper_slots_at(particles, positions);
    for (((a, b), block), slot) in upper_pairs::<N>().zip(local).zip(slots) {
        let (p, q) = (particles[a], particles[b]);
        if p.min(q).wrapping_sub(low) < count {
            target[slot as usize - first] += oriented(block, p, q);
        }
    }
}

/// Everything that exerts force on one cloth, borrowed for one evaluation.
#[derive(Debug, Clone, Copy)]
pub struct ForceModel<'a> {
    /// Inverse masses [1/kg] (not zeroed for pins: pinned particles feel weight too).
    pub inv_mass: &'a [f32],
    /// Areal density [kg/m²], to turn damping per area into a rate.
    pub density: f32,
    /// The cloth's springs.
    pub springs: &'a Springs,
    /// The cloth's triangles, for wind.
    pub triangles: &'a [[u32; 3]],
    /// Bending hinges.
    pub hinges: &'a BendingHinges,
    /// Membrane triangles.
    pub membranes: &'a MembraneTriangles,
    /// Incidence rows and derivative pattern.
    pub topology: &'a ClothTopology,
    /// Gravitational acceleration [m/s²].
    pub gravity: Vec3,
    /// Drag and wind.
    pub air: Air,
    /// Sparse external forces [N].
    pub user_forces: &'a [(u32, Vec3)],
}

impl<'a> ForceModel<'a> {
    /// The cloth's elements, from which its topology finds what it builds on demand.
    pub fn elements(&self) -> ClothElements<'a> {
        ClothElements {
            springs: self.springs,
            triangles: self.triangles,
            hinges: self.hinges,
            membranes: self.membranes,
        }
    }

    fn spring(&self, s: usize) -> SpringElement {
        SpringElement {
            rest: self.springs.rest_length[s],
            stiffness: self.springs.stiffness[s],
            damping: self.springs.damping[s],
        }
    }

    /// Linear damping rate [1/s]: the mass-proportional drag plus the damping per area
    /// divided by the areal density (`η / ρ`, Zheng §2.2.3).
    pub fn damping_rate(&self) -> f32 {
        self.air.drag + self.air.area_damping / self.density
    }

    /// Angles away from rest and summed moments `∂E/∂θ` of every hinge, into `scratch`.
    fn bending_moments(&self, x: &[Vec3], scratch: &mut ForceScratch) {
        let bending = self.hinges.view();
        let hinge_count = self.hinges.vertices.len();
        scratch.hinge_delta.resize(hinge_count, 0.0);
        bending.angles(x, &mut scratch.hinge_delta);
        let delta = &scratch.hinge_delta;
        scratch.face_moment.resize(self.hinges.faces.len(), [0.0; 3]);
        scratch.face_moment.par_iter_mut().with_min_len(PARALLEL_MIN_LEN).enumerate().for_each(|(f, m)| {
            *m = bending.face_moments(f, delta);
        });
        let faces = &scratch.face_moment;
        scratch.hinge_moment.resize(hinge_count, 0.0);
        scratch.hinge_moment.par_iter_mut().with_min_len(PARALLEL_MIN_LEN).enumerate().for_each(|(h, m)| {
            *m = self.hinge_moment(h, |f| faces[f]);
        });
    }

    /// Summed moment `∂E/∂θ` of hinge `h` from the moments `face_moment(f)` of its faces.
    fn hinge_moment(&self, h: usize, face_moment: impl Fn(usize) -> [f32; 3]) -> f32 {
        self.topology.hinge_faces.row(h).iter().map(|&side| face_moment(side as usize / 3)[side as usize % 3]).sum()
    }

    /// The force on particle `i` at velocity `v` [m/s] before its membranes': weight,
    /// damping, springs and hinges, the elements' forces given by `elements` (see
    /// [`ElementForces`]). A particle's total adds its membranes' forces to it in the
    /// membranes' order, then the wind's ([`ForceModel::add_wind`]), user forces left
    /// out: the order [`ForceModel::eval`] and [`ForceModel::pin_forces`] share, so that
    /// both give the same bits.
    fn force_before_membranes(&self, i: usize, v: Vec3, rate: f32, elements: &impl ElementForces) -> Vec3 {
        let topology = self.topology;
        let mass = 1.0 / self.inv_mass[i];
        let mut total = mass * (self.gravity - rate * v);
        for &s in topology.particle_springs.row(i) {
            let sf = elements.spring(s as usize);
            total += if self.springs.pairs[s as usize][0] as usize == i { sf } else { -sf };
        }
        if !self.hinges.is_quadratic() {
            for &corner in topology.particle_hinges.row(i) {
                total += elements.hinge(corner as usize / 4)[corner as usize % 4];
            }
        }
        total
    }

    /// Quadratic bending's force on particle `i` at `x`: row `i` of its constant
    /// Jacobian (`quadratic`: [`QuadraticBlocks`]) times the other particles' offsets
    /// from `x_i`, `Σ_j s_ij (x_j − x_i)`, which is `J x` since the blocks of a row sum
    /// to zero, and is the same to the bit for a translated cloth. Row by row, some 20
    /// products a particle where the faces' own forces took some 150 operations a face.
    /// Three plain loops (the row's blocks below and above the diagonal, then its
    /// couplings across an edge): chained, the walk tested at every entry which part it
    /// was in, and `kernels/forces/quadratic` took 3 to 4 % longer.
    fn quadratic_bending(&self, i: usize, x: &[Vec3], quadratic: &QuadraticBlocks) -> Vec3 {
        let row = self.topology.pattern.symmetric_row(i);
        let scales = &quadratic.scales;
        let mut sum = Vec3::ZERO;
        for (&j, &mirror) in row.below.iter().zip(row.mirrors) {
            sum += scales[mirror as usize] * (x[j as usize] - x[i]);
        }
        for (&j, &s) in row.above.iter().zip(&scales[row.storage]) {
            sum += s * (x[j as usize] - x[i]);
        }
        quadratic.couplings.fold(i, sum, |sum, j, s| sum + s * (x[j as usize] - x[i]))
    }

    /// Adds the wind's force on particle `i` to its `total`, triangle by triangle.
    fn add_wind(&self, i: usize, total: &mut Vec3, elements: &impl ElementForces) {
        if self.air.wind_drag > 0.0 {
            for &t in self.topology.particle_triangles(self.triangles).row(i) {
                *total += elements.wind(t as usize);
            }
        }
    }

    /// Forces of membrane triangle `m` on its corners at positions `x`.
    fn membrane_forces(&self, m: usize, x: &[Vec3]) -> [Vec3; 3] {
        let membranes = self.membranes;
        membranes.element(m).forces(&membranes.material, membranes.indices[m].map(|p| x[p as usize]))
    }

    /// The total force on each pinned particle of the topology (`ClothTopology::pinned`,
    /// in its order) at state `(x, v)` and time `t` [N], as [`ForceModel::eval`] gives it,
    /// from their own elements alone: the pins' reaction without evaluating the whole
    /// cloth. `scratch` takes the angles of the hinges whose moments the particles'
    /// hinges need (those of their faces); the other hinges' entries are left as they
    /// were, and not read.
    pub fn pin_forces<'p>(
        &'p self,
        x: &'p [Vec3],
        v: &'p [Vec3],
        t: f32,
        scratch: &'p mut ForceScratch,
    ) -> impl Iterator<Item = Vec3> + 'p {
        let (bending, topology) = (self.hinges.view(), self.topology);
        let particles = topology.pinned.iter().copied();
        let quadratic = self.hinges.is_quadratic();
        scratch.hinge_delta.resize(if quadratic { 0 } else { self.hinges.vertices.len() }, 0.0);
        for p in particles.clone().filter(|_| !quadratic) {
            for &corner in topology.particle_hinges.row(p as usize) {
                for &side in topology.hinge_faces.row(corner as usize / 4) {
                    for &h in self.hinges.faces[side as usize / 3].hinges.iter().filter(|&&h| h != NO_HINGE) {
                        scratch.hinge_delta[h as usize] = bending.angle(h as usize, x);
                    }
                }
            }
        }
        let ForceScratch { hinge_delta, quadratic: blocks, .. } = scratch;
        blocks.refresh(self);
        let blocks = &*blocks;
        let local = LocalForces { model: self, x, v, wind: self.air.wind_at(t), delta: hinge_delta };
        let rate = self.damping_rate();
        particles.enumerate().map(move |(row, p)| {
            let i = p as usize;
            let user = self.user_forces.iter().filter(|(q, _)| *q == p).map(|(_, f)| *f);
            let mut total = self.force_before_membranes(i, v[i], rate, &local);
            for &corner in topology.pinned_membranes.row(row) {
                total += self.membrane_forces(corner as usize / 3, x)[corner as usize % 3];
            }
            if quadratic {
                total += self.quadratic_bending(i, x, blocks);
            }
            self.add_wind(i, &mut total, &local);
            user.fold(total, |total, f| total + f)
        })
    }

    /// Total force on every particle at state `(x, v)` and time `t` [s], written to `out`.
    pub fn eval(&self, x: &[Vec3], v: &[Vec3], t: f32, scratch: &mut ForceScratch, out: &mut [Vec3]) {
        self.element_forces(x, v, t, scratch);
        let scratch = &*scratch;
        by_parts(out, &scratch.row_parts.bounds, |part, rows, out| {
            self.gather(part, rows, x, v, scratch, out, |m| self.membrane_forces(m, x));
        });
        self.add_user_forces(out);
    }

    /// The forces of the elements kept per element (springs, hinges, wind), the parts of
    /// the rows the forces are gathered by, and quadratic bending's constant blocks.
    fn element_forces(&self, x: &[Vec3], v: &[Vec3], t: f32, scratch: &mut ForceScratch) {
        scratch.spring.resize(self.springs.len(), Vec3::ZERO);
        scratch.spring.par_iter_mut().with_min_len(PARALLEL_MIN_LEN).enumerate().for_each(|(s, f)| {
            let [i, j] = self.springs.pairs[s].map(|p| p as usize);
            *f = self.spring(s).force(x[i], x[j], v[i], v[j]);
        });

        if !self.hinges.is_quadratic() {
            self.bending_moments(x, scratch);
            scratch.hinge_gradient.resize(self.hinges.vertices.len(), [Vec3::ZERO; 4]);
            self.hinges.view().gradients(x, &mut scratch.hinge_gradient);
        }

        let wind = self.air.wind_at(t);
        let with_wind = self.air.wind_drag > 0.0;
        scratch.triangle.resize(if with_wind { self.triangles.len() } else { 0 }, Vec3::ZERO);
        scratch.triangle.par_iter_mut().with_min_len(PARALLEL_MIN_LEN).enumerate().for_each(|(t, f)| {
            let tri = self.triangles[t].map(|p| p as usize);
            *f = triangle_wind_force(tri.map(|p| x[p]), tri.map(|p| v[p]), wind, self.air.wind_drag);
        });
        scratch.row_parts.refresh(self, false);
        scratch.quadratic.refresh(self);
    }

    /// The total forces on the particles of part `part` of the rows (`rows`, their forces
    /// `out`), the membranes' forces given by `membrane(m)`. Each part gathers its
    /// particles' forces before the membranes', adds the forces of the membranes with a
    /// corner among them in the membranes' order, which is the order of each particle's
    /// own list, then quadratic bending's, then the wind's. A membrane beside a cut is
    /// computed by both parts; kept instead, the membranes' forces were 72 bytes a
    /// particle.
    fn gather(
        &self,
        part: usize,
        rows: std::ops::Range<usize>,
        x: &[Vec3],
        v: &[Vec3],
        scratch: &ForceScratch,
        out: &mut [Vec3],
        mut membrane: impl FnMut(usize) -> [Vec3; 3],
    ) {
        let rate = self.damping_rate();
        for (i, f) in rows.clone().zip(out.iter_mut()) {
            *f = self.force_before_membranes(i, v[i], rate, scratch);
        }
        for &m in scratch.row_parts.membranes.row(part) {
            let forces = membrane(m as usize);
            for (&p, force) in self.membranes.indices[m as usize].iter().zip(forces) {
                if rows.contains(&(p as usize)) {
                    out[p as usize - rows.start] += force;
                }
            }
        }
        if self.hinges.is_quadratic() {
            for (i, f) in rows.clone().zip(out.iter_mut()) {
                *f += self.quadratic_bending(i, x, &scratch.quadratic);
            }
        }
        for (i, f) in rows.zip(out.iter_mut()) {
            self.add_wind(i, f, scratch);
        }
    }

    /// Adds the user forces to the particles' `out`.
    fn add_user_forces(&self, out: &mut [Vec3]) {
        for &(particle, force) in self.user_forces {
            out[particle as usize] += force;
        }
    }

    /// Forces (as [`ForceModel::eval`]) and the derivatives ∂f/∂x and ∂f/∂v over the
    /// topology's pattern. With `definite`, each element gives the semi-definite variant of
    /// its stiffness that conjugate gradients need (for bending: the faces' Gauss–Newton
    /// blocks without the hinges' angle-curvature term). Wind is left out of the derivatives:
    /// implicit solvers treat it explicitly, and so is the springs' damping's dependence on
    /// position, which is not symmetric ([`SpringElement::position_jacobian`]).
    pub fn assemble(
        &self,
        x: &[Vec3],
        v: &[Vec3],
        t: f32,
        definite: bool,
        scratch: &mut ForceScratch,
        out: &mut [Vec3],
        dfdx: &mut SymmetricBlockMatrix,
        dfdv: &mut VelocityJacobian,
    ) {
        self.element_forces(x, v, t, scratch);
        self.derivatives_before_membranes(x, definite, scratch, dfdx, dfdv);
        // The membranes' forces and blocks in one pass, each triangle's from one
        // deformation: computed apart, their forces took 2.5 ms of the 256² hang scene's
        // step.
        let topology = self.topology;
        let (pattern, material, scratch) = (&topology.pattern, &self.membranes.material, &*scratch);
        dfdx.add_by_parts_beside(pattern, &scratch.row_parts.bounds, out, |part, rows, target, first, out| {
            let (low, count) = (rows.start as u32, rows.len() as u32);
            self.gather(part, rows, x, v, scratch, out, |m| {
                let particles = self.membranes.indices[m];
                let element = self.membranes.element(m);
                let (forces, blocks) =
                    element.forces_and_jacobian(material, particles.map(|p| x[p as usize]), definite);
                let positions = topology.membrane_positions.get(m);
                add_part_blocks(pattern, particles, &positions, blocks, (low, count), target, first);
                forces
            });
        });
        self.add_user_forces(out);
        self.add_damping(dfdv);
    }

    /// The derivatives of [`ForceModel::assemble`] at `x`, from the element data (the
    /// hinges' angles, gradients and moments) that [`ForceModel::eval`] left in `scratch`
    /// at the same positions.
    fn derivatives(
        &self,
        x: &[Vec3],
        definite: bool,
        scratch: &mut ForceScratch,
        dfdx: &mut SymmetricBlockMatrix,
        dfdv: &mut VelocityJacobian,
    ) {
        self.derivatives_before_membranes(x, definite, scratch, dfdx, dfdv);
        let (topology, material) = (self.topology, &self.membranes.material);
        let triangles = |m: usize| self.membranes.indices[m];
        let membrane_positions = |m: usize| topology.membrane_positions.get(m);
        let parts = (scratch.row_parts.bounds.as_slice(), &scratch.row_parts.membranes);
        add_elements(dfdx, &topology.pattern, parts, membrane_positions, triangles, |m| {
            let corners = triangles(m).map(|p| x[p as usize]);
            self.membranes.element(m).position_jacobian(material, corners, definite)
        });
        self.add_damping(dfdv);
    }

    /// Adds the linear damping's `−c m I` to ∂f/∂v.
    fn add_damping(&self, dfdv: &mut VelocityJacobian) {
        let rate = self.damping_rate();
        if rate > 0.0 {
            dfdv.add_diagonal(&self.topology.pattern, |i| -rate / self.inv_mass[i]);
        }
    }

    /// The derivatives of [`ForceModel::derivatives`] but the membranes' and the
    /// damping's.
    fn derivatives_before_membranes(
        &self,
        x: &[Vec3],
        definite: bool,
        scratch: &mut ForceScratch,
        dfdx: &mut SymmetricBlockMatrix,
        dfdv: &mut VelocityJacobian,
    ) {
        let topology = self.topology;
        let pattern = &topology.pattern;
        dfdx.reset_to_identities(pattern, scratch.quadratic.refresh(self));
        let damped = (0..self.springs.len()).any(|s| self.spring(s).damping > 0.0);
        dfdv.reset(pattern, damped);
        scratch.row_parts.refresh(self, !definite);
        let ForceScratch { hinge_delta, hinge_gradient, hinge_moment, row_parts, .. } = scratch;
        let bounds = row_parts.bounds.as_slice();
        // A spring's blocks are `[K, −K; −K, K]` for its 3 × 3 derivative `K`.
        let add_springs = |matrix: &mut SymmetricBlockMatrix,
                           derivative: &(dyn Fn(usize, [Vec3; 2]) -> Mat3 + Sync)| {
            let (pairs, spring_positions) = (&self.springs.pairs, &topology.spring_positions);
            add_elements(
                matrix,
                pattern,
                (bounds, &row_parts.springs),
                |s| spring_positions.get(s),
                |s| pairs[s],
                |s| {
                    let k = derivative(s, pairs[s].map(|p| x[p as usize]));
                    [k, -k, k]
                },
            );
        };
        add_springs(dfdx, &|s, [a, b]| self.spring(s).position_jacobian(a, b, definite));
        if let Some(dfdv) = dfdv.full_matrix() {
            add_springs(dfdv, &|s, [a, b]| {
                let spring = self.spring(s);
                if spring.damping > 0.0 { spring.velocity_jacobian(a, b) } else { Mat3::ZERO }
            });
        }
        let bending = self.hinges.view();
        let (faces, face_positions) = (&self.hinges.faces, &topology.face_positions);
        let face_stencil = |f: usize| faces[f].vertices;
        // Quadratic bending's Jacobian, exact and constant, is where the matrix started.
        let quadratic = self.hinges.is_quadratic();
        if !quadratic {
            add_elements(
                dfdx,
                pattern,
                (bounds, &row_parts.faces),
                |f| face_positions.get(f),
                face_stencil,
                |f| bending.face_jacobian(f, hinge_gradient, hinge_delta),
            );
        }
        if !definite && !quadratic {
            // A hinge's blocks are among those of a face beside it (`corners` says where).
            let hinge_positions = |h: usize| {
                let side = topology.hinge_faces.row(h)[0] as usize;
                let (positions, corners) = (face_positions.get(side / 3), faces[side / 3].corners[side % 3]);
                upper_map::<4, 10, _>(|a, b| {
                    positions[upper_pair::<6>(usize::from(corners[a]), usize::from(corners[b]))]
                })
            };
            let hinges = |h: usize| self.hinges.vertices[h];
            add_elements(dfdx, pattern, (bounds, &row_parts.hinges), hinge_positions, hinges, |h| {
                let blocks = bending.hinge_curvature_jacobian(h, x, hinge_moment[h]);
                upper_map::<4, 10, _>(|a, b| blocks[a][b])
            });
        }
    }

    /// Potential energy at positions `x` [J]: gravitational (zero at the origin) plus the
    /// elastic energy of every spring, hinge and membrane triangle. `scratch` holds the
    /// hinge angles.
    pub fn potential_energy(&self, x: &[Vec3], scratch: &mut ForceScratch) -> f64 {
        let gravity = reduce::sum(x.len(), |i| -f64::from(self.gravity.dot(x[i]) / self.inv_mass[i]));
        let springs = reduce::sum(self.springs.len(), |s| {
            let [i, j] = self.springs.pairs[s].map(|p| p as usize);
            f64::from(self.spring(s).energy(x[i], x[j]))
        });
        let bending = self.hinges.view();
        let hinges = if self.hinges.is_quadratic() {
            self.hinges.quadratic.energy(x)
        } else {
            let delta = &mut scratch.hinge_delta;
            delta.resize(self.hinges.vertices.len(), 0.0);
            bending.angles(x, delta);
            reduce::sum(self.hinges.faces.len(), |f| f64::from(bending.face_energy(f, delta)))
        };
        let material = &self.membranes.material;
        let membranes = reduce::sum(self.membranes.indices.len(), |m| {
            let corners = self.membranes.indices[m].map(|p| x[p as usize]);
            f64::from(self.membranes.element(m).energy(material, corners))
        });
        gravity + springs + hinges + membranes
    }
}

/// A cloth's [`ForceModel`] seen as [`Dynamics`]: forces divided by mass, with pinned
/// particles (zero free inverse mass) never accelerating.
pub struct ClothDynamics<'a> {
    /// The forces.
    pub model: ForceModel<'a>,
    /// Inverse masses with pinned particles at zero [1/kg].
    pub free_inv_mass: &'a [f32],
    /// Element buffers for [`ForceModel::eval`].
    pub scratch: &'a mut ForceScratch,
    /// How the cloth's layers meet, where it collides with itself, which bounds block
    /// descent's iterations.
    pub self_collision: Option<LayerContact>,
    /// The other cloths it collides with, which bound block descent's iterations too.
    pub others: Option<Others<'a>>,
    /// The cloth–cloth contacts the implicit step holds apart.
    pub contact_springs: &'a mut [ContactSpring],
    /// The solid bodies where the step ends, which bound block descent's iterations.
    pub bodies: &'a [ContactBody],
    /// The forces at the state of the first linearisation, evaluated there by
    /// [`ForceModel::eval`] with `scratch`, which nothing has used since: that
    /// linearisation takes them, and the element data the evaluation left in `scratch`,
    /// instead of evaluating again. `accumulate_forces` evaluates a cloth that touches a
    /// body at the step's start, where the implicit step linearises next: over sphere_64's
    /// whole run, one evaluation a step, 7 ms of some 135 a frame.
    pub start_force: Option<&'a [Vec3]>,
}

impl Dynamics for ClothDynamics<'_> {
    fn acceleration(&mut self, x: &[Vec3], v: &[Vec3], t: f32, out: &mut [Vec3]) {
        self.model.eval(x, v, t, self.scratch, out);
        out.par_iter_mut()
            .zip(self.free_inv_mass.par_iter())
            .with_min_len(PARALLEL_MIN_LEN)
            .for_each(|(a, w)| *a *= *w);
    }
}

impl LinearDynamics for ClothDynamics<'_> {
    fn pattern(&self) -> &BlockPattern {
        &self.model.topology.pattern
    }

    fn mass(&self, i: usize) -> f32 {
        1.0 / self.model.inv_mass[i]
    }

    fn is_free(&self, i: usize) -> bool {
        self.free_inv_mass[i] > 0.0
    }

    fn colouring(&self) -> &Colouring {
        self.model.topology.colouring(self.model.elements())
    }

    fn contact_surface(&self) -> Option<Surface<'_>> {
        let (triangles, topology) = (self.model.triangles, self.model.topology);
        self.self_collision.map(|_| Surface { triangles, edges: topology.edges(triangles) })
    }

    fn layer_contact(&self) -> Option<LayerContact> {
        self.self_collision
    }

    fn contact_others(&self) -> Option<Others<'_>> {
        self.others
    }

    fn contact_bodies(&self) -> &[ContactBody] {
        self.bodies
    }

    fn hierarchy(&self) -> &Hierarchy {
        self.model.topology.hierarchy(self.model.elements())
    }

    /// The quadratic bending's, whose Jacobian is constant and alone reaches outside the
    /// finest pattern (the springs and membranes are within it).
    fn constant_couplings(&self) -> Option<&ConstantCouplings> {
        self.scratch.quadratic.couplings(&self.model)
    }

    fn contact_springs(&self) -> &[ContactSpring] {
        self.contact_springs
    }

    fn contact_springs_mut(&mut self) -> &mut [ContactSpring] {
        self.contact_springs
    }

    fn linearize(
        &mut self,
        x: &[Vec3],
        v: &[Vec3],
        t: f32,
        force: &mut [Vec3],
        dfdx: &mut SymmetricBlockMatrix,
        dfdv: &mut VelocityJacobian,
    ) {
        match self.start_force.take() {
            Some(start) => {
                force.copy_from_slice(start);
                self.model.derivatives(x, true, self.scratch, dfdx, dfdv);
            }
            None => self.model.assemble(x, v, t, true, self.scratch, force, dfdx, dfdv),
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Affine3A;

    use super::*;
    use crate::builders::grid::build_grid;
    use crate::components::{
        BendingDesc, BendingLawDesc, ClothMaterial, MembraneDesc, Particles, SolverParts, SpringCoefficients, Triangles,
    };

    /// A cloth and its topology, from which a test borrows its force model.
    struct Fixture {
        particles: Particles,
        springs: Springs,
        triangles: Triangles,
        hinges: BendingHinges,
        membranes: MembraneTriangles,
        topology: ClothTopology,
    }

    impl Fixture {
        /// A 4 × 4 cloth with every element kind, deformed and moving, bending by Zheng's law.
        fn new() -> Self {
            Self::bending_by(BendingLawDesc::Zheng { kappa0: 30.0 })
        }

        /// The cloth of [`Fixture::new`] bending by `law`.
        fn bending_by(law: BendingLawDesc) -> Self {
            let spring = Some(SpringCoefficients { stiffness: 40.0, damping: 0.3 });
            let material = ClothMaterial {
                density: 0.2,
                stretch: spring,
                shear: spring,
                bend: None,
                membrane: Some(MembraneDesc::Anisotropic { d1: 300.0, d2: 200.0, d3: 50.0, d4: 30.0 }),
                bending: Some(BendingDesc { warp: 2e-3, weft: 1e-3, twist: None, law }),
            };
            let mut data = build_grid((0.3, 0.3), (4, 4), Affine3A::IDENTITY, &material);
            data.add_surface_elements(&material, Vec3::new(1.0, 0.3, 0.0).normalize()).expect("flat");
            let particles = &mut data.particles;
            for (i, (x, v)) in particles.position.iter_mut().zip(particles.velocity.iter_mut()).enumerate() {
                let f = i as f32;
                *x += Vec3::new(
                    0.01 * (f * 1.3).sin(),
                    0.012 * (f * 0.7).cos(),
                    0.3 * x.x * x.x + 0.02 * (f * 2.1).sin(),
                );
                *v = Vec3::new((f * 0.9).cos(), (f * 1.7).sin(), 0.5 * (f * 0.4).cos());
            }
            let topology =
                ClothTopology::build(&data.particles.inv_mass, data.elements(), &[], 1, SolverParts::default());
            let (particles, springs, triangles, hinges, membranes) =
                (data.particles, data.springs, data.triangles, data.hinges, data.membranes);
            Self { particles, springs, triangles, hinges, membranes, topology }
        }

        /// The cloth's forces in `air`, under gravity, with `user_forces`.
        fn model<'a>(&'a self, air: Air, user_forces: &'a [(u32, Vec3)]) -> ForceModel<'a> {
            ForceModel {
                inv_mass: &self.particles.inv_mass,
                density: 0.2,
                springs: &self.springs,
                triangles: &self.triangles.indices,
                hinges: &self.hinges,
                membranes: &self.membranes,
                topology: &self.topology,
                gravity: Vec3::new(0.0, -9.81, 0.0),
                air,
                user_forces,
            }
        }
    }

    /// The fixtures of the force model's tests: bending by Zheng's law and quadratic.
    fn fixtures() -> [Fixture; 2] {
        [Fixture::new(), Fixture::bending_by(BendingLawDesc::Quadratic)]
    }

    #[test]
    fn assembled_derivatives_match_differences_of_the_whole_force_model() {
        for fixture in fixtures() {
            derivatives_match_differences(&fixture);
        }
    }

    fn derivatives_match_differences(fixture: &Fixture) {
        let (topology, model) =
            (&fixture.topology, fixture.model(Air { drag: 0.7, area_damping: 0.1, ..Air::default() }, &[]));
        let x = &fixture.particles.position;
        let n = x.len();
        // At rest, where the springs' damping does not depend on position: ∂f/∂x leaves
        // that part out ([`ForceModel::assemble`]). ∂f/∂v does not depend on velocity.
        let v = &vec![Vec3::ZERO; n];
        let mut scratch = ForceScratch::default();
        let (mut force, mut dfdx, mut dfdv) =
            (vec![Vec3::ZERO; n], SymmetricBlockMatrix::default(), VelocityJacobian::default());
        model.assemble(x, v, 0.0, false, &mut scratch, &mut force, &mut dfdx, &mut dfdv);
        let force_at = |x: &[Vec3], v: &[Vec3]| {
            let mut out = vec![Vec3::ZERO; n];
            model.eval(x, v, 0.0, &mut ForceScratch::default(), &mut out);
            out
        };
        let h = 1e-4;
        for b in 0..n {
            for axis in 0..3 {
                let mut step = Vec3::ZERO;
                step[axis] = h;
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[b] += step;
                xm[b] -= step;
                // Forces are linear in velocity: a large step has no truncation error and
                // keeps f32 rounding small.
                let (mut vp, mut vm) = (v.clone(), v.clone());
                vp[b] += 500.0 * step;
                vm[b] -= 500.0 * step;
                let (fxp, fxm, fvp, fvm) = (force_at(&xp, v), force_at(&xm, v), force_at(x, &vp), force_at(x, &vm));
                for a in 0..n {
                    let numeric_x = (fxp[a] - fxm[a]) / (2.0 * h);
                    let numeric_v = (fvp[a] - fvm[a]) / (1000.0 * h);
                    let (a, b) = (a as u32, b as u32);
                    // The coupling across an edge, if any (a row holds a column once).
                    let across = scratch
                        .quadratic
                        .couplings(&model)
                        .map_or(0.0, |c| c.fold(a as usize, 0.0, |found, j, s| if j == b { s } else { found }));
                    let across = Mat3::from_diagonal(Vec3::splat(across));
                    let analytic_x = (dfdx.block(&topology.pattern, a, b) + across).col(axis);
                    let analytic_v = dfdv.block(&topology.pattern, a, b).col(axis);
                    let scale = numeric_x.length().max(analytic_x.length()).max(1.0);
                    assert!(
                        (analytic_x - numeric_x).length() <= 2e-2 * scale,
                        "∂f{a}/∂x{b}[{axis}]: {analytic_x} against {numeric_x}"
                    );
                    assert!(
                        (analytic_v - numeric_v).length() <= 1e-2 * numeric_v.length().max(0.1),
                        "∂f{a}/∂v{b}[{axis}]: {analytic_v} against {numeric_v}"
                    );
                }
            }
        }
    }

    /// The force on a few pinned particles from their own elements is bit for bit the
    /// force the whole cloth's evaluation gives them, with every element kind, wind, gusts
    /// and user forces (one particle pushed twice), in the order they were pinned (one
    /// pinned twice).
    #[test]
    fn the_force_on_the_pinned_particles_matches_the_whole_evaluation() {
        for fixture in fixtures() {
            pin_forces_match_the_whole_evaluation(&fixture);
        }
    }

    fn pin_forces_match_the_whole_evaluation(fixture: &Fixture) {
        let user_forces = [(5, Vec3::new(0.1, 0.2, -0.3)), (9, Vec3::X), (5, Vec3::new(-0.02, 0.0, 0.7))];
        let air = Air {
            drag: 0.7,
            area_damping: 0.1,
            wind: Vec3::new(1.0, 0.5, 3.0),
            wind_drag: 0.6,
            gust: Some(Gust { amplitude: 0.4, period_s: 1.3 }),
        };
        let chosen = [9, 0, 5, 6, 15, 5];
        let pinned = ClothTopology::build(
            &fixture.particles.inv_mass,
            fixture.model(air, &user_forces).elements(),
            &chosen,
            1,
            SolverParts::default(),
        );
        let model = ForceModel { topology: &pinned, ..fixture.model(air, &user_forces) };
        let (x, v) = (&fixture.particles.position, &fixture.particles.velocity);
        let mut whole = vec![Vec3::ZERO; x.len()];
        model.eval(x, v, 0.4, &mut ForceScratch::default(), &mut whole);
        // The scratch holds another state's hinge angles, as between steps.
        let mut scratch = ForceScratch::default();
        let elsewhere: Vec<Vec3> = x.iter().map(|p| 1.1 * *p + Vec3::Y * p.x * p.z).collect();
        model.eval(&elsewhere, v, 0.4, &mut scratch, &mut vec![Vec3::ZERO; x.len()]);
        let local: Vec<Vec3> = model.pin_forces(x, v, 0.4, &mut scratch).collect();
        let expected: Vec<Vec3> = chosen.iter().map(|&p| whole[p as usize]).collect();
        assert_eq!(local, expected);
        assert!(expected.iter().all(|f| f.length() > 0.0));
    }

    /// A linearisation that takes the start force evaluated before it (and the element
    /// data that evaluation left in the scratch) gives the bits of one that evaluates, and
    /// takes it only once: the next linearisation, at another state, evaluates there. The
    /// one evaluates the membranes' forces with their blocks ([`ForceModel::assemble`]),
    /// the other apart ([`ForceModel::eval`], then [`ForceModel::derivatives`]).
    #[test]
    fn a_linearisation_taking_the_start_force_matches_one_that_evaluates() {
        for fixture in fixtures() {
            linearisations_match(&fixture);
        }
    }

    fn linearisations_match(fixture: &Fixture) {
        let air = Air { drag: 0.7, area_damping: 0.1, wind: Vec3::new(1.0, 0.5, 3.0), wind_drag: 0.6, gust: None };
        let user_forces = [(5, Vec3::new(0.1, 0.2, -0.3))];
        let model = fixture.model(air, &user_forces);
        let (x, v) = (&fixture.particles.position, &fixture.particles.velocity);
        let elsewhere: Vec<Vec3> = x.iter().map(|p| 1.1 * *p + Vec3::Y * p.x * p.z).collect();
        let n = x.len();
        let linearisations = |given: bool| {
            let mut scratch = ForceScratch::default();
            let mut start = vec![Vec3::ZERO; n];
            if given {
                model.eval(x, v, 0.4, &mut scratch, &mut start);
            }
            let mut dynamics = ClothDynamics {
                model,
                free_inv_mass: &fixture.topology.free_inv_mass,
                scratch: &mut scratch,
                self_collision: None,
                others: None,
                contact_springs: &mut [],
                bodies: &[],
                start_force: given.then_some(&start),
            };
            [x, &elsewhere].map(|at| {
                let (mut force, mut dfdx, mut dfdv) =
                    (vec![Vec3::ZERO; n], SymmetricBlockMatrix::default(), VelocityJacobian::default());
                dynamics.linearize(at, v, 0.4, &mut force, &mut dfdx, &mut dfdv);
                (force, dfdx, dfdv)
            })
        };
        let (taken, evaluated) = (linearisations(true), linearisations(false));
        assert_eq!(taken, evaluated);
        assert_ne!(evaluated[0].0, evaluated[1].0);
        assert!(evaluated[0].1.blocks.iter().any(|b| *b != Mat3::ZERO));
    }

    #[test]
    fn wind_on_a_facing_triangle_is_drag_times_area_times_speed_squared() {
        // A right triangle of area 0.5 m² in the xy plane, wind 4 m/s along +z.
        let x = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let per_vertex = triangle_wind_force(x, [Vec3::ZERO; 3], Vec3::new(0.0, 0.0, 4.0), 0.6);
        let total = 3.0 * per_vertex;
        assert!((total - Vec3::new(0.0, 0.0, 0.6 * 0.5 * 16.0)).length() < 1e-5);
        // Wind in the plane of the cloth exerts no normal drag.
        let edge_on = triangle_wind_force(x, [Vec3::ZERO; 3], Vec3::new(4.0, 0.0, 0.0), 0.6);
        assert_eq!(edge_on, Vec3::ZERO);
    }

    #[test]
    fn gusts_modulate_the_wind_around_its_mean() {
        let air = Air { wind: Vec3::X, gust: Some(Gust { amplitude: 0.5, period_s: 2.0 }), ..Air::default() };
        assert!((air.wind_at(0.5) - Vec3::new(1.5, 0.0, 0.0)).length() < 1e-6);
        assert!((air.wind_at(1.5) - Vec3::new(0.5, 0.0, 0.0)).length() < 1e-6);
    }
}
