//! Cloth against cloth (E3, Z5, Z7, D11): after each step, the motion of every vertex
//! from where the step started to where it ended is made free of crossings, in three
//! stages of increasing force (Bridson, Fedkiw and Anderson 2002; Zheng §3.2–3.5):
//!
//! 1. **Proximity.** Point–triangle and edge–edge pairs closer than their separation δ at
//!    the start of the step get an inelastic impulse that stops their approach and
//!    restores a fraction of the missing gap, with Coulomb friction.
//! 2. **Continuous collision.** Pairs whose straight-line paths become coplanar within
//!    the step (the cubic of Zheng eq. 3.22) and touch there get an impulse that leaves
//!    them a sliver apart at the end of the step; repeated for a few passes.
//! 3. **Impact zones** (Provot 1997, Bridson 2002). Vertices of collisions still left are
//!    merged into zones that move rigidly for the step; zones grow until nothing collides.
//!    A rigid motion cannot create a crossing inside a zone, so if the step started
//!    untangled it ends untangled; in the last resort every vertex keeps its start
//!    position.
//!
//! Before these, while the mesh may be tangled (at first, and until a step finds it is
//! not), edges crossing triangles are moved back through ([`super::untangle`]); the
//! vertices moved are left out of the three stages for that step.
//!
//! Impulses are split by mass (Zheng eq. 3.30, Bridson's weights): a pinned vertex has
//! infinite mass and does not move. Impulses are applied one pair after another in a
//! fixed order, so results do not depend on the thread count.

use std::collections::BTreeMap;

use glam::{Quat, Vec3};
use rayon::prelude::*;

use super::bvh::{Aabb, Bvh};
use super::primitives::{Sweep, closest_between_segments, closest_on_triangle};
use super::untangle::Untangler;
use crate::solver::PARALLEL_MIN_LEN;
use crate::solver::contact_springs::{ContactSpring, Outside, Stencil, spring_step};
use crate::solver::elements::spring::outer;
use crate::solver::gather::{Gather, reserve_floored};

/// The cloths that collide with one another, as one mesh with global vertex numbers.
#[derive(Debug, Clone, Default)]
pub struct ContactMesh {
    /// Triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Edges of the triangles, each once, smaller vertex first.
    pub edges: Vec<[u32; 2]>,
    /// Inverse masses, zero for pinned vertices [1/kg]: what impact zones weigh.
    pub inv_mass: Vec<f32>,
    /// Inverse masses for impulses: also zero for vertices that impulses should not move,
    /// such as those resting on a body (so that cloth falling on them does not push
    /// them into it) [1/kg].
    pub impulse_inv_mass: Vec<f32>,
    /// Half the separation each vertex keeps from other cloth [m]: a pair keeps the sum of
    /// its two sides' halves.
    pub half_gap: Vec<f32>,
    /// Each vertex's Coulomb friction coefficient; a pair uses the mean of its sides.
    pub friction: Vec<f32>,
    /// Each vertex's layer: a higher layer belongs on the side of a lower layer's
    /// triangle normals, which is how untangling knows which side is wrong.
    pub layer: Vec<u32>,
    /// Each cloth's first vertex (the cloths numbered by their place in the mesh), and
    /// after the last cloth's the number of vertices.
    pub first: Vec<u32>,
    /// Whether the cloths' implicit steps hold their close pairs apart with
    /// [`ContactSpring`]s ([`SelfContactSolver::springs`]).
    pub springs: bool,
}

impl ContactMesh {
    /// The edges of `triangles`, each once, sorted. Gathered once per side, so twice over
    /// inside a sheet; the list is shrunk to the edges, since every cloth keeps it for its
    /// lifetime (24 bytes a particle otherwise).
    pub fn edges_of(triangles: &[[u32; 3]]) -> Vec<[u32; 2]> {
        let mut edges: Vec<[u32; 2]> = triangles
            .iter()
            .flat_map(|&[a, b, c]| [[a, b], [b, c], [c, a]])
            .map(|[p, q]| [p.min(q), p.max(q)])
            .collect();
        edges.sort_unstable();
        edges.dedup();
        edges.shrink_to_fit();
        edges
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.half_gap.len()
    }

    /// Whether the mesh has no vertex.
    pub fn is_empty(&self) -> bool {
        self.half_gap.is_empty()
    }

    /// Vertex `k`'s cloth.
    pub fn cloth_of(&self, k: u32) -> u32 {
        (self.first.partition_point(|&first| first <= k) - 1) as u32
    }

    /// Whether impulses leave vertex `k` where it is: pinned, or resting on a body.
    pub fn held(&self, k: u32) -> bool {
        self.impulse_inv_mass[k as usize] == 0.0
    }
}

/// Fraction of the missing gap a proximity impulse restores in one step.
const GAP_RECOVERY: f32 = 0.25;
/// Fraction of the missing gap the contact springs of the next implicit step restore in
/// it, of a pair at rest with no other force: `k h² / (m + k h²)` under implicit Euler,
/// for a step no longer than
/// [`SPRING_STEP`](crate::solver::contact_springs::SPRING_STEP) (more in a longer one).
const SPRING_RECOVERY: f32 = 0.95;
/// `k h² / m` of the contact springs.
const SPRING_RATIO: f32 = SPRING_RECOVERY / (1.0 - SPRING_RECOVERY);
/// Distance, in separations, within which a pair beyond its separation gets an armed
/// contact spring for the next implicit step ([`spring`]).
const SPRING_REACH: f32 = 2.0;
/// Gap, as a fraction of δ, a continuous-collision impulse leaves between a pair.
const IMPACT_GAP: f32 = 0.1;
/// Passes of continuous collision before impact zones take over.
const IMPACT_PASSES: u32 = 6;
/// Rounds of zone growth before every vertex is held at its start.
const ZONE_ROUNDS: u32 = 100;

/// What self-contact did in one step.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SelfContactReport {
    /// Pairs closer than their separation at the start of the step.
    pub proximity: u32,
    /// Continuous collisions resolved by impulses.
    pub impacts: u32,
    /// Rounds of impact zones needed (0 when impulses sufficed).
    pub zone_rounds: u32,
    /// Whether the last resort held every vertex at its start.
    pub frozen: bool,
    /// Edge–triangle crossings found at the start of the step and being untangled.
    pub crossings: u32,
}

impl SelfContactReport {
    /// Adds `other` to these counts.
    pub fn add(&mut self, other: &SelfContactReport) {
        self.proximity += other.proximity;
        self.impacts += other.impacts;
        self.zone_rounds += other.zone_rounds;
        self.frozen |= other.frozen;
        self.crossings += other.crossings;
    }
}

/// A pair that needs an impulse: along `normal`, their relative velocity must reach
/// `target` [m/s].
#[derive(Debug, Clone, Copy)]
struct Contact {
    stencil: Stencil,
    normal: Vec3,
    target: f32,
    friction: f32,
}

/// A candidate pair of primitives.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Pair {
    /// A vertex and a triangle (index).
    PointTriangle(u32, u32),
    /// Two edges (indices).
    EdgeEdge(u32, u32),
}

impl Pair {
    /// The order of a listing ([`SelfContactSolver::candidates`]): the points' pairs
    /// first, by point and then triangle, then the edges' pairs.
    fn key(self) -> (bool, u32, u32) {
        match self {
            Pair::PointTriangle(p, t) => (false, p, t),
            Pair::EdgeEdge(e, f) => (true, e, f),
        }
    }
}

/// At most one vertex in this many may have moved away for [`SelfContactSolver::mend`]
/// to list theirs alone rather than every pair again. A mend costs about 20 µs a moved
/// vertex and 0.3 ms besides, a whole listing 3.5 ms on sphere_64 and 5.7 on fold_64;
/// and a mend moves only the vertices that left, so the others, nearer the edge of what
/// they are listed for, call for the next mend sooner than a whole listing would. Listing
/// and mending over whole runs took fold_64, sphere_64 and sphere_64_adaptive 3.69, 1.58
/// and 0.82 s at one in 64, against 3.97, 1.67 and 1.21 listing alone; 4.13, 1.95 and
/// 0.71 at one in 16; 3.73, 1.66 and 0.98 at one in 256.
const MEND_SHARE: usize = 64;

/// Vertices whose displacements give [`SelfContactSolver::typical_motion`]: few enough
/// to take their median on the stack.
const TYPICAL_SAMPLES: usize = 255;

/// How many margins long a mended vertex's sweep may be ([`SelfContactSolver::mend`]): a
/// whole listing keeps the ends of sweeps longer than one margin alone, for memory, but a
/// few vertices' longer boxes cost little.
const MEND_SWEEP: f32 = 4.0;

/// Levels below the edge tree's root at which its pairs with itself are split into
/// independent parts: about 2¹⁰ subtrees, each with itself and with the few whose boxes
/// meet it, enough parts to share among the threads.
const EDGE_ROOT_DEPTH: u32 = 10;

/// The largest separation of a pair of `mesh`.
fn largest_gap(mesh: &ContactMesh) -> f32 {
    2.0 * mesh.half_gap.iter().fold(0.0f32, |m, g| m.max(*g))
}

/// The trees' margin in separations. A wider margin keeps a candidate list for more
/// steps (it serves while no end point has moved half the margin) but lists more pairs,
/// each measured at every step. Listing is the costly part (4 to 8 ms on sphere_64 and
/// fold_64). Self contact over sphere_64's first 90 frames, and fold_64's first 60, took
/// 3.2 and 5.0 s at one separation (with boxes grown by a whole margin each, before
/// [`SelfContactSolver::grown`] and the edge tree's pairs with itself), 2.5 and 4.8 s at
/// two; with both, 2.0 and 4.2 s at two (377 and 466 listings), 1.9 and 5.1 s at three,
/// 2.2 and 5.8 s at four. The frames are the same, to the bit, whatever the margin.
const MARGIN_GAPS: f32 = 2.0;

/// The trees and scratch space kept from step to step.
#[derive(Debug, Default)]
pub struct SelfContactSolver {
    /// The triangles' and the edges' boxes swept over the step, grown
    /// ([`SelfContactSolver::refit`]).
    triangle_tree: Bvh,
    edge_tree: Bvh,
    /// Mean velocity of each vertex over the step, as the contacts change it.
    mean_velocity: Vec<Vec3>,
    /// The mean velocities the step came with.
    initial_velocity: Vec<Vec3>,
    /// Zone of each vertex (a union-find forest), for impact zones.
    zone: Vec<u32>,
    /// Untangling of crossings found at the start of a step.
    untangler: Untangler,
    /// Candidate pairs whose swept boxes meet.
    pairs: Vec<Pair>,
    /// Where each vertex's sweep ended when the candidates were listed (or mended, moved
    /// back by the motion most vertices shared then, [`SelfContactSolver::mend`]).
    listed_end: Vec<Vec3>,
    /// Whether the candidates serve while each vertex stays near the box of its whole
    /// listed sweep, not only near its end: where no sweep of the listing was longer than
    /// the margin ([`SelfContactSolver::candidates_cover`]).
    sweeps_listed: bool,
    /// Where each sweep started then, kept only where the sweeps were listed.
    listed_start: Vec<Vec3>,
    /// Whether some vertex was exempt (being untangled) when they were listed, which
    /// left its pairs out.
    listed_with_exemptions: bool,
    /// The vertices [`SelfContactSolver::mend`] lists again, and the pairs it finds.
    moved: Vec<bool>,
    mended: Vec<Pair>,
    /// Whether every vertex lay in a triangle at the last listing: a mend finds the pairs
    /// of a point that stayed through its triangles' boxes.
    points_in_triangles: bool,
    /// Vertices a pass of continuous collision moved or left colliding.
    dirty: Vec<bool>,
    /// Proximity contacts among the candidates.
    contacts: Vec<Contact>,
    /// Those of a held point, moved after the others ([`held_last`]).
    held_contacts: Vec<Contact>,
    /// Candidates whose paths touch.
    hits: Vec<Pair>,
    /// Those of a held point, moved after the others ([`held_last`]).
    held_hits: Vec<Pair>,
    /// Per-task buffers for gathering pairs and contacts without allocating.
    pair_gather: Gather<Pair>,
    /// The edge tree's subtree pairs ([`Bvh::self_overlap_roots`]), and the edge pairs
    /// listed under them, sorted.
    edge_roots: Vec<[u32; 2]>,
    edge_pairs: Vec<[u32; 2]>,
    edge_gather: Gather<[u32; 2]>,
    contact_gather: Gather<Contact>,
    spring_gather: Gather<ContactSpring>,
}

impl SelfContactSolver {
    /// Makes the step from `x0` to `x1` (length `h`) free of crossings of `mesh` with
    /// itself, moving `x1` and changing the end velocities `v` by what the contacts
    /// changed the step's mean velocity.
    pub fn resolve(
        &mut self,
        mesh: &ContactMesh,
        h: f32,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v: &mut [Vec3],
    ) -> SelfContactReport {
        let mut report = SelfContactReport::default();
        if mesh.triangles.is_empty() || h <= 0.0 {
            return report;
        }
        if self.untangler.watching() {
            self.refit(mesh, x0, x1);
            report.crossings = self.untangler.run(mesh, &self.triangle_tree, h, x0, x1, v);
        } else {
            self.untangler.clear(mesh.len());
        }
        self.mean_velocity.clear();
        self.mean_velocity.extend(x0.iter().zip(x1.iter()).map(|(a, b)| (*b - *a) / h));
        self.initial_velocity.clone_from(&self.mean_velocity);
        self.dirty.resize(mesh.len(), false);

        // 1. Proximity at the start of the step. The last step's candidates still serve
        // while both ends of this step's sweeps are within half the margin of where they
        // were listed for (see `candidates_cover`), as on cloth at rest, or once the few
        // vertices that left are listed again (`mend`), and none were left out for
        // untangling.
        let exemptions = self.untangler.watching() || self.listed_with_exemptions;
        let kept = !exemptions
            && (self.candidates_cover(mesh, x0) && self.candidates_cover(mesh, x1) || self.mend(mesh, x0, x1));
        if !kept {
            self.candidates(mesh, x0, x1);
        }
        let pairs = &self.pairs;
        self.contact_gather.run(pairs.len(), &mut self.contacts, |i, out| out.extend(proximity(mesh, pairs[i], h, x0)));
        // A point–triangle contact's point is its stencil's first vertex, weighed 1.
        let held = |c: &Contact| c.stencil.weights[0] == 1.0 && mesh.held(c.stencil.vertices[0]);
        held_last(&mut self.contacts, &mut self.held_contacts, held);
        report.proximity = self.contacts.len() as u32;
        for contact in &self.contacts {
            apply(contact, mesh, &mut self.mean_velocity);
        }
        advance(x0, &self.mean_velocity, h, x1);

        // 2. Continuous collision, pass after pass. The candidates are listed again only
        // when some end point has moved by half the margin since they were; and since a
        // pair's sweep depends on its four vertices alone, a pass after the first looks
        // only at pairs sharing a vertex with the last pass's hits (the only vertices its
        // impulses moved, and the hits that may remain).
        let mut remaining = true;
        for pass in 0..IMPACT_PASSES {
            let covered = self.candidates_cover(mesh, x1);
            if !covered && !self.mend(mesh, x0, x1) {
                self.candidates(mesh, x0, x1);
            }
            self.impacts(mesh, h, x0, x1, pass > 0 && covered);
            if self.hits.is_empty() {
                remaining = false;
                break;
            }
            for &pair in &self.hits {
                // Earlier impulses of this pass may have resolved or changed it.
                if let Some(contact) = impact(mesh, pair, h, x0, x1) {
                    report.impacts += 1;
                    apply(&contact, mesh, &mut self.mean_velocity);
                    for &k in &contact.stencil.vertices {
                        let k = k as usize;
                        x1[k] = x0[k] + h * self.mean_velocity[k];
                    }
                }
            }
        }

        // 3. Impact zones for whatever is left.
        if remaining {
            self.zone.clear();
            self.zone.extend(0..mesh.len() as u32);
            loop {
                self.candidates(mesh, x0, x1);
                self.impacts(mesh, h, x0, x1, false);
                if self.hits.is_empty() {
                    break;
                }
                if report.zone_rounds == ZONE_ROUNDS {
                    for (k, w) in mesh.inv_mass.iter().enumerate() {
                        if *w > 0.0 {
                            self.mean_velocity[k] = Vec3::ZERO;
                        }
                    }
                    advance(x0, &self.mean_velocity, h, x1);
                    report.frozen = true;
                    break;
                }
                report.zone_rounds += 1;
                for &pair in &self.hits {
                    let vertices = pair_vertices(mesh, pair);
                    for k in &vertices[1..] {
                        union(&mut self.zone, vertices[0], *k);
                    }
                }
                self.move_zones_rigidly(mesh, h, x0);
                advance(x0, &self.mean_velocity, h, x1);
            }
        }

        for k in 0..mesh.len() {
            if mesh.inv_mass[k] > 0.0 {
                v[k] += self.mean_velocity[k] - self.initial_velocity[k];
            }
        }
        if report.zone_rounds > 0 {
            // A zone holding moving pinned vertices is not rigid and may have let cloth
            // through: look again next step.
            self.untangler.watch();
        }
        report
    }

    /// Lists in `springs` the pairs closer than their separation at `x1`, where the step
    /// from `x0` that [`SelfContactSolver::resolve`] just made free of crossings ended
    /// (with velocities `v`) and the next step of length `h` starts: the springs that hold
    /// them apart in it.
    pub fn springs(
        &mut self,
        mesh: &ContactMesh,
        h: f32,
        x0: &[Vec3],
        x1: &[Vec3],
        v: &[Vec3],
        springs: &mut Vec<ContactSpring>,
    ) {
        springs.clear();
        if !mesh.springs || mesh.triangles.is_empty() || h <= 0.0 {
            return;
        }
        if !self.candidates_cover(mesh, x1) && !self.mend(mesh, x0, x1) {
            self.candidates(mesh, x0, x1);
        }
        let pairs = &self.pairs;
        self.spring_gather.run(pairs.len(), springs, |i, out| out.extend(spring(mesh, pairs[i], h, x1, v)));
    }

    /// How far an end point may move, beyond the motion common to all, while a candidate
    /// list serves, twice over ([`SelfContactSolver::candidates_cover`]): [`MARGIN_GAPS`]
    /// times the largest separation of a pair, `gap` ([`largest_gap`]).
    fn margin(gap: f32) -> f32 {
        MARGIN_GAPS * gap
    }

    /// How much the trees' boxes (and a point's query box) are grown: half of the largest
    /// separation and the margin, so that two boxes meet wherever their primitives are
    /// within both ([`SelfContactSolver::candidates_cover`]). Grown by the whole margin
    /// each (a third more at two separations), they met pairs that the exact test
    /// ([`may_touch`]) then left out: fold_64's first 60 frames listed for 5.0 s against
    /// 3.8.
    fn grown(gap: f32) -> f32 {
        0.5 * (gap + Self::margin(gap))
    }

    /// Refits the trees to the boxes swept from `x0` to `x1` (grown) and lists in `pairs`
    /// the point–triangle and edge–edge pairs whose boxes meet and which may come within
    /// their separation while listed ([`may_touch`]), leaving out pairs that share a
    /// vertex or hold one being untangled: the points' pairs first, each point's and each
    /// edge's sorted. A point's box is grown too, as both edges' are, so that pairs stay
    /// listed while their ends move under half the margin
    /// ([`SelfContactSolver::candidates_cover`]): with only the
    /// triangle's box grown, a pair a point–triangle spring needed was missed on the fold
    /// heap (180 springs in a step instead of 181).
    fn candidates(&mut self, mesh: &ContactMesh, x0: &[Vec3], x1: &[Vec3]) {
        self.refit(mesh, x0, x1);
        let gap = largest_gap(mesh);
        let (margin, grown) = (Self::margin(gap), Self::grown(gap));
        let longest_sweep =
            x0.par_iter().zip(x1).with_min_len(PARALLEL_MIN_LEN).map(|(a, b)| a.distance(*b)).reduce(|| 0.0, f32::max);
        let sweeps = longest_sweep <= margin;
        self.sweeps_listed = sweeps;
        self.listed_start.clear();
        if sweeps {
            self.listed_start.extend_from_slice(x0);
        }
        self.listed_end.clear();
        self.listed_end.extend_from_slice(x1);
        // The triangles' vertices, marked in the mend's scratch: its room is made while
        // warming up, not in a step long after, and the mesh is the same till the next
        // listing.
        self.moved.clear();
        self.moved.resize(x1.len(), false);
        for &k in mesh.triangles.iter().flatten() {
            self.moved[k as usize] = true;
        }
        self.points_in_triangles = !self.moved.contains(&false);
        let (triangle_tree, edge_tree) = (&self.triangle_tree, &self.edge_tree);
        let exempt = &self.untangler.exempt;
        let free = |vertices: &[u32]| !vertices.iter().any(|&k| exempt[k as usize]);
        self.listed_with_exemptions = exempt.contains(&true);
        let points = mesh.len();
        self.pair_gather.run(points, &mut self.pairs, |i, out| {
            let p = i as u32;
            if free(&[p]) {
                let start = out.len();
                triangle_tree.query(&swept_box(&[p], x0, x1).inflated(grown), |t| {
                    let triangle = &mesh.triangles[t as usize];
                    let pair = Pair::PointTriangle(p, t);
                    if !triangle.contains(&p) && free(triangle) && may_touch(mesh, pair, x0, x1, margin, sweeps) {
                        out.push(pair);
                    }
                });
                out[start..].sort_unstable_by_key(|pair| match *pair {
                    Pair::PointTriangle(_, t) | Pair::EdgeEdge(_, t) => t,
                });
            }
        });
        // The edge tree against itself, pairs of subtrees in parallel: a query per edge, each
        // from the root, took 9 % longer on sphere_64.
        edge_tree.self_overlap_roots(EDGE_ROOT_DEPTH, &mut self.edge_roots);
        let roots = &self.edge_roots;
        self.edge_gather.run(roots.len(), &mut self.edge_pairs, |i, out| {
            edge_tree.overlaps_below(roots[i], |e, f| {
                let ([a, b], [c, d]) = (mesh.edges[e as usize], mesh.edges[f as usize]);
                if a != c
                    && a != d
                    && b != c
                    && b != d
                    && free(&[a, b, c, d])
                    && may_touch(mesh, Pair::EdgeEdge(e, f), x0, x1, margin, sweeps)
                {
                    out.push([e, f]);
                }
            });
        });
        self.edge_pairs.sort_unstable();
        self.pairs.extend(self.edge_pairs.iter().map(|&[e, f]| Pair::EdgeEdge(e, f)));
        reserve_floored(&mut self.mended, self.pairs.len());
    }

    /// Whether the candidates still cover the sweeps to `x1`: no end point, moved back by
    /// a motion common to all of them (the centre of the box of their displacements since
    /// the listing's end, [`SelfContactSolver::common_motion`], or else the motion most of
    /// them share, [`SelfContactSolver::typical_motion`]), which brings no pair closer,
    /// lies farther than half the margin
    /// from where it was listed for: its sweep's end, or where
    /// [`SelfContactSolver::sweeps_listed`] the box of its whole sweep. (A pair's swept
    /// boxes, so moved back, are then each within half the margin of those listed, so a
    /// pair that can come within its separation still had listed boxes closer than its
    /// separation and the margin, which they were grown by together
    /// ([`SelfContactSolver::grown`]).
    /// The sweeps' starts must be covered too, which they are within the step that listed
    /// them, and are checked the same way for a later step's; at any time between, the
    /// common motion is a blend of the two.) A falling sheet, moving 5 mm a step at 10
    /// steps a frame against a half margin of 2 mm, lists its candidates again at every
    /// step, most of sphere_64's fall.
    ///
    /// The box of the listed sweep, not its end alone, where the sweeps were short: a
    /// vertex caught between the step and the contacts goes back and forth over the same
    /// few millimetres, the step carrying it one way and the contacts after it back. On
    /// sphere_64's drape stepped once a frame with multigrid, two vertices of a fold went
    /// 2.5 to 2.8 mm each way every step, beyond the 2 mm half margin from the listing's
    /// end, and listing the candidates twice a step (after the step, and for the springs
    /// of the next) took 5.7 of a resting frame's 15 ms. Sweeps longer than the margin (a
    /// landing) keep the end alone: the boxes' wider reach ([`may_touch`]) listed more
    /// pairs there: with every sweep listed so, sphere_64's peak memory grew by 8 % (3 053
    /// against 2 824 bytes a particle).
    fn candidates_cover(&self, mesh: &ContactMesh, x1: &[Vec3]) -> bool {
        if x1.len() != self.listed_end.len() {
            return false;
        }
        let half = 0.5 * Self::margin(largest_gap(mesh));
        // Where only the ends were listed, each vertex's box is its end alone.
        let start = if self.sweeps_listed { &self.listed_start } else { &self.listed_end };
        let covered = |common: Vec3| {
            x1.par_iter()
                .zip(start)
                .zip(&self.listed_end)
                .with_min_len(PARALLEL_MIN_LEN)
                .all(|((now, start), end)| !beyond(*now - common, *start, *end, half))
        };
        covered(self.common_motion(x1)) || covered(self.typical_motion(x1))
    }

    /// The motion common to all vertices since the candidates were listed, from where
    /// they were listed for to `x` ([`SelfContactSolver::candidates_cover`]): the centre
    /// of the box of their displacements, which leaves the farthest any vertex is from
    /// where it was listed for the least.
    fn common_motion(&self, x: &[Vec3]) -> Vec3 {
        let (low, high) = x
            .par_iter()
            .zip(&self.listed_end)
            .with_min_len(PARALLEL_MIN_LEN)
            .map(|(now, listed)| (*now - *listed, *now - *listed))
            .reduce(|| (Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), (c, d)| (a.min(c), b.max(d)));
        0.5 * (low + high)
    }

    /// The motion most vertices share since the candidates were listed, to `x`: the
    /// median, axis by axis, of the displacements of [`TYPICAL_SAMPLES`] vertices spread
    /// over the mesh. The centre of [`SelfContactSolver::common_motion`] lies midway
    /// between the extremes, so where a few vertices move away, the vertices at the other
    /// extreme are as far from it as they are. Mending around the centre instead, over
    /// whole runs: sphere_64 1 976 mends against 974 (listing and mending 1.65 s against
    /// 1.53), sphere_64_adaptive 244 listings against 211 (0.92 s against 0.81).
    fn typical_motion(&self, x: &[Vec3]) -> Vec3 {
        let stride = x.len().div_ceil(TYPICAL_SAMPLES).max(1);
        let mut samples = [0.0f32; TYPICAL_SAMPLES];
        let count = x.len().div_ceil(stride);
        let mut median = [0.0f32; 3];
        for (axis, median) in median.iter_mut().enumerate() {
            let displacements =
                x.iter().zip(&self.listed_end).step_by(stride).map(|(now, listed)| (*now - *listed)[axis]);
            for (sample, displacement) in samples.iter_mut().zip(displacements) {
                *sample = displacement;
            }
            *median = *samples[..count].select_nth_unstable_by(count / 2, f32::total_cmp).1;
        }
        Vec3::from_array(median)
    }

    /// Makes the candidates cover the step from `x0` to `x1` again where a few vertices
    /// have left what they were listed for, and returns whether it did. Moved back by the
    /// motion most vertices share at each end ([`SelfContactSolver::typical_motion`]),
    /// those vertices are listed for their sweep now, and their pairs are found again as
    /// a whole listing would find them were every vertex where it is listed for: the list
    /// stays the one a listing over those positions makes, pair for pair and in its
    /// order, so a pair of two vertices that stayed keeps the reason it was (or was not)
    /// listed for. The trees' boxes of the moved vertices' primitives are put in place
    /// ([`Bvh::enlarge`]), not refitted. On sphere_64_adaptive's resting sheet, stepped
    /// once a frame, a fold or a free edge takes a few vertices beyond half the margin at
    /// most steps, and listing every pair again took 3 ms of a resting frame's 15 to 18;
    /// mending, 0.1 to 1.5 ms.
    ///
    /// It does not where the listing kept the ends of long sweeps alone, where some
    /// vertex was left out for untangling, where a vertex lies in no triangle (the pairs
    /// of a point that stayed are found through its triangles' boxes), or where more than
    /// one vertex in [`MEND_SHARE`] moved away or one's new sweep is longer than
    /// [`MEND_SWEEP`] margins.
    fn mend(&mut self, mesh: &ContactMesh, x0: &[Vec3], x1: &[Vec3]) -> bool {
        let n = mesh.len();
        if !self.sweeps_listed
            || self.listed_with_exemptions
            || !self.points_in_triangles
            || self.listed_end.len() != n
            || x0.len() != n
        {
            return false;
        }
        let gap = largest_gap(mesh);
        let (margin, grown) = (Self::margin(gap), Self::grown(gap));
        let commons = [x0, x1].map(|x| self.typical_motion(x));
        let (start, end) = (&self.listed_start, &self.listed_end);
        // The sweep vertex `k` is listed for if it has left its own.
        let moved_away = |k: usize| {
            let ends = [x0[k] - commons[0], x1[k] - commons[1]];
            ends.iter().any(|&at| beyond(at, start[k], end[k], 0.5 * margin)).then_some(ends)
        };
        let count = (0..n).into_par_iter().with_min_len(PARALLEL_MIN_LEN).filter(|&k| moved_away(k).is_some()).count();
        if count == 0 {
            return true;
        }
        if count > n / MEND_SHARE {
            return false;
        }
        self.moved.clear();
        self.moved.resize(n, false);
        for k in 0..n {
            if let Some(ends) = moved_away(k) {
                if ends[0].distance(ends[1]) > MEND_SWEEP * margin {
                    return false;
                }
                self.moved[k] = true;
            }
        }
        for k in (0..n).filter(|&k| self.moved[k]) {
            [self.listed_start[k], self.listed_end[k]] = [x0[k] - commons[0], x1[k] - commons[1]];
        }
        let (start, end) = (std::mem::take(&mut self.listed_start), std::mem::take(&mut self.listed_end));
        let moved = &self.moved;
        let touches = |vertices: &[u32]| vertices.iter().any(|&k| moved[k as usize]);
        let swept = |vertices: &[u32]| swept_box(vertices, &start, &end).inflated(grown);
        for (t, triangle) in mesh.triangles.iter().enumerate().filter(|(_, t)| touches(*t)) {
            self.triangle_tree.enlarge(t as u32, swept(triangle));
        }
        for (e, edge) in mesh.edges.iter().enumerate().filter(|(_, e)| touches(*e)) {
            self.edge_tree.enlarge(e as u32, swept(edge));
        }
        let point_box = |p: u32| swept(&[p]);
        let (triangle_tree, edge_tree, found) = (&self.triangle_tree, &self.edge_tree, &mut self.mended);
        // Keeps of what a primitive's query found, from `first` on, each pair once and
        // only those that may touch: the list grows by no more than one query's finds.
        let keep_listed = |found: &mut Vec<Pair>, first: usize| {
            found[first..].sort_unstable_by_key(|pair| pair.key());
            let mut kept = first;
            for i in first..found.len() {
                let pair = found[i];
                if (i == first || found[i - 1] != pair) && may_touch(mesh, pair, &start, &end, margin, true) {
                    found[kept] = pair;
                    kept += 1;
                }
            }
            found.truncate(kept);
        };
        found.clear();
        for (t, triangle) in mesh.triangles.iter().enumerate().filter(|(_, t)| touches(*t)) {
            // The points that stayed: each lies in a triangle whose box meets this one's.
            let (first, reach) = (found.len(), triangle_tree.aabb(t as u32));
            triangle_tree.query(&reach, |u| {
                for p in mesh.triangles[u as usize] {
                    if !moved[p as usize] && !triangle.contains(&p) && point_box(p).overlaps(&reach) {
                        found.push(Pair::PointTriangle(p, t as u32));
                    }
                }
            });
            keep_listed(found, first);
        }
        for p in (0..n as u32).filter(|&p| moved[p as usize]) {
            let first = found.len();
            triangle_tree.query(&point_box(p), |t| {
                if !mesh.triangles[t as usize].contains(&p) {
                    found.push(Pair::PointTriangle(p, t));
                }
            });
            keep_listed(found, first);
        }
        for (e, &[a, b]) in mesh.edges.iter().enumerate().filter(|(_, e)| touches(*e)) {
            let (first, e) = (found.len(), e as u32);
            edge_tree.query(&edge_tree.aabb(e), |f| {
                let [c, d] = mesh.edges[f as usize];
                if a != c && a != d && b != c && b != d {
                    found.push(Pair::EdgeEdge(e.min(f), e.max(f)));
                }
            });
            keep_listed(found, first);
        }
        // Two moved edges find each other twice.
        found.sort_unstable_by_key(|pair| pair.key());
        found.dedup();
        self.pairs.retain(|&pair| !touches(&pair_vertices(mesh, pair)));
        self.pairs.extend_from_slice(found);
        self.pairs.sort_unstable_by_key(|pair| pair.key());
        (self.listed_start, self.listed_end) = (start, end);
        true
    }

    /// Lists in `hits` the candidate pairs whose paths from `x0` to `x1` touch. With
    /// `near_hits`, only the pairs sharing a vertex with the hits listed before are
    /// looked at: the candidates must be the same and only those vertices moved since.
    fn impacts(&mut self, mesh: &ContactMesh, h: f32, x0: &[Vec3], x1: &[Vec3], near_hits: bool) {
        if near_hits {
            self.dirty.fill(false);
            for &pair in &self.hits {
                for k in pair_vertices(mesh, pair) {
                    self.dirty[k as usize] = true;
                }
            }
        }
        let (pairs, dirty) = (&self.pairs, &self.dirty);
        let wanted = |pair: Pair| !near_hits || pair_vertices(mesh, pair).iter().any(|&k| dirty[k as usize]);
        self.pair_gather.run(pairs.len(), &mut self.hits, |i, out| {
            if wanted(pairs[i]) && impact(mesh, pairs[i], h, x0, x1).is_some() {
                out.push(pairs[i]);
            }
        });
        let held = |pair: &Pair| matches!(*pair, Pair::PointTriangle(p, _) if mesh.held(p));
        held_last(&mut self.hits, &mut self.held_hits, held);
    }

    /// Refits the trees to the boxes of the primitives swept from `x0` to `x1`, grown by
    /// [`SelfContactSolver::grown`].
    fn refit(&mut self, mesh: &ContactMesh, x0: &[Vec3], x1: &[Vec3]) {
        let grown = Self::grown(largest_gap(mesh));
        let swept = |vertices: &[u32]| swept_box(vertices, x0, x1).inflated(grown);
        self.triangle_tree.refit(mesh.triangles.len(), |t| swept(&mesh.triangles[t]));
        self.edge_tree.refit(mesh.edges.len(), |e| swept(&mesh.edges[e]));
    }

    /// Gives every zone of two or more vertices one rigid motion for the step: the
    /// translation and rotation that keep its linear and angular momentum. A zone
    /// holding a vertex impulses may not move (pinned, or resting on a body) translates
    /// with those vertices' mean motion instead, so zones never push cloth into a body.
    fn move_zones_rigidly(&mut self, mesh: &ContactMesh, h: f32, x0: &[Vec3]) {
        let mut zones: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
        for k in 0..mesh.len() as u32 {
            let root = find(&mut self.zone, k);
            zones.entry(root).or_default().push(k);
        }
        for members in zones.into_values().filter(|m| m.len() > 1) {
            let vel = &mut self.mean_velocity;
            let pinned: Vec<u32> =
                members.iter().copied().filter(|&k| mesh.impulse_inv_mass[k as usize] == 0.0).collect();
            if !pinned.is_empty() {
                let mean = pinned.iter().map(|&k| vel[k as usize]).sum::<Vec3>() / pinned.len() as f32;
                for &k in &members {
                    if mesh.inv_mass[k as usize] > 0.0 {
                        vel[k as usize] = mean;
                    }
                }
                continue;
            }
            let mass = |k: u32| 1.0 / mesh.inv_mass[k as usize];
            let total: f32 = members.iter().map(|&k| mass(k)).sum();
            let centre = members.iter().map(|&k| mass(k) * x0[k as usize]).sum::<Vec3>() / total;
            let velocity = members.iter().map(|&k| mass(k) * vel[k as usize]).sum::<Vec3>() / total;
            let mut momentum = Vec3::ZERO;
            let mut inertia = glam::Mat3::ZERO;
            for &k in &members {
                let r = x0[k as usize] - centre;
                momentum += mass(k) * r.cross(vel[k as usize] - velocity);
                inertia += mass(k) * (glam::Mat3::from_diagonal(Vec3::splat(r.length_squared())) - outer(r, r));
            }
            // A zone on a line has no inertia about it: regularise by a trace fraction.
            let trace = inertia.x_axis.x + inertia.y_axis.y + inertia.z_axis.z;
            let regular = inertia + glam::Mat3::from_diagonal(Vec3::splat(1e-6 * trace + f32::MIN_POSITIVE));
            let omega = regular.inverse() * momentum;
            let turn = Quat::from_scaled_axis(h * omega);
            for &k in &members {
                let r = x0[k as usize] - centre;
                let end = centre + h * velocity + turn * r;
                vel[k as usize] = (end - x0[k as usize]) / h;
            }
        }
    }
}

/// Whether `x` lies half the margin, `half`, or farther from the segment's box between
/// `start` and `end` ([`SelfContactSolver::candidates_cover`]).
fn beyond(x: Vec3, start: Vec3, end: Vec3, half: f32) -> bool {
    x.distance_squared(x.clamp(start.min(end), start.max(end))) >= half * half
}

/// The box around `vertices` at `x0` and at `x1`.
fn swept_box(vertices: &[u32], x0: &[Vec3], x1: &[Vec3]) -> Aabb {
    Aabb::around(vertices.iter().flat_map(|&k| [x0[k as usize], x1[k as usize]]))
}

fn find(parent: &mut [u32], mut k: u32) -> u32 {
    while parent[k as usize] != k {
        let up = parent[parent[k as usize] as usize];
        parent[k as usize] = up;
        k = up;
    }
    k
}

fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    // The smaller index becomes the root, so zones do not depend on merge order.
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}

fn advance(x0: &[Vec3], mean_velocity: &[Vec3], h: f32, x1: &mut [Vec3]) {
    x1.par_iter_mut().zip(x0).zip(mean_velocity).with_min_len(PARALLEL_MIN_LEN).for_each(|((x1, x0), v)| {
        *x1 = *x0 + h * *v;
    });
}

/// Moves the `items` that `held` picks, a held point's pairs, after the others, each part
/// in its order, through `buffer`. Impulses go pair after pair, each from the velocities
/// the ones before left, and a held point (pinned, or resting on a body) under a free
/// triangle lifts the point's spot by moving the triangle's vertices each by its weight
/// over the sum of the weights' squares: up to 1.5 times the lift at a vertex. Where a
/// free layer falls on a held one whose points come first, the layer's triangles were
/// lifted one after another, each overshooting at its vertices: a square dropped 2.7 cm in
/// a step onto a pinned cloth ended 12 mm above where it should have landed, and at 8.6 %
/// strain. The free points' own pairs lift each free vertex by what it needs, and a held
/// point's pair after them has little left to do: it lands flat, as it did where its
/// points came first (`tests/layer_slope.rs`).
fn held_last<T: Copy>(items: &mut Vec<T>, buffer: &mut Vec<T>, held: impl Fn(&T) -> bool) {
    buffer.clear();
    buffer.extend(items.iter().copied().filter(|item| held(item)));
    if !buffer.is_empty() {
        items.retain(|item| !held(item));
        items.extend_from_slice(buffer);
    }
}

/// The four vertices of a pair.
fn pair_vertices(mesh: &ContactMesh, pair: Pair) -> [u32; 4] {
    match pair {
        Pair::PointTriangle(p, t) => {
            let [a, b, c] = mesh.triangles[t as usize];
            [p, a, b, c]
        }
        Pair::EdgeEdge(e, f) => {
            let ([a, b], [c, d]) = (mesh.edges[e as usize], mesh.edges[f as usize]);
            [a, b, c, d]
        }
    }
}

/// How many of a pair's [`pair_vertices`] are its first side's: the point, or the first
/// edge's two.
fn first_side(pair: Pair) -> usize {
    if matches!(pair, Pair::PointTriangle(..)) { 1 } else { 2 }
}

/// Separation δ and friction μ of a pair: sums of the sides' half gaps, mean friction.
fn pair_gap_and_friction(mesh: &ContactMesh, pair: Pair) -> (f32, f32) {
    let vertices = pair_vertices(mesh, pair);
    let first_side = first_side(pair);
    let side = |range: std::ops::Range<usize>| {
        let n = range.len() as f32;
        let (gap, mu) = range.fold((0.0, 0.0), |(g, m), k| {
            let v = vertices[k] as usize;
            (g + mesh.half_gap[v], m + mesh.friction[v])
        });
        (gap / n, mu / n)
    };
    let (g1, m1) = side(0..first_side);
    let (g2, m2) = side(first_side..4);
    (g1 + g2, 0.5 * (m1 + m2))
}

/// A pair closer than its separation.
struct Close {
    stencil: Stencil,
    /// Unit normal from the second side to the first.
    normal: Vec3,
    /// The separation δ [m].
    gap: f32,
    /// The distance between the closest points [m].
    distance: f32,
    friction: f32,
}

/// The closest points of a pair at `x`, as the stencil that joins them, and a normal of
/// its primitives (not unit) for where they touch.
fn closest(mesh: &ContactMesh, pair: Pair, x: &[Vec3]) -> (Stencil, Vec3) {
    let vertices = pair_vertices(mesh, pair);
    let [p, a, b, c] = vertices.map(|k| x[k as usize]);
    match pair {
        Pair::PointTriangle(_, t) => {
            let w = closest_on_triangle(p, a, b, c);
            let tri = mesh.triangles[t as usize];
            (Stencil::point_triangle(vertices[0], tri, w), (b - a).cross(c - a))
        }
        Pair::EdgeEdge(e, f) => {
            let (s, u) = closest_between_segments(p, a, b, c);
            (Stencil::edge_edge(mesh.edges[e as usize], mesh.edges[f as usize], s, u), (a - p).cross(c - b))
        }
    }
}

/// Whether a pair whose boxes met may come within its separation while it stays listed:
/// its distance at the listing's end `x1` is within its separation plus the most that
/// distance can shrink, with a thousandth for rounding. The distance shrinks by no more
/// than the farthest two vertices of the pair's two sides move apart. In the listing's
/// own step that is the most they move apart from `x1` back to `x0`; in a later one, each
/// vertex moves beyond the common motion by no more than half the `margin` from its
/// listed end ([`SelfContactSolver::candidates_cover`]), so twice that. Where the
/// `sweeps` were listed, a vertex may stay anywhere within half the margin of the box of
/// its sweep, so within that and its sweep's length of its listed end: the margin and
/// the longest sweep of each side then bound both.
fn may_touch(mesh: &ContactMesh, pair: Pair, x0: &[Vec3], x1: &[Vec3], margin: f32, sweeps: bool) -> bool {
    let distance = closest(mesh, pair, x1).0.relative(x1).length();
    let vertices = pair_vertices(mesh, pair);
    let moves = vertices.map(|k| x0[k as usize] - x1[k as usize]);
    let (first, second) = moves.split_at(first_side(pair));
    let shrink = if sweeps {
        let longest = |side: &[Vec3]| side.iter().fold(0.0f32, |most, m| most.max(m.length()));
        margin + longest(first) + longest(second)
    } else {
        let apart = first.iter().flat_map(|a| second.iter().map(move |b| a.distance(*b))).fold(0.0f32, f32::max);
        margin.max(apart)
    };
    let (gap, _) = pair_gap_and_friction(mesh, pair);
    distance <= 1.001 * (gap + shrink)
}

/// The pair at `x`, if it is closer than `reach` times its separation.
fn close(mesh: &ContactMesh, pair: Pair, x: &[Vec3], reach: f32) -> Option<Close> {
    let (stencil, fallback) = closest(mesh, pair, x);
    let (gap, friction) = pair_gap_and_friction(mesh, pair);
    let offset = stencil.relative(x);
    let distance = offset.length();
    if distance >= reach * gap {
        return None;
    }
    let normal = if distance > 1e-6 * gap {
        offset / distance
    } else {
        let n = fallback.try_normalize()?;
        if n.dot(offset) < 0.0 { -n } else { n }
    };
    Some(Close { stencil, normal, gap, distance, friction })
}

/// The proximity contact of a pair at the start of the step, if it is closer than its
/// separation: the impulse will make its normal velocity restore [`GAP_RECOVERY`] of the
/// missing gap over the step.
fn proximity(mesh: &ContactMesh, pair: Pair, h: f32, x0: &[Vec3]) -> Option<Contact> {
    let Close { stencil, normal, gap, distance, friction } = close(mesh, pair, x0, 1.0)?;
    Some(Contact { stencil, normal, target: GAP_RECOVERY * (gap - distance) / h, friction })
}

/// The spring that holds a pair closer than its separation at `x` apart in the next
/// implicit step (see [`ContactSpring`]), if any of its vertices is free; in the mesh's
/// numbers, whichever cloths its sides belong to (a pair with another cloth becomes a
/// spring of the cloth whose side is free where the other's is held,
/// `systems::contacts`). Stiff enough to restore [`SPRING_RECOVERY`] of
/// the missing gap within a step of length `h` on its own: `k = r m / h²` for the pair's
/// effective mass `m = 1 / Σ (w² / m_k)`, and no softer than for a step of
/// [`SPRING_STEP`](crate::solver::contact_springs::SPRING_STEP) ([`spring_step`]). Its
/// friction is first lagged from the push at `x` and the velocities `v`
/// ([`ContactSpring::lag_friction`]); the step lags it again from its own solution
/// ([`crate::solver::contact_springs::lag`]).
///
/// A pair beyond its separation but within [`SPRING_REACH`] of them gets an armed spring
/// instead: no stiffness in the step's first solve, and its stiffness where that solve
/// brings the pair within its separation, solving again (the lags). At one step a frame a
/// fold's layers resting just beyond their separation otherwise fell into each other in
/// the solve by up to `h² g` (2.7 mm), to be pushed back vertex by vertex by the contact
/// stage against neighbours the solve had balanced without it: edges in sphere_64's
/// folds stayed 6 to 7 % stretched, step after step, where the solve left 2.5 %. A spring
/// with the pair's own distance as its gap instead held any layer where it was
/// (`tests/layer_slope.rs`'s upper layer hung 3 mm up).
///
/// Only a pair whose closest points lie inside both its primitives gets a spring. Where
/// one lies on a boundary (a vertex near the edge of a triangle, an edge's end near
/// another edge), the normal leans away from the surfaces' normals, and a spring frozen
/// along it for the step pushes sideways as the layers slide, more the further they slide
/// within the step: a layer sliding without friction on a layer of the same cloth was
/// braked from 4.9 to 1.5 m/s² (`scenes/layer_slope.ron`). The pairs inside the
/// primitives next to it hold the layers apart there, and the contact stage still sees
/// the boundary pair.
fn spring(mesh: &ContactMesh, pair: Pair, h: f32, x: &[Vec3], v: &[Vec3]) -> Option<ContactSpring> {
    let Close { stencil, normal, gap, distance, friction } = close(mesh, pair, x, SPRING_REACH)?;
    if stencil.weights.contains(&0.0) {
        return None;
    }
    let inv_mass = stencil.inverse_mass(&mesh.inv_mass);
    (inv_mass > 0.0).then(|| {
        let made_for = spring_step(h);
        let stiffness = SPRING_RATIO / (inv_mass * made_for * made_for);
        let spring = ContactSpring {
            stencil,
            normal,
            gap,
            stiffness,
            friction,
            drag: 0.0,
            armed: 0.0,
            outside: Outside::default(),
        };
        if distance >= gap {
            return ContactSpring { stiffness: 0.0, armed: stiffness, ..spring };
        }
        let mut spring = spring;
        spring.lag_friction(stiffness * (gap - distance), v);
        spring
    })
}

/// The continuous collision of a pair between `x0` and `x1`, if their paths touch: the
/// impulse will leave them [`IMPACT_GAP`] δ apart along the normal at the end of the
/// step.
fn impact(mesh: &ContactMesh, pair: Pair, h: f32, x0: &[Vec3], x1: &[Vec3]) -> Option<Contact> {
    let vertices = pair_vertices(mesh, pair);
    let sweep = Sweep { start: vertices.map(|k| x0[k as usize]), end: vertices.map(|k| x1[k as usize]) };
    let (gap, friction) = pair_gap_and_friction(mesh, pair);
    let tolerance = (1e-3 * gap).max(1e-7);
    let (stencil, normal_at_hit) = match pair {
        Pair::PointTriangle(p, tri) => {
            let (t, w) = sweep.point_triangle_hit(tolerance)?;
            let [_, a, b, c] = lerp4(&sweep, t);
            (Stencil::point_triangle(p, mesh.triangles[tri as usize], w), (b - a).cross(c - a))
        }
        Pair::EdgeEdge(e, f) => {
            let (t, (s, u)) = sweep.edge_edge_hit(tolerance)?;
            let [p0, p1, q0, q1] = lerp4(&sweep, t);
            (Stencil::edge_edge(mesh.edges[e as usize], mesh.edges[f as usize], s, u), (p1 - p0).cross(q1 - q0))
        }
    };
    let start = stencil.relative(x0);
    let end = stencil.relative(x1);
    let mut normal =
        normal_at_hit.try_normalize().or_else(|| start.try_normalize()).or_else(|| (start - end).try_normalize())?;
    // The normal points to the side the first primitive started on (or, starting in
    // contact, to the side it came from).
    let side = if start.dot(normal).abs() > 1e-3 * tolerance { start.dot(normal) } else { (start - end).dot(normal) };
    if side < 0.0 {
        normal = -normal;
    }
    let start_gap = start.dot(normal);
    Some(Contact { stencil, normal, target: (IMPACT_GAP * gap - start_gap) / h, friction })
}

fn lerp4(sweep: &Sweep, t: f32) -> [Vec3; 4] {
    std::array::from_fn(|k| sweep.start[k].lerp(sweep.end[k], t))
}

/// Applies the impulse of `contact` to the mean velocities: the pair's normal velocity
/// rises to the target (if below it) and friction takes at most μ times that change off
/// its tangential velocity (all of it if that suffices: static friction). The change is
/// shared by the vertices in proportion to weight × inverse mass: the impulse masses,
/// unless the vertices those hold still carry most of the pair's weight (moving the
/// contact point would then fling a lightly weighted vertex), in which case the true
/// masses.
fn apply(contact: &Contact, mesh: &ContactMesh, velocity: &mut [Vec3]) {
    let stencil = &contact.stencil;
    let relative = stencil.relative(velocity);
    let normal_speed = relative.dot(contact.normal);
    if normal_speed >= contact.target {
        return;
    }
    let (held, free) = (stencil.inverse_mass(&mesh.impulse_inv_mass), stencil.inverse_mass(&mesh.inv_mass));
    let (inv_mass, share) = if held >= 0.25 * free { (&mesh.impulse_inv_mass, held) } else { (&mesh.inv_mass, free) };
    if share <= 0.0 {
        return;
    }
    let normal_change = contact.target - normal_speed;
    let tangential = relative - normal_speed * contact.normal;
    let speed = tangential.length();
    let friction_change = if speed <= contact.friction * normal_change {
        -tangential
    } else {
        -tangential * (contact.friction * normal_change / speed)
    };
    let change = normal_change * contact.normal + friction_change;
    for k in 0..4 {
        let vertex = stencil.vertices[k] as usize;
        velocity[vertex] += (stencil.weights[k] * inv_mass[vertex] / share) * change;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::intersection::count_self_intersections;

    /// Two unit squares of two triangles each, the second `height` above the first.
    fn two_sheets(height: f32) -> (ContactMesh, Vec<Vec3>) {
        let square =
            |y: f32| [Vec3::new(0.0, y, 0.0), Vec3::new(1.0, y, 0.0), Vec3::new(1.0, y, 1.0), Vec3::new(0.0, y, 1.0)];
        let x: Vec<Vec3> = square(0.0).into_iter().chain(square(height)).collect();
        let triangles = vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]];
        let mesh = ContactMesh {
            edges: ContactMesh::edges_of(&triangles),
            triangles,
            inv_mass: vec![1.0; 8],
            impulse_inv_mass: vec![1.0; 8],
            half_gap: vec![0.005; 8],
            friction: vec![0.0; 8],
            layer: vec![0; 8],
            first: vec![0, 8],
            springs: false,
        };
        (mesh, x)
    }

    #[test]
    fn a_sheet_dropped_through_another_in_one_step_is_stopped_and_momentum_is_kept() {
        let (mesh, x0) = two_sheets(0.1);
        let h = 0.01;
        // The upper sheet falls at 20 m/s: 0.2 m in the step, through the lower one.
        let mut v: Vec<Vec3> = (0..8).map(|k| if k >= 4 { Vec3::new(0.0, -20.0, 0.0) } else { Vec3::ZERO }).collect();
        let mut x1: Vec<Vec3> = x0.iter().zip(&v).map(|(x, v)| *x + h * *v).collect();
        let momentum: Vec3 = v.iter().sum();
        let report = SelfContactSolver::default().resolve(&mesh, h, &x0, &mut x1, &mut v);
        assert!(report.impacts > 0 || report.zone_rounds > 0, "{report:?}");
        // The sheets meet within the step and end it a tenth of their separation apart
        // (Zheng eq. 3.23), the impulse shared equally by the equal masses.
        for k in 0..4 {
            let gap = x1[k + 4].y - x1[k].y;
            assert!((gap - IMPACT_GAP * 0.01).abs() < 2e-4, "gap {gap}");
        }
        assert!((v.iter().sum::<Vec3>() - momentum).length() < 1e-3, "impulses conserve momentum");
        assert!((v[0].y + 5.05).abs() < 0.05 && (v[4].y + 14.95).abs() < 0.05, "{v:?}");
    }

    #[test]
    fn a_sheet_resting_closer_than_the_separation_is_pushed_apart_only_by_the_recovery() {
        let (mesh, x0) = two_sheets(0.004);
        let h = 0.01;
        let mut v = vec![Vec3::ZERO; 8];
        let mut x1 = x0.clone();
        let report = SelfContactSolver::default().resolve(&mesh, h, &x0, &mut x1, &mut v);
        assert!(report.proximity > 0);
        // Gap 4 mm of 10 mm: the pair's normal velocity becomes 0.25 × 6 mm / h.
        let relative = v[4].y - v[0].y;
        assert!((relative - GAP_RECOVERY * 0.006 / h).abs() < 1e-3, "relative {relative}");
    }

    /// A step's candidates serve the next while its sweeps stay within half the margin
    /// of where they were listed for (cloth at rest), and find what a fresh listing
    /// finds; a step starting farther away lists them again.
    #[test]
    fn candidates_serve_the_next_step_only_while_the_cloth_moves_little() {
        let h = 0.01;
        let lower = |sheets: &[Vec3], by: f32| {
            sheets.iter().enumerate().map(|(k, x)| if k >= 4 { *x - by * Vec3::Y } else { *x }).collect::<Vec<_>>()
        };
        let slide = |sheets: &[Vec3], by: f32| {
            sheets.iter().enumerate().map(|(k, x)| if k >= 4 { *x + by * Vec3::X } else { *x }).collect::<Vec<_>>()
        };
        let fall = |sheets: &[Vec3], by: f32| sheets.iter().map(|x| *x - by * Vec3::Y).collect::<Vec<_>>();
        // Resting 4 mm apart, then sliding 2 mm (within half the 10 mm margin); resting
        // 14 mm apart, then 4.5 mm closer, within the 10 mm separation (the points' pairs
        // were listed only because the points' boxes are grown too); resting 10 cm apart
        // (no candidates), then starting the next step 4 mm apart; 4 mm apart, then both
        // sheets 30 cm lower, thirty times the margin (a motion common to all no pair sees).
        let (_, close) = two_sheets(0.004);
        let (_, near) = two_sheets(0.014);
        let (mesh, far) = two_sheets(0.1);
        for (first, second_start, kept) in [
            (close.clone(), slide(&close, 0.002), true),
            (near.clone(), lower(&near, 0.0045), true),
            (far.clone(), lower(&far, 0.096), false),
            (close.clone(), fall(&close, 0.3), true),
        ] {
            let mut solver = SelfContactSolver::default();
            let (mut end, mut v) = (first.clone(), vec![Vec3::ZERO; 8]);
            solver.resolve(&mesh, h, &first, &mut end, &mut v);
            let listed = solver.listed_end.clone();
            let (mut next, mut next_v) = (second_start.clone(), v.clone());
            let report = solver.resolve(&mesh, h, &second_start, &mut next, &mut next_v);
            assert_eq!(solver.listed_end == listed, kept, "kept {kept}");
            let (mut fresh, mut fresh_v) = (second_start.clone(), v);
            let fresh_report = SelfContactSolver::default().resolve(&mesh, h, &second_start, &mut fresh, &mut fresh_v);
            assert!(report.proximity > 0 && report.proximity == fresh_report.proximity, "kept {kept}: {report:?}");
            assert_eq!((next, next_v), (fresh, fresh_v), "kept {kept}");
        }
    }

    /// Vertices carried one way by a step and back by the next keep the candidates while
    /// they stay near their listed sweeps, however far that is from the listing's ends,
    /// and the candidates find what a fresh listing finds.
    #[test]
    fn candidates_serve_vertices_going_back_and_forth_over_their_listed_sweeps() {
        let h = 0.01;
        let (mesh, rest) = two_sheets(0.004);
        // Two corners of the upper sheet 15 mm each way along x and back: sweeps within
        // the 20 mm margin, but ends 30 mm apart once back.
        let moved = |x: &[Vec3], by: f32| {
            let mut x = x.to_vec();
            x[4].x += by;
            x[6].x -= by;
            x
        };
        let velocity = |x0: &[Vec3], x1: &[Vec3]| x0.iter().zip(x1).map(|(a, b)| (*b - *a) / h).collect::<Vec<_>>();
        let mut solver = SelfContactSolver::default();
        let mut end = moved(&rest, 0.015);
        let mut v = velocity(&rest, &end);
        solver.resolve(&mesh, h, &rest, &mut end, &mut v);
        let listed = solver.listed_end.clone();
        let start = end;
        let back = moved(&start, -0.015);
        let displacements: Vec<Vec3> = back.iter().zip(&listed).map(|(now, then)| *now - *then).collect();
        let (low, high) =
            displacements.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), d| (l.min(*d), h.max(*d)));
        let beyond = displacements.iter().map(|d| (*d - 0.5 * (low + high)).length()).fold(0.0f32, f32::max);
        let half_margin = 0.5 * SelfContactSolver::margin(largest_gap(&mesh));
        assert!(beyond > half_margin, "the ends alone would not serve: {beyond} against {half_margin}");
        let (mut next, mut next_v) = (back.clone(), velocity(&start, &back));
        let report = solver.resolve(&mesh, h, &start, &mut next, &mut next_v);
        assert_eq!(solver.listed_end, listed, "kept");
        let (mut fresh, mut fresh_v) = (back.clone(), velocity(&start, &back));
        let fresh_report = SelfContactSolver::default().resolve(&mesh, h, &start, &mut fresh, &mut fresh_v);
        assert!(report.proximity > 0 && report.proximity == fresh_report.proximity, "{report:?}");
        assert_eq!((next, next_v), (fresh, fresh_v));
    }

    #[test]
    fn friction_stops_a_slow_sliding_contact_and_slows_a_fast_one() {
        for slide in [0.05, 1.0] {
            let (mut mesh, x0) = two_sheets(0.008);
            mesh.friction = vec![0.5; 8];
            mesh.inv_mass[..4].fill(0.0);
            mesh.impulse_inv_mass[..4].fill(0.0);
            let h = 0.01;
            // The upper sheet slides along x and approaches the pinned lower one at 0.5 m/s.
            let mut v: Vec<Vec3> =
                (0..8).map(|k| if k >= 4 { Vec3::new(slide, -0.5, 0.0) } else { Vec3::ZERO }).collect();
            let mut x1: Vec<Vec3> = x0.iter().zip(&v).map(|(x, v)| *x + h * *v).collect();
            SelfContactSolver::default().resolve(&mesh, h, &x0, &mut x1, &mut v);
            assert!(v[4].y > -1e-6, "approach stopped: {}", v[4].y);
            if slide < 0.1 {
                assert!(v[4].x.abs() < 1e-6, "sticks: {}", v[4].x);
            } else {
                assert!(v[4].x > 0.2 && v[4].x < slide - 0.2, "slides, slower: {}", v[4].x);
            }
        }
    }

    /// A flat `n × n` grid sheet of the given spacing in the plane y = 0, each square split
    /// along one diagonal, every vertex with the given half gap.
    fn grid_sheet(n: usize, spacing: f32, half_gap: f32) -> (ContactMesh, Vec<Vec3>) {
        let mut x = Vec::new();
        for j in 0..n {
            for i in 0..n {
                x.push(Vec3::new(i as f32 * spacing, 0.0, j as f32 * spacing));
            }
        }
        let mut triangles = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let k = (j * n + i) as u32;
                triangles.push([k, k + 1, k + 1 + n as u32]);
                triangles.push([k, k + 1 + n as u32, k + n as u32]);
            }
        }
        let mesh = ContactMesh {
            edges: ContactMesh::edges_of(&triangles),
            inv_mass: vec![1.0; x.len()],
            impulse_inv_mass: vec![1.0; x.len()],
            half_gap: vec![half_gap; x.len()],
            friction: vec![0.2; x.len()],
            layer: vec![0; x.len()],
            first: vec![0, x.len() as u32],
            springs: false,
            triangles,
        };
        (mesh, x)
    }

    /// The listing drops pairs whose boxes met but which cannot come within their
    /// separation ([`may_touch`]); every pair that does come within it, in the listing's
    /// own step or while the candidates still cover the positions, must still be listed.
    #[test]
    fn the_candidates_hold_every_pair_that_comes_within_its_separation() {
        // A crumpled sheet of 4 mm squares with a 2 mm separation (and a 4 mm margin), moving
        // in the step that lists it 10 mm and up to 3.5 mm more at each vertex (longer than
        // the margin: the list serves near the sweeps' ends), or up to 3.5 mm alone (the
        // list serves near the whole sweeps, which the later positions then go back over).
        let (mesh, flat) = grid_sheet(8, 0.004, 0.001);
        let wave = |k: usize, a: f32| (k as f32 * a).sin();
        let x1: Vec<Vec3> = flat.iter().enumerate().map(|(k, x)| *x + 0.003 * wave(k, 1.3) * Vec3::Y).collect();
        let margin = SelfContactSolver::margin(largest_gap(&mesh));
        let points = (0..mesh.len() as u32).flat_map(|p| {
            let triangles = mesh.triangles.iter().enumerate().filter(move |(_, t)| !t.contains(&p));
            triangles.map(move |(t, _)| Pair::PointTriangle(p, t as u32))
        });
        let edge_list = &mesh.edges;
        let edges = (0..edge_list.len() as u32).flat_map(|e| {
            let [a, b] = edge_list[e as usize];
            let apart = (e + 1..edge_list.len() as u32).filter(move |&f| {
                let [c, d] = edge_list[f as usize];
                a != c && a != d && b != c && b != d
            });
            apart.map(move |f| Pair::EdgeEdge(e, f))
        });
        let all: Vec<Pair> = points.chain(edges).collect();
        for fall in [0.01, 0.0] {
            let x0: Vec<Vec3> = x1
                .iter()
                .enumerate()
                .map(|(k, x)| *x + fall * Vec3::Y + 0.002 * Vec3::new(wave(k, 0.7), wave(k, 1.9), wave(k, 2.9)))
                .collect();
            let mut solver = SelfContactSolver::default();
            solver.untangler.clear(mesh.len());
            solver.candidates(&mesh, &x0, &x1);
            assert_eq!(solver.sweeps_listed, fall == 0.0, "{fall}: sweeps listed");
            let missing = |x: &[Vec3]| {
                all.iter()
                    .filter(|&&pair| close(&mesh, pair, x, 1.0).is_some() && !solver.pairs.contains(&pair))
                    .count()
            };
            let (mut touching, mut covered) = (0, 0);
            for s in [0.0, 0.25, 0.5, 0.75, 1.0] {
                let x: Vec<Vec3> = x0.iter().zip(&x1).map(|(a, b)| a.lerp(*b, s)).collect();
                touching += all.iter().filter(|&&pair| close(&mesh, pair, &x, 1.0).is_some()).count();
                assert_eq!(missing(&x), 0, "{fall}: in the listing's step at {s}");
            }
            for trial in 0..40 {
                let common = trial as f32 * Vec3::new(0.003, -0.01, 0.002);
                let x: Vec<Vec3> = (0..x1.len())
                    .map(|k| {
                        let turn = (k * 41 + trial * 7) as f32;
                        let direction = Vec3::new(turn.sin(), (1.7 * turn).cos(), (2.3 * turn).sin()).normalize();
                        // Where the whole sweeps serve, each vertex anywhere back over its own.
                        let back = if solver.sweeps_listed { 0.5 + 0.5 * (3.1 * turn).sin() } else { 0.0 };
                        x1[k].lerp(x0[k], back) + common + 0.4 * margin * direction
                    })
                    .collect();
                if solver.candidates_cover(&mesh, &x) {
                    covered += 1;
                    touching += all.iter().filter(|&&pair| close(&mesh, pair, &x, 1.0).is_some()).count();
                    assert_eq!(missing(&x), 0, "{fall}: trial {trial}");
                }
            }
            assert!(covered >= 30, "{fall}: the cover test held in {covered} of 40 trials");
            assert!(touching > 50, "{fall}: {touching} pairs within their separation: the test tests something");
            assert!(solver.pairs.len() < all.len() / 4, "{fall}: {} of {} pairs listed", solver.pairs.len(), all.len());
        }
    }

    /// A few vertices leaving their listed sweeps are listed again alone, and the list is
    /// then the one a whole listing over the positions they are listed for makes, pair for
    /// pair and in its order; more than one vertex in [`MEND_SHARE`] is listed anew.
    #[test]
    fn mended_candidates_are_those_of_a_listing_of_where_the_vertices_are_listed_for() {
        // A crumpled sheet of 4 mm squares, 2 mm separation, 4 mm margin, listed over
        // short sweeps; then the whole sheet 5 cm away, and a few vertices 2.5 mm more at
        // the step's start and 5 mm at its end, out of their listed sweeps (half the
        // margin is 2 mm) however the motion common to all is taken.
        let (mesh, flat) = grid_sheet(16, 0.004, 0.001);
        let wave = |k: usize, a: f32| (k as f32 * a).sin();
        let x1: Vec<Vec3> = flat.iter().enumerate().map(|(k, x)| *x + 0.003 * wave(k, 1.3) * Vec3::Y).collect();
        let x0: Vec<Vec3> =
            x1.iter().enumerate().map(|(k, x)| *x + 0.001 * Vec3::new(wave(k, 0.7), wave(k, 1.9), 0.0)).collect();
        let shifted = |moved: &[usize], by: f32| {
            let own = |k: usize| if moved.contains(&k) { by * Vec3::new(0.0, 0.8, -0.6) } else { Vec3::ZERO };
            x1.iter().enumerate().map(|(k, x)| *x + Vec3::new(0.05, 0.0, 0.0) + own(k)).collect::<Vec<_>>()
        };
        let few = [17, 100, 101, 200];
        let mut solver = SelfContactSolver::default();
        solver.untangler.clear(mesh.len());
        solver.candidates(&mesh, &x0, &x1);
        assert!(solver.sweeps_listed);
        let (start, end) = (shifted(&few, 0.0025), shifted(&few, 0.005));
        assert!(solver.candidates_cover(&mesh, &start) && !solver.candidates_cover(&mesh, &end));
        assert!(solver.mend(&mesh, &start, &end), "four vertices of 256 are mended");
        assert!(solver.candidates_cover(&mesh, &start) && solver.candidates_cover(&mesh, &end));
        let mended: Vec<usize> = (0..mesh.len()).filter(|&k| solver.moved[k]).collect();
        assert_eq!(mended, few);
        let mut fresh = SelfContactSolver::default();
        fresh.untangler.clear(mesh.len());
        fresh.candidates(&mesh, &solver.listed_start, &solver.listed_end);
        assert!(fresh.sweeps_listed);
        assert_eq!(solver.pairs, fresh.pairs, "the pairs of a listing where they are listed for");
        let of_few = |pair: &Pair| pair_vertices(&mesh, *pair).iter().any(|&k| few.contains(&(k as usize)));
        assert!(solver.pairs.iter().any(of_few));
        let many: Vec<usize> = (0..=mesh.len() / MEND_SHARE).map(|k| 3 * k).collect();
        assert!(!solver.mend(&mesh, &end, &shifted(&many, 0.01)), "{} vertices are listed anew", many.len());
    }

    #[test]
    fn impact_zones_keep_a_crumpling_sheet_untangled() {
        // A 12 × 12 grid sheet whose vertices get large random velocities: impulses alone
        // cannot sort it out in a step, the zones must.
        let (mesh, x0) = grid_sheet(12, 0.02, 0.0005);
        let mut v: Vec<Vec3> = (0..x0.len())
            .map(|k| {
                let s = k as f32;
                Vec3::new((s * 1.7).sin(), (s * 2.3).sin() * 3.0, (s * 0.9).cos()) * 2.0
            })
            .collect();
        let h = 0.01;
        let mut x1: Vec<Vec3> = x0.iter().zip(&v).map(|(x, v)| *x + h * *v).collect();
        assert!(count_self_intersections(&x1, &mesh.triangles) > 0, "the unresolved step tangles");
        let report = SelfContactSolver::default().resolve(&mesh, h, &x0, &mut x1, &mut v);
        assert_eq!(count_self_intersections(&x1, &mesh.triangles), 0, "{report:?}");
    }
}
