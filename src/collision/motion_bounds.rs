//! How far each vertex of a cloth may move from a configuration, in any direction, so that
//! no vertex passes through a triangle and no edge through an edge whatever the other
//! vertices do within their own bounds: the conservative bounds of offset geometric
//! contact (Chen et al. 2025), which vertex block descent applies to every iteration.
//!
//! A point–triangle or edge–edge pair `d` apart stays apart while each of its four
//! vertices moves less than `d / 2` along a straight line: every point of a triangle or
//! an edge is a convex combination of its vertices, so it moves no farther than they do,
//! and the pair's distance falls by at most twice the largest move. Each vertex may move
//! [`GAMMA`] (< ½) times the distance of the nearest pair it belongs to. Pairs farther
//! apart than the reach `r` are not looked for; no vertex moves more than `GAMMA r` either,
//! so they stay apart too.
//!
//! The other cloths a cloth collides with stand still while its solve runs (the cloths
//! step one after another, each against the others where they stand then), so a pair with
//! one of them has only the cloth's side moving, and the same fraction of its distance
//! keeps it apart with room to spare: [`Others`] adds those pairs.
//!
//! Where one side of a pair stands still in the solve (a pinned layer), a ball of a
//! fraction of the gap stops a layer sliding on it: each measure lets it slide 0.4 of the
//! gap, whatever the slide wants. A free vertex over a still triangle keeps instead to the
//! half-space beyond that triangle's plane, grown by the layers' separation, as a vertex
//! over a body keeps to the body's tangent plane ([`super::body_bounds`]): it may slide
//! along the layer as far as its ball lets it, and the ball no longer counts the pairs the
//! planes keep apart ([`Resting`]). The other cloths' triangles stand still too, and give
//! planes the same way ([`Under`]).

use std::ops::Range;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::body_contact::CAUGHT;
use super::bvh::{Aabb, Bvh};
use super::primitives::{closest_between_segments, closest_on_triangle};
use crate::solver::PARALLEL_MIN_LEN;

/// A vertex's bound as a fraction of its nearest pair's distance: below ½, with room for
/// rounding; a pair ends at least a fifth of its distance apart.
pub const GAMMA: f32 = 0.4;

/// Where a vertex may go from the point its bounds were measured at (its anchor): within
/// `radius` of it, and on the positive side of `plane`, the points `y` with
/// `normal · y ≥ w` for `plane = (normal, w)` (the zero plane allows every point). Both
/// regions are convex, so a straight move from a point within them leaves them at most
/// once, and cutting it short there keeps all of it within. A vertex pressed against the
/// plane is put `slack` beyond it, not on it: one on it would be across it by round-off
/// as often as not, and every move along the plane would be cut.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bound {
    /// Largest distance from the anchor [m].
    pub radius: f32,
    /// The half-space the vertex keeps to: unit normal and offset [m].
    pub plane: Vec4,
    /// How far beyond the plane a vertex pressed against it is put [m].
    pub slack: f32,
}

impl Bound {
    /// No bound.
    pub const FREE: Self = Self { radius: f32::INFINITY, plane: Vec4::ZERO, slack: 0.0 };

    /// Within `radius` [m] of the anchor, on any side.
    pub fn within(radius: f32) -> Self {
        Self { radius, ..Self::FREE }
    }

    /// How far `y` lies on the plane's positive side [m]: negative outside it.
    pub fn room(&self, y: Vec3) -> f32 {
        self.plane.truncate().dot(y) - self.plane.w
    }

    /// Whether a vertex at `y` is pressed against the plane: within two slacks of it, as a
    /// projected step puts it one slack beyond.
    pub fn pressed(&self, y: Vec3) -> bool {
        self.plane != Vec4::ZERO && self.room(y) <= 2.0 * self.slack
    }

    /// The fraction `t ∈ [0, 1]` of the straight move by `step` from `from` (within the
    /// bound) that keeps the vertex within the bound about `anchor`.
    pub fn allowed(&self, anchor: Vec3, from: Vec3, step: Vec3) -> f32 {
        self.ball_allows(anchor, from, step).min(self.plane_allows(from, step))
    }

    /// The fraction `t ∈ [0, 1]` of the straight move by `step` from `from` that keeps
    /// the vertex within `radius` of `anchor`.
    pub fn ball_allows(&self, anchor: Vec3, from: Vec3, step: Vec3) -> f32 {
        let (offset, radius) = (from - anchor, self.radius);
        let (a, b, c) = (step.length_squared(), offset.dot(step), offset.length_squared() - radius * radius);
        if a == 0.0 || (offset + step).length_squared() <= radius * radius {
            return 1.0;
        }
        // |offset + t step|² = radius², the root in [0, 1].
        ((-b + (b * b - a * c).max(0.0).sqrt()) / a).clamp(0.0, 1.0)
    }

    /// The fraction `t ∈ [0, 1]` of the straight move by `step` from `from` that keeps
    /// the vertex on the plane's positive side.
    pub fn plane_allows(&self, from: Vec3, step: Vec3) -> f32 {
        let approach = self.plane.truncate().dot(step);
        let room = self.room(from);
        if approach < 0.0 && room + approach < 0.0 { (room / -approach).clamp(0.0, 1.0) } else { 1.0 }
    }
}

/// How a vertex moves in the solve its bounds are measured for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mobility {
    /// Free of constraints: it may keep to a plane.
    Free,
    /// Moving within a constraint's filter, which a plane could leave no room.
    Constrained,
    /// Standing still where its bound is measured: pinned there.
    Still,
}

/// How a cloth's layers meet: the gap its pairs keep, and their friction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayerContact {
    /// Distance kept between layers' mid-surfaces [m].
    pub separation: f32,
    /// Coulomb friction between layers [-].
    pub friction: f32,
}

/// What lets a layer rest and slide on a still one ([`MotionBounds::compute`]): how each
/// vertex moves, and the separation a vertex over a still triangle keeps from it.
#[derive(Debug, Clone, Copy)]
pub struct Resting<'a> {
    /// Per vertex.
    pub mobility: &'a [Mobility],
    /// The layers' separation [m].
    pub separation: f32,
}

/// A still triangle can carry a free vertex's plane only where the vertex lies over it:
/// its height above the triangle's plane at least this fraction of its distance. Beside a
/// triangle of its own sheet a vertex is level with it, and that plane would hold it there.
const OVER: f32 = 0.7;

/// No still triangle under a vertex.
const NO_SUPPORT: u64 = u64::MAX;

/// A cloth surface whose vertices must not pass through it.
#[derive(Debug, Clone, Copy)]
pub struct Surface<'a> {
    /// Triangles.
    pub triangles: &'a [[u32; 3]],
    /// The triangles' edges, each once.
    pub edges: &'a [[u32; 2]],
}

/// The surfaces of the cloths that collide with one another, each where it stands
/// between their steps, with trees over each cloth's triangles and edges: what bounds each
/// cloth's iterations against the others ([`ClothSurfaces::others`]). Kept from step to
/// step, so that a warm step allocates nothing.
#[derive(Debug, Default)]
pub struct ClothSurfaces {
    /// The cloths' vertices, one cloth after another, and their velocities, which a
    /// layer resting on one slides against.
    positions: Vec<Vec3>,
    velocities: Vec<Vec3>,
    /// Their triangles and edges, numbered in `positions`.
    triangles: Vec<[u32; 3]>,
    edges: Vec<[u32; 2]>,
    /// The first `count` are the cloths'; those after, kept for their trees' buffers.
    parts: Vec<SurfacePart>,
    count: usize,
}

/// One cloth of [`ClothSurfaces`]: where its vertices, triangles and edges begin and end
/// there, and the trees over its triangles and edges, numbered from its first.
#[derive(Debug)]
struct SurfacePart {
    /// How the cloth's layers meet: a pair with another cloth keeps the mean of the two
    /// separations and takes the mean of their frictions, as the contact stage's do.
    layers: LayerContact,
    vertices: Range<usize>,
    triangles: Range<usize>,
    edges: Range<usize>,
    triangle_tree: Bvh,
    edge_tree: Bvh,
}

impl ClothSurfaces {
    /// Empties the surfaces, for the cloths to be added again in their order.
    pub fn clear(&mut self) {
        self.positions.clear();
        self.velocities.clear();
        self.triangles.clear();
        self.edges.clear();
        self.count = 0;
    }

    /// Adds a cloth's `surface`, whose layers meet as `layers`, at `positions` moving at
    /// `velocities`, after the cloths added since the last [`ClothSurfaces::clear`],
    /// fitting its trees, and returns its number among them.
    pub fn add(
        &mut self,
        surface: Surface<'_>,
        layers: LayerContact,
        positions: &[Vec3],
        velocities: &[Vec3],
    ) -> usize {
        let offset = self.positions.len() as u32;
        let (triangles, edges) = (self.triangles.len(), self.edges.len());
        self.triangles.extend(surface.triangles.iter().map(|t| t.map(|k| k + offset)));
        self.edges.extend(surface.edges.iter().map(|e| e.map(|k| k + offset)));
        self.positions.extend_from_slice(positions);
        self.velocities.extend_from_slice(velocities);
        if self.parts.len() == self.count {
            self.parts.push(SurfacePart {
                layers,
                vertices: 0..0,
                triangles: 0..0,
                edges: 0..0,
                triangle_tree: Bvh::default(),
                edge_tree: Bvh::default(),
            });
        }
        let part = &mut self.parts[self.count];
        part.layers = layers;
        part.vertices = offset as usize..self.positions.len();
        part.triangles = triangles..self.triangles.len();
        part.edges = edges..self.edges.len();
        self.count += 1;
        self.refit(self.count - 1);
        self.count - 1
    }

    /// Moves cloth `cloth` to `positions` and `velocities`, where its step ended, and
    /// refits its trees.
    pub fn moved(&mut self, cloth: usize, positions: &[Vec3], velocities: &[Vec3]) {
        let vertices = self.parts[cloth].vertices.clone();
        self.positions[vertices.clone()].copy_from_slice(positions);
        self.velocities[vertices].copy_from_slice(velocities);
        self.refit(cloth);
    }

    /// Fits cloth `cloth`'s trees to where it stands.
    fn refit(&mut self, cloth: usize) {
        let Self { positions: x, triangles, edges, parts, .. } = self;
        let part = &mut parts[cloth];
        let (triangles, edges) = (&triangles[part.triangles.clone()], &edges[part.edges.clone()]);
        part.triangle_tree.refit(triangles.len(), |t| Aabb::around(triangles[t].map(|k| x[k as usize])));
        part.edge_tree.refit(edges.len(), |e| Aabb::around(edges[e].map(|k| x[k as usize])));
    }

    /// The cloths other than `cloth`, as its solve meets them; `None` where there are none.
    pub fn others(&self, cloth: usize) -> Option<Others<'_>> {
        (self.count > 1).then_some(Others { surfaces: self, own: cloth })
    }
}

/// The other cloths a cloth collides with ([`ClothSurfaces::others`]), standing still
/// while it is solved.
#[derive(Debug, Clone, Copy)]
pub struct Others<'a> {
    surfaces: &'a ClothSurfaces,
    /// The number of the cloth being solved.
    own: usize,
}

impl<'a> Others<'a> {
    /// Each other cloth's part.
    fn parts(&self) -> impl Iterator<Item = &'a SurfacePart> + use<'a> {
        let own = self.own;
        self.surfaces.parts[..self.surfaces.count].iter().enumerate().filter(move |&(c, _)| c != own).map(|(_, p)| p)
    }

    /// The nearest of the other cloths' triangles that `p` lies over ([`lies_over`]),
    /// if nearer than `limit`: its number in the surfaces and its distance, the lowest
    /// number among equals.
    fn under(&self, p: Vec3, limit: f32) -> Option<(u32, f32)> {
        let point = Aabb::around([p]);
        let mut nearest: Option<(u32, f32)> = None;
        for part in self.parts() {
            let tree = &part.triangle_tree;
            tree.query(&point.inflated(limit), |t| {
                let bound = nearest.map_or(limit, |(_, d)| d);
                // A triangle whose box is farther than the nearest so far cannot be nearer.
                if point.distance(&tree.aabb(t)) > bound {
                    return;
                }
                let global = part.triangles.start as u32 + t;
                let Some(d) = lies_over(p, self.corners(global)).filter(|&d| d < limit) else {
                    return;
                };
                if nearest.is_none_or(|(u, e)| (d, global) < (e, u)) {
                    nearest = Some((global, d));
                }
            });
        }
        nearest
    }

    /// The corners of another cloth's triangle `t`, in the surfaces' numbering.
    fn corners(&self, t: u32) -> [Vec3; 3] {
        self.surfaces.triangles[t as usize].map(|k| self.surfaces.positions[k as usize])
    }

    /// The velocity under weights `w` of another cloth's triangle `t`.
    fn velocity(&self, t: u32, w: [f32; 3]) -> Vec3 {
        let triangle = self.surfaces.triangles[t as usize];
        (0..3).map(|k| w[k] * self.surfaces.velocities[triangle[k] as usize]).sum()
    }

    /// How the cloth's layers meet another cloth's triangle `t`: the mean of the two
    /// cloths' separations and frictions.
    fn layers(&self, t: u32) -> LayerContact {
        let parts = &self.surfaces.parts[..self.surfaces.count];
        let (own, theirs) = (parts[self.own].layers, parts.iter().find(|p| p.triangles.contains(&(t as usize))));
        let theirs = theirs.map_or(own, |p| p.layers);
        LayerContact {
            separation: 0.5 * (own.separation + theirs.separation),
            friction: 0.5 * (own.friction + theirs.friction),
        }
    }
}

/// The trees and buffers of [`MotionBounds::compute`], kept from call to call so that a
/// warm call allocates nothing. A clone starts with empty buffers.
#[derive(Debug, Default)]
pub struct MotionBounds {
    /// The triangles' and the edges' boxes at the positions of the last call.
    triangle_tree: Bvh,
    edge_tree: Bvh,
    /// Per vertex, the distance of the nearest pair it belongs to, as the bits of a
    /// non-negative `f32`, whose order is the numbers' order: an atomic minimum over them
    /// is exact and does not depend on the order the pairs are met in.
    nearest: Vec<AtomicU32>,
    /// Per free vertex, its nearest still triangle that it lies over, as its distance's
    /// bits above the triangle's number (so the minimum is the nearest, the lowest number
    /// among equals), or [`NO_SUPPORT`].
    support: Vec<AtomicU64>,
    /// Per vertex, the plane the still triangle under it gives, or zero.
    planes: Vec<Vec4>,
    /// Whether the last call gave any vertex a still triangle's plane.
    supported: bool,
    /// Per vertex and per edge, whether it has a pair with one side still, which the
    /// planes' pass visits again.
    vertices_left: Vec<bool>,
    edges_left: Vec<bool>,
}

impl Clone for MotionBounds {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl MotionBounds {
    /// Sets `bounds[v]` to how far vertex `v` of `surface`, at `x`, may move, looking
    /// for pairs as far as a move of `wanted` [m] needs: the reach is `2 wanted / GAMMA`,
    /// from an eighth of the mean edge length to all of it. Each step of the search grows
    /// as the reach squared (in a heap of folds, as the layers within it), and on a
    /// smooth sheet the nearest primitives that do not touch a vertex are about 0.7 of an
    /// edge from it, so looking farther than an edge would loosen no bound.
    ///
    /// With `others`, the pairs with the other cloths' triangles and edges, which stand
    /// still, bound the vertices too. With `resting`, a free vertex over a still triangle
    /// (its cloth's own or another cloth's) keeps to that triangle's plane
    /// ([`MotionBounds::planes`]), and the pairs with one side still that the planes keep
    /// apart ([`guarded`]) no longer shrink the balls.
    pub fn compute(
        &mut self,
        surface: Surface<'_>,
        others: Option<Others<'_>>,
        resting: Option<Resting<'_>>,
        x: &[Vec3],
        wanted: f32,
        bounds: &mut [Bound],
    ) {
        let Surface { triangles, edges } = surface;
        // Without a still vertex or another cloth there is no pair to leave to the planes.
        let resting = resting.filter(|r| others.is_some() || r.mobility.contains(&Mobility::Still));
        let edge = if edges.is_empty() {
            0.0
        } else {
            edges.iter().map(|&[a, b]| x[a as usize].distance(x[b as usize])).sum::<f32>() / edges.len() as f32
        };
        let reach = (2.0 * wanted / GAMMA).clamp(0.125 * edge, edge);
        self.triangle_tree.refit(triangles.len(), |t| Aabb::around(triangles[t].map(|k| x[k as usize])));
        self.edge_tree.refit(edges.len(), |e| Aabb::around(edges[e].map(|k| x[k as usize])));
        self.nearest.resize_with(x.len(), AtomicU32::default);
        self.nearest
            .par_iter()
            .with_min_len(PARALLEL_MIN_LEN)
            .for_each(|d| d.store(reach.to_bits(), Ordering::Relaxed));
        if resting.is_some() {
            self.support.resize_with(x.len(), AtomicU64::default);
            self.support.par_iter().with_min_len(PARALLEL_MIN_LEN).for_each(|s| s.store(NO_SUPPORT, Ordering::Relaxed));
        }
        let mobility = |k: u32| resting.map_or(Mobility::Constrained, |r| r.mobility[k as usize]);
        let all_still = |vertices: &[u32]| vertices.iter().all(|&k| mobility(k) == Mobility::Still);
        // A pair with one side still and the other not: the still side's plane may keep
        // it apart, which only the pass after the planes knows.
        let one_side_still = |a: &[u32], b: &[u32]| all_still(a) != all_still(b);
        let Self { triangle_tree, edge_tree, nearest, support, vertices_left, edges_left, .. } = self;
        let (triangle_tree, edge_tree, nearest, support) = (&*triangle_tree, &*edge_tree, &*nearest, &*support);
        let lower = |k: u32, d: f32| lower_to(nearest, k, d);
        // Vertex `v` lies over still triangle `t` ([`Under::of`] numbers them) at distance `d`.
        let rest_on = |v: u32, t: u32, d: f32| {
            support[v as usize].fetch_min(u64::from(d.to_bits()) << 32 | u64::from(t), Ordering::Relaxed);
        };
        let theirs = others.filter(|_| resting.is_some());
        // A pair can lower no vertex's distance once it is at least the largest of its
        // vertices' distances so far, which only fall: skipping it where its boxes' gap
        // says so leaves every minimum, and so the bounds, as they were.
        let farthest = |vertices: &[u32]| farthest_in(nearest, vertices);
        let point_triangle = |p: Vec3, triangle: [u32; 3]| triangle_distance(p, triangle.map(|k| x[k as usize]));
        // Each vertex against the triangles around it; a free vertex's pairs with still
        // triangles, its own cloth's and the other cloths', are where it looks for the one
        // it lies over. Each says whether it left a pair with one side still to the
        // planes' pass, and so does each edge.
        (0..x.len() as u32)
            .into_par_iter()
            .with_min_len(PARALLEL_MIN_LEN)
            .map(|v| {
                let p = x[v as usize];
                let mut own = reach;
                let point = Aabb::around([p]);
                let mut left = false;
                triangle_tree.query(&point.inflated(reach), |t| {
                    let triangle = triangles[t as usize];
                    if triangle.contains(&v) {
                        return;
                    }
                    if one_side_still(&[v], &triangle) {
                        left = true;
                        if mobility(v) == Mobility::Free && point.distance(&triangle_tree.aabb(t)) < reach {
                            let over = lies_over(p, triangle.map(|k| x[k as usize])).filter(|&d| d < reach);
                            over.into_iter().for_each(|d| rest_on(v, t, d));
                        }
                        return;
                    }
                    if point.distance(&triangle_tree.aabb(t)) >= own.max(farthest(&triangle)) {
                        return;
                    }
                    let d = point_triangle(p, triangle);
                    if d < reach {
                        own = own.min(d);
                        triangle.iter().for_each(|&k| lower(k, d));
                    }
                });
                lower(v, own);
                if let Some(others) = theirs.filter(|_| mobility(v) == Mobility::Free) {
                    // Only this iteration sets `v`'s support: the nearest still triangle of
                    // its own cloth so far bounds the search. So does its nearest pair: a
                    // plane on a triangle farther than that would loosen nothing.
                    let limit = supporting(&support[v as usize]).map_or(own, |(_, d)| d.min(own));
                    if let Some((t, d)) = others.under(p, limit) {
                        rest_on(v, Under::theirs(t, triangles), d);
                    }
                }
                left
            })
            .collect_into_vec(vertices_left);
        // Each edge against the edges after it.
        (0..edges.len() as u32)
            .into_par_iter()
            .with_min_len(PARALLEL_MIN_LEN)
            .map(|e| {
                let [a, b] = edges[e as usize];
                let own = edge_tree.aabb(e);
                let mut left = false;
                edge_tree.query_from(&own.inflated(reach), e + 1, |f| {
                    let [c, d] = edges[f as usize];
                    if [a, b].contains(&c) || [a, b].contains(&d) {
                        return;
                    }
                    if one_side_still(&[a, b], &[c, d]) {
                        left = true;
                        return;
                    }
                    if own.distance(&edge_tree.aabb(f)) >= farthest(&[a, b, c, d]) {
                        return;
                    }
                    let distance = edge_edge(x, [a, b], [c, d]);
                    if distance < reach {
                        [a, b, c, d].into_iter().for_each(|k| lower(k, distance));
                    }
                });
                left
            })
            .collect_into_vec(edges_left);
        if let Some(resting) = resting {
            self.planes(triangles, x, others, resting.separation);
            self.guard(surface, resting, x, reach);
        } else {
            self.supported = false;
        }
        let Self { nearest, planes, .. } = &*self;
        // A pair with another cloth, which stands still, that the planes keep apart
        // bounds no ball.
        let kept = |moving: &[u32], still: &[Vec3]| {
            resting.is_some_and(|r| self.keeps_apart(x, moving, still, reach, r.separation))
        };
        let slack = resting.map_or(0.0, |r| SLACK * r.separation);
        if let Some(others) = others {
            let lower = |k: u32, d: f32| lower_to(nearest, k, d);
            let farthest = |vertices: &[u32]| farthest_in(nearest, vertices);
            let triangle_tree = &self.triangle_tree;
            let edge_tree = &self.edge_tree;
            let ClothSurfaces { positions: y, triangles: their_triangles, edges: their_edges, .. } = others.surfaces;
            // Each vertex against the other cloths' triangles: only the vertex moves, so
            // only those nearer than its nearest pair so far matter.
            (0..x.len() as u32).into_par_iter().with_min_len(PARALLEL_MIN_LEN).for_each(|v| {
                let p = x[v as usize];
                let mut own = f32::from_bits(nearest[v as usize].load(Ordering::Relaxed));
                let point = Aabb::around([p]);
                for part in others.parts() {
                    let (tree, their_triangles) = (&part.triangle_tree, &their_triangles[part.triangles.clone()]);
                    tree.query(&point.inflated(own), |t| {
                        if point.distance(&tree.aabb(t)) >= own {
                            return;
                        }
                        let corners = their_triangles[t as usize].map(|k| y[k as usize]);
                        let d = triangle_distance(p, corners);
                        if d < own && !kept(&[v], &corners) {
                            own = d;
                        }
                    });
                }
                lower(v, own);
            });
            // The other cloths' vertices against the cloth's triangles.
            for part in others.parts() {
                y[part.vertices.clone()].par_iter().with_min_len(PARALLEL_MIN_LEN).for_each(|&p| {
                    let point = Aabb::around([p]);
                    triangle_tree.query(&point.inflated(reach), |t| {
                        let triangle = triangles[t as usize];
                        if point.distance(&triangle_tree.aabb(t)) >= farthest(&triangle) {
                            return;
                        }
                        let d = triangle_distance(p, triangle.map(|k| x[k as usize]));
                        if !kept(&triangle, &[p]) {
                            triangle.iter().for_each(|&k| lower(k, d));
                        }
                    });
                });
            }
            // The cloth's edges against the other cloths' edges.
            (0..edges.len() as u32).into_par_iter().with_min_len(PARALLEL_MIN_LEN).for_each(|e| {
                let [a, b] = edges[e as usize];
                let (pa, pb) = (x[a as usize], x[b as usize]);
                let own = edge_tree.aabb(e);
                for part in others.parts() {
                    let (tree, their_edges) = (&part.edge_tree, &their_edges[part.edges.clone()]);
                    tree.query(&own.inflated(farthest(&[a, b])), |f| {
                        if own.distance(&tree.aabb(f)) >= farthest(&[a, b]) {
                            return;
                        }
                        let [pc, pd] = their_edges[f as usize].map(|k| y[k as usize]);
                        let distance = segment_distance([pa, pb], [pc, pd]);
                        if !kept(&[a, b], &[pc, pd]) {
                            [a, b].into_iter().for_each(|k| lower(k, distance));
                        }
                    });
                }
            });
        }
        bounds.par_iter_mut().zip(nearest.par_iter()).enumerate().with_min_len(PARALLEL_MIN_LEN).for_each(
            |(v, (bound, d))| {
                *bound = Bound::within(GAMMA * f32::from_bits(d.load(Ordering::Relaxed)));
                if let Some(&plane) = planes.get(v).filter(|p| resting.is_some() && **p != Vec4::ZERO) {
                    bound.plane = plane;
                    bound.slack = slack;
                }
            },
        );
    }

    /// Sets each free vertex's plane from the still triangle it lies over, if any: the
    /// triangle's plane, on the vertex's side, grown by the separation (`separation`, or
    /// with another cloth the two cloths' mean) less the slack, or through the vertex
    /// where it is nearer than that, so that measuring again never lets it closer (as a
    /// body's plane is placed, [`super::body_bounds`]).
    fn planes(&mut self, triangles: &[[u32; 3]], x: &[Vec3], others: Option<Others<'_>>, separation: f32) {
        let slack = SLACK * separation;
        let Self { support, planes, .. } = self;
        planes.resize(x.len(), Vec4::ZERO);
        planes.par_iter_mut().zip(support.par_iter()).enumerate().with_min_len(PARALLEL_MIN_LEN).for_each(
            |(v, (plane, s))| {
                *plane = match supporting(s).and_then(|(t, _)| Under::of(t, triangles, others)) {
                    None => Vec4::ZERO,
                    Some(under) => {
                        let (corners, separation) = match under {
                            Under::Own(t) => (triangles[t as usize].map(|k| x[k as usize]), separation),
                            Under::Theirs(others, t) => (others.corners(t), others.layers(t).separation),
                        };
                        let (normal, height) = over(corners, x[v]);
                        normal.extend(normal.dot(x[v]) - (height - separation + slack).max(0.0))
                    }
                };
            },
        );
        self.supported = self.planes.iter().any(|p| *p != Vec4::ZERO);
    }

    /// Lowers the distances of the pairs with one side still that the planes do not keep
    /// apart: every one where no vertex has a plane. Visits only the vertices and edges
    /// the first pass found such pairs of.
    fn guard(&self, surface: Surface<'_>, resting: Resting<'_>, x: &[Vec3], reach: f32) {
        let Surface { triangles, edges } = surface;
        let Self { triangle_tree, edge_tree, nearest, vertices_left, edges_left, .. } = self;
        let still = |k: u32| resting.mobility[k as usize] == Mobility::Still;
        let all_still = |vertices: &[u32]| vertices.iter().all(|&k| still(k));
        let lower = |k: u32, d: f32| lower_to(nearest, k, d);
        let farthest = |vertices: &[u32]| farthest_in(nearest, vertices);
        let kept = |moving: &[u32], still: &[Vec3]| self.keeps_apart(x, moving, still, reach, resting.separation);
        let at = |k: u32| x[k as usize];
        let vertices = (0..x.len() as u32).into_par_iter().with_min_len(PARALLEL_MIN_LEN);
        vertices.filter(|&v| vertices_left[v as usize]).for_each(|v| {
            let p = x[v as usize];
            let point = Aabb::around([p]);
            triangle_tree.query(&point.inflated(reach), |t| {
                let triangle = triangles[t as usize];
                let (v_still, t_still) = (still(v), all_still(&triangle));
                if triangle.contains(&v)
                    || v_still == t_still
                    || point.distance(&triangle_tree.aabb(t)) >= farthest(&[v, triangle[0], triangle[1], triangle[2]])
                {
                    return;
                }
                let d = triangle_distance(p, triangle.map(|k| x[k as usize]));
                let apart = || if v_still { kept(&triangle, &[p]) } else { kept(&[v], &triangle.map(at)) };
                if d < reach && !apart() {
                    [v, triangle[0], triangle[1], triangle[2]].into_iter().for_each(|k| lower(k, d));
                }
            });
        });
        let edge_numbers = (0..edges.len() as u32).into_par_iter().with_min_len(PARALLEL_MIN_LEN);
        edge_numbers.filter(|&e| edges_left[e as usize]).for_each(|e| {
            let [a, b] = edges[e as usize];
            let own = edge_tree.aabb(e);
            edge_tree.query_from(&own.inflated(reach), e + 1, |f| {
                let [c, d] = edges[f as usize];
                let (e_still, f_still) = (all_still(&[a, b]), all_still(&[c, d]));
                if [a, b].contains(&c)
                    || [a, b].contains(&d)
                    || e_still == f_still
                    || own.distance(&edge_tree.aabb(f)) >= farthest(&[a, b, c, d])
                {
                    return;
                }
                let distance = edge_edge(x, [a, b], [c, d]);
                let apart = || if e_still { kept(&[c, d], &[at(a), at(b)]) } else { kept(&[a, b], &[at(c), at(d)]) };
                if distance < reach && !apart() {
                    [a, b, c, d].into_iter().for_each(|k| lower(k, distance));
                }
            });
        });
    }

    /// Whether the planes of this call keep the `moving` vertices, at `x`, off the `still`
    /// points whatever they do within balls of up to `GAMMA · reach` ([`guarded`]), with
    /// a slack of the layers' `separation`.
    fn keeps_apart(&self, x: &[Vec3], moving: &[u32], still: &[Vec3], reach: f32, separation: f32) -> bool {
        self.supported && guarded(&self.planes, x, moving, still, GAMMA * reach, SLACK * separation)
    }

    /// Whether the last call gave any vertex a still triangle's plane.
    pub fn supported(&self) -> bool {
        self.supported
    }

    /// The still triangle vertex `i`, at `end[i]`, rests on, of those the planes of the
    /// last call stood on (the cloth's own `triangles`, or those of the `others` the call
    /// was given): one whose plane it lies beyond by no more than the layers' separation
    /// (and what the contact stage lets pass as round-off). Its normal towards the vertex,
    /// its velocity under the vertex (an own triangle's vertices' moves from `start` over
    /// `h`, another cloth's velocities) and the layers' friction.
    #[allow(clippy::too_many_arguments)]
    pub fn resting_on(
        &self,
        triangles: &[[u32; 3]],
        others: Option<Others<'_>>,
        layers: LayerContact,
        i: usize,
        end: &[Vec3],
        start: &[Vec3],
        h: f32,
    ) -> Option<(Vec3, Vec3, f32)> {
        let (t, _) = supporting(self.support.get(i).filter(|_| self.supported)?)?;
        let under = Under::of(t, triangles, others)?;
        let (corners, layers) = match under {
            Under::Own(t) => (triangles[t as usize].map(|k| end[k as usize]), layers),
            Under::Theirs(others, t) => (others.corners(t), others.layers(t)),
        };
        let (normal, height) = over(corners, end[i]);
        if height <= 0.0 || height > layers.separation * (1.0 + CAUGHT) {
            return None;
        }
        let [a, b, c] = corners;
        let w = closest_on_triangle(end[i], a, b, c);
        let velocity = match under {
            Under::Own(t) => {
                let triangle = triangles[t as usize];
                (0..3).map(|k| w[k] * (end[triangle[k] as usize] - start[triangle[k] as usize])).sum::<Vec3>() / h
            }
            Under::Theirs(others, t) => others.velocity(t, w),
        };
        Some((normal, velocity, layers.friction))
    }
}

/// The bound's [`Bound::slack`] beyond a still triangle's plane, as a fraction of the
/// layers' separation: as a body's is of its thickness.
const SLACK: f32 = 0.5 * CAUGHT;

/// The distance from `p` to the triangle with corners `corners`.
fn triangle_distance(p: Vec3, corners: [Vec3; 3]) -> f32 {
    let [a, b, c] = corners;
    let w = closest_on_triangle(p, a, b, c);
    p.distance(w[0] * a + w[1] * b + w[2] * c)
}

/// Lowers vertex `k`'s nearest distance to `d`.
fn lower_to(nearest: &[AtomicU32], k: u32, d: f32) {
    nearest[k as usize].fetch_min(d.to_bits(), Ordering::Relaxed);
}

/// The largest nearest distance so far of `vertices`.
fn farthest_in(nearest: &[AtomicU32], vertices: &[u32]) -> f32 {
    vertices.iter().map(|&k| f32::from_bits(nearest[k as usize].load(Ordering::Relaxed))).fold(0.0, f32::max)
}

/// The still triangle a vertex's support holds, if any, and the vertex's distance from it.
fn supporting(support: &AtomicU64) -> Option<(u32, f32)> {
    let s = support.load(Ordering::Relaxed);
    (s != NO_SUPPORT).then_some(((s & u64::from(u32::MAX)) as u32, f32::from_bits((s >> 32) as u32)))
}

/// The triangle with corners `corners` seen from `p`: its unit normal on `p`'s side, and
/// `p`'s height above its plane.
fn over(corners: [Vec3; 3], p: Vec3) -> (Vec3, f32) {
    let [a, b, c] = corners;
    let normal = (b - a).cross(c - a).normalize_or_zero();
    let height = normal.dot(p - a);
    if height < 0.0 { (-normal, -height) } else { (normal, height) }
}

/// `p`'s distance from the triangle with corners `corners` where `p` lies over it: its
/// height above the triangle's plane at least [`OVER`] of that distance.
fn lies_over(p: Vec3, corners: [Vec3; 3]) -> Option<f32> {
    let (d, (_, height)) = (triangle_distance(p, corners), over(corners, p));
    (height > 0.0 && height >= OVER * d).then_some(d)
}

/// A still triangle that a vertex's support names ([`MotionBounds::support`]).
#[derive(Debug, Clone, Copy)]
enum Under<'a> {
    /// The cloth's own triangle, numbered below its triangles' count.
    Own(u32),
    /// Another cloth's, numbered after them by its number in the surfaces.
    Theirs(Others<'a>, u32),
}

impl<'a> Under<'a> {
    /// The triangle support number `t` names, of the cloth's `triangles` or the
    /// `others`'; `None` for another cloth's without them.
    fn of(t: u32, triangles: &[[u32; 3]], others: Option<Others<'a>>) -> Option<Self> {
        let own = triangles.len() as u32;
        if t < own { Some(Self::Own(t)) } else { others.map(|others| Self::Theirs(others, t - own)) }
    }

    /// The support number of another cloth's triangle `t` (in the surfaces' numbering).
    fn theirs(t: u32, triangles: &[[u32; 3]]) -> u32 {
        triangles.len() as u32 + t
    }
}

/// The distance between edges `e` and `f` at `x`.
fn edge_edge(x: &[Vec3], e: [u32; 2], f: [u32; 2]) -> f32 {
    segment_distance(e.map(|k| x[k as usize]), f.map(|k| x[k as usize]))
}

/// The distance between the segments `[pa, pb]` and `[pc, pd]`.
fn segment_distance([pa, pb]: [Vec3; 2], [pc, pd]: [Vec3; 2]) -> f32 {
    let (s, t) = closest_between_segments(pa, pb, pc, pd);
    (pa + s * (pb - pa)).distance(pc + t * (pd - pc))
}

/// Whether the planes keep the `moving` vertices, at `x` where their bounds are measured,
/// off the `still` points whatever they do within their bounds: every moving vertex has a
/// plane, and the first one's plane has the still vertices behind it by more than
/// `tolerance`, and every moving vertex ahead of it. Each vertex `u` keeps to its own
/// plane, `n_u · y ≥ w_u`, and within `travel` of `x_u`, so along the first's normal `n`,
/// `n · y − w ≥ (w_u − w) + (n − n_u) · x_u − |n − n_u| travel`; a point of the moving
/// primitive is a convex combination of its vertices, so it lies ahead of the least of
/// these. On a flat still layer the planes agree to round-off and the test holds with the
/// whole gap to spare; where they disagree by more than the gap over a move, it fails,
/// and the pair bounds the balls.
fn guarded(planes: &[Vec4], x: &[Vec3], moving: &[u32], still: &[Vec3], travel: f32, tolerance: f32) -> bool {
    let first = planes[moving[0] as usize];
    if moving.iter().any(|&u| planes[u as usize] == Vec4::ZERO) {
        return false;
    }
    let (normal, w) = (first.truncate(), first.w);
    let ahead = moving
        .iter()
        .map(|&u| {
            let plane = planes[u as usize];
            let tilt = normal - plane.truncate();
            (plane.w - w) + tilt.dot(x[u as usize]) - tilt.length() * travel
        })
        .fold(f32::INFINITY, f32::min);
    let behind = still.iter().map(|&q| normal.dot(q) - w).fold(f32::NEG_INFINITY, f32::max);
    behind < ahead - tolerance
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::collision::primitives::Sweep;
    use crate::collision::self_contact::ContactMesh;

    /// A small deterministic generator: the tests need scattered numbers, not good ones.
    pub(crate) struct Lcg(pub(crate) u64);

    impl Lcg {
        pub(crate) fn next(&mut self) -> f32 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (self.0 >> 40) as f32 / (1u64 << 24) as f32
        }

        fn direction(&mut self) -> Vec3 {
            loop {
                let v = Vec3::new(self.next(), self.next(), self.next()) * 2.0 - Vec3::ONE;
                if (0.01..1.0).contains(&v.length_squared()) {
                    return v.normalize();
                }
            }
        }
    }

    /// Two crumpled 6 × 6 sheets 4 mm apart, as one mesh: the lower one's 36 vertices
    /// first, each above the other's vertex of the same number less 36.
    pub(crate) fn two_layers(rng: &mut Lcg) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let (n, spacing) = (6u32, 0.01f32);
        let mut x = Vec::new();
        let mut triangles = Vec::new();
        for layer in 0..2u32 {
            let offset = layer * n * n;
            for i in 0..n {
                for j in 0..n {
                    let y = 0.004 * layer as f32 + 0.0015 * (rng.next() - 0.5);
                    x.push(Vec3::new(i as f32 * spacing, y, j as f32 * spacing));
                }
            }
            for i in 0..n - 1 {
                for j in 0..n - 1 {
                    let k = offset + i * n + j;
                    triangles.push([k, k + n, k + 1]);
                    triangles.push([k + 1, k + n, k + n + 1]);
                }
            }
        }
        (x, triangles)
    }

    /// Whether any vertex passes through a triangle or any edge through an edge it does
    /// not share a vertex with, moving on straight lines from `x0` to `x1`.
    pub(crate) fn any_crossing(triangles: &[[u32; 3]], edges: &[[u32; 2]], x0: &[Vec3], x1: &[Vec3]) -> bool {
        let sweep = |k: [u32; 4]| Sweep { start: k.map(|i| x0[i as usize]), end: k.map(|i| x1[i as usize]) };
        let point_triangle = (0..x0.len() as u32).any(|p| {
            triangles
                .iter()
                .any(|&[a, b, c]| ![a, b, c].contains(&p) && sweep([p, a, b, c]).point_triangle_hit(0.0).is_some())
        });
        let edge_edge = edges.iter().enumerate().any(|(i, &[a, b])| {
            edges[i + 1..].iter().any(|&[c, d]| {
                ![a, b].contains(&c) && ![a, b].contains(&d) && sweep([a, b, c, d]).edge_edge_hit(0.0).is_some()
            })
        });
        point_triangle || edge_edge
    }

    #[test]
    fn moves_within_the_bounds_cross_nothing_and_moves_past_them_do() {
        let mut rng = Lcg(7);
        let (x0, triangles) = two_layers(&mut rng);
        let edges = ContactMesh::edges_of(&triangles);
        let surface = Surface { triangles: &triangles, edges: &edges };
        let mut bounds = vec![Bound::FREE; x0.len()];
        let mut motion = MotionBounds::default();
        motion.compute(surface, None, None, &x0, 1.0, &mut bounds);
        // Each bound is at most GAMMA times the layers' gap: the nearest pair of a vertex
        // is across the gap (4 ± 1.5 mm) or along its own sheet (7 mm).
        assert!(bounds.iter().all(|b| b.plane == Vec4::ZERO && b.radius > 0.0 && b.radius <= GAMMA * 0.0055 + 1e-6));
        // Every vertex moves its whole bound, the top layer down and the bottom up or in
        // random directions: nothing crosses.
        for trial in 0..20 {
            let x1: Vec<Vec3> = x0
                .iter()
                .zip(&bounds)
                .enumerate()
                .map(|(i, (p, b))| {
                    let towards = if i < 36 { Vec3::Y } else { -Vec3::Y };
                    let direction = if trial % 2 == 0 { towards } else { rng.direction() };
                    *p + b.radius * direction
                })
                .collect();
            assert!(!any_crossing(&triangles, &edges, &x0, &x1), "trial {trial} crossed");
        }
        // The top layer pressed through the bottom one by 1.2 cm crosses: the check can fail.
        let through: Vec<Vec3> =
            x0.iter().enumerate().map(|(i, p)| if i < 36 { *p } else { *p - 0.012 * Vec3::Y }).collect();
        assert!(any_crossing(&triangles, &edges, &x0, &through));
        // A second call over the same mesh gives the same bounds.
        let mut again = vec![Bound::FREE; x0.len()];
        motion.compute(surface, None, None, &x0, 1.0, &mut again);
        assert_eq!(again, bounds);
    }

    #[test]
    fn another_cloth_standing_still_bounds_a_cloth_as_its_own_layer_would() {
        // The two layers as two cloths: the lower one stands still while the upper one
        // is solved.
        let mut rng = Lcg(11);
        let (x, triangles) = two_layers(&mut rng);
        let (lower, upper) = triangles.split_at(triangles.len() / 2);
        let upper: Vec<[u32; 3]> = upper.iter().map(|t| t.map(|k| k - 36)).collect();
        let (lower_edges, upper_edges) = (ContactMesh::edges_of(lower), ContactMesh::edges_of(&upper));
        let (x_lower, x_upper) = x.split_at(36);
        let mut surfaces = ClothSurfaces::default();
        surfaces.clear();
        let (layers, still) = (LayerContact { separation: 0.002, friction: 0.3 }, [Vec3::ZERO; 36]);
        surfaces.add(Surface { triangles: lower, edges: &lower_edges }, layers, x_lower, &still);
        let own = surfaces.add(Surface { triangles: &upper, edges: &upper_edges }, layers, x_upper, &still);
        assert!(surfaces.others(own).is_some());
        let surface = Surface { triangles: &upper, edges: &upper_edges };
        let mut motion = MotionBounds::default();
        let (mut alone, mut bounds) = (vec![Bound::FREE; 36], vec![Bound::FREE; 36]);
        motion.compute(surface, None, None, x_upper, 1.0, &mut alone);
        motion.compute(surface, surfaces.others(own), None, x_upper, 1.0, &mut bounds);
        // Alone, each vertex is bounded by its own sheet (7 mm to the nearest diagonal);
        // with the other cloth, by the gap (4 ± 1.5 mm).
        assert!(alone.iter().all(|b| b.radius > GAMMA * 0.0065), "{alone:?}");
        assert!(bounds.iter().all(|b| b.radius > 0.0 && b.radius <= GAMMA * 0.0055 + 1e-6), "{bounds:?}");
        // The upper cloth's vertices each move their whole bound, down or anywhere, the
        // lower one standing: nothing crosses.
        let edges = ContactMesh::edges_of(&triangles);
        let moved = |bounds: &[Bound], direction: &mut dyn FnMut() -> Vec3| -> Vec<Vec3> {
            let upper = x_upper.iter().zip(bounds).map(|(p, b)| *p + b.radius * direction());
            x_lower.iter().copied().chain(upper).collect()
        };
        for trial in 0..20 {
            let x1 = match trial % 2 {
                0 => moved(&bounds, &mut || -Vec3::Y),
                _ => moved(&bounds, &mut || rng.direction()),
            };
            assert!(!any_crossing(&triangles, &edges, &x, &x1), "trial {trial} crossed");
        }
        // The lower cloth moved away loosens the bounds.
        let away: Vec<Vec3> = x_lower.iter().map(|p| *p - 0.01 * Vec3::Y).collect();
        surfaces.moved(0, &away, &still);
        let mut looser = vec![Bound::FREE; 36];
        motion.compute(surface, surfaces.others(own), None, x_upper, 1.0, &mut looser);
        assert_eq!(looser, alone);
    }

    /// The two layers of [`two_layers`], the lower one smoothed to a tenth of its
    /// roughness (±0.075 mm), the upper one 1.5 mm lower, 2.5 ± 0.75 mm up: within reach
    /// of its balls.
    fn a_layer_over_a_smooth_one(rng: &mut Lcg) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let (mut x, triangles) = two_layers(rng);
        x[..36].iter_mut().for_each(|p| p.y *= 0.1);
        x[36..].iter_mut().for_each(|p| p.y -= 0.0015);
        (x, triangles)
    }

    /// Checks the bounds `upper` of the upper layer of [`a_layer_over_a_smooth_one`] at
    /// `x0`, measured with the lower one still and a 2 mm separation, against `balls`,
    /// measured without the planes; returns the upper vertices (numbered from 0) given a
    /// plane. Those over the lower layer's middle keep to a plane at 2 mm, and their balls
    /// are set by their own sheet, its nearest diagonal 7 mm away, where without the
    /// planes every ball is 0.4 of the gap. Every upper vertex moving as far as its bound
    /// lets it (along the layer, down into it or anywhere, its move cut at its plane)
    /// crosses nothing; the same moves down past the planes cross.
    fn planes_hold(x0: &[Vec3], triangles: &[[u32; 3]], upper: &[Bound], balls: &[Bound], rng: &mut Lcg) -> Vec<usize> {
        assert!(balls.iter().all(|b| b.radius <= GAMMA * 0.0035 + 1e-6));
        let planed: Vec<usize> = (0..36).filter(|&i| upper[i].plane != Vec4::ZERO).collect();
        let loosened = planed.iter().filter(|&&i| upper[i].radius > GAMMA * 0.0065).count();
        assert!(planed.len() >= 16 && loosened >= 8, "{} planes, {loosened} balls loosened", planed.len());
        for &i in &planed {
            let room = upper[i].room(x0[36 + i]);
            assert!((0.0..0.002).contains(&room), "vertex {i}: {room} m beyond its plane");
        }
        let edges = ContactMesh::edges_of(triangles);
        let moved = |bounds: &[Bound], direction: &mut dyn FnMut() -> Vec3| -> Vec<Vec3> {
            let lower = x0[..36].iter().copied();
            lower
                .chain(x0[36..].iter().zip(bounds).map(|(&p, b)| {
                    let step = b.radius * direction();
                    p + b.plane_allows(p, step) * step
                }))
                .collect()
        };
        for trial in 0..30 {
            let x1 = match trial % 3 {
                0 => moved(upper, &mut || -Vec3::Y),
                1 => {
                    let along = rng.direction().with_y(-0.2).normalize();
                    moved(upper, &mut || along)
                }
                _ => moved(upper, &mut || rng.direction()),
            };
            assert!(!any_crossing(triangles, &edges, x0, &x1), "trial {trial} crossed");
        }
        // The planes do the holding: many balls reach past them. And the check can fail.
        assert!(planed.iter().filter(|&&i| upper[i].radius > upper[i].room(x0[36 + i])).count() >= 8);
        let through = moved(&upper.iter().map(|b| Bound::within(b.radius)).collect::<Vec<_>>(), &mut || -Vec3::Y);
        assert!(any_crossing(triangles, &edges, x0, &through));
        planed
    }

    #[test]
    fn a_layer_over_a_still_layer_keeps_to_its_planes_and_slides_past_its_balls() {
        // The lower layer still (pinned): each upper vertex keeps to the plane of the
        // lower triangle under it. (Over the crumpled one of `two_layers`, whose
        // triangles' planes differ by a tenth of a radian, most pairs fail the planes'
        // test.)
        let mut rng = Lcg(5);
        let (x0, triangles) = a_layer_over_a_smooth_one(&mut rng);
        let edges = ContactMesh::edges_of(&triangles);
        let surface = Surface { triangles: &triangles, edges: &edges };
        let mobility: Vec<Mobility> = (0..72).map(|i| if i < 36 { Mobility::Still } else { Mobility::Free }).collect();
        let resting = Resting { mobility: &mobility, separation: 0.002 };
        let (mut balls, mut bounds) = (vec![Bound::FREE; 72], vec![Bound::FREE; 72]);
        let mut motion = MotionBounds::default();
        motion.compute(surface, None, None, &x0, 1.0, &mut balls);
        motion.compute(surface, None, Some(resting), &x0, 1.0, &mut bounds);
        assert!(motion.supported());
        let planed = planes_hold(&x0, &triangles, &bounds[36..], &balls[36..], &mut rng);
        // The friction's support: an upper vertex on its plane rests on the layer, one
        // lifted away does not.
        let layers = LayerContact { separation: 0.002, friction: 0.3 };
        let i = 36 + planed[0];
        let mut end = x0.clone();
        end[i] -= bounds[i].room(x0[i]) * bounds[i].plane.truncate();
        let resting_on = |end: &[Vec3]| motion.resting_on(&triangles, None, layers, i, end, &x0, 0.01);
        let (normal, velocity, friction) = resting_on(&end).expect("rests");
        assert!(normal.y > 0.9 && velocity == Vec3::ZERO && friction == 0.3, "{normal} {velocity}");
        end[i] += 0.01 * Vec3::Y;
        assert!(resting_on(&end).is_none());
    }

    #[test]
    fn a_cloth_over_another_standing_still_keeps_to_its_planes_and_slides_past_its_balls() {
        // The same layers as two cloths, the lower one standing still while the upper one,
        // all of it free, is solved: the lower cloth's triangles give the planes.
        let mut rng = Lcg(5);
        let (x0, triangles) = a_layer_over_a_smooth_one(&mut rng);
        let (lower, upper) = triangles.split_at(triangles.len() / 2);
        let upper: Vec<[u32; 3]> = upper.iter().map(|t| t.map(|k| k - 36)).collect();
        let (lower_edges, upper_edges) = (ContactMesh::edges_of(lower), ContactMesh::edges_of(&upper));
        let (x_lower, x_upper) = x0.split_at(36);
        // The lower cloth drifts at 0.1 m/s, with more friction than the upper one.
        let drift = [Vec3::new(0.1, 0.0, 0.0); 36];
        let (own, theirs) =
            (LayerContact { separation: 0.002, friction: 0.3 }, LayerContact { separation: 0.002, friction: 0.5 });
        let mut surfaces = ClothSurfaces::default();
        surfaces.add(Surface { triangles: lower, edges: &lower_edges }, theirs, x_lower, &drift);
        let cloth = surfaces.add(Surface { triangles: &upper, edges: &upper_edges }, own, x_upper, &[Vec3::ZERO; 36]);
        let surface = Surface { triangles: &upper, edges: &upper_edges };
        let mobility = [Mobility::Free; 36];
        let resting = Resting { mobility: &mobility, separation: 0.002 };
        let (mut balls, mut bounds) = (vec![Bound::FREE; 36], vec![Bound::FREE; 36]);
        let mut motion = MotionBounds::default();
        let others = surfaces.others(cloth);
        motion.compute(surface, others, None, x_upper, 1.0, &mut balls);
        motion.compute(surface, others, Some(resting), x_upper, 1.0, &mut bounds);
        assert!(motion.supported());
        let planed = planes_hold(&x0, &triangles, &bounds, &balls, &mut rng);
        // It rests on the lower cloth, sliding against its drift, with the mean friction.
        let i = planed[0];
        let mut end = x_upper.to_vec();
        end[i] -= bounds[i].room(x_upper[i]) * bounds[i].plane.truncate();
        let resting_on = |end: &[Vec3]| motion.resting_on(&upper, others, own, i, end, x_upper, 0.01);
        let (normal, velocity, friction) = resting_on(&end).expect("rests");
        assert!(normal.y > 0.9 && (velocity - drift[0]).length() < 1e-6 && friction == 0.4, "{normal} {velocity}");
        end[i] += 0.01 * Vec3::Y;
        assert!(resting_on(&end).is_none());
    }

    #[test]
    fn a_lone_flat_sheet_is_bounded_by_its_own_nearest_primitives() {
        // A flat 4 × 4 grid of unit spacing split along one diagonal: a vertex's nearest
        // primitive not touching it is a diagonal edge of a neighbouring cell, 1/√2 away.
        let n = 4u32;
        let x: Vec<Vec3> = (0..n * n).map(|k| Vec3::new((k / n) as f32, 0.0, (k % n) as f32)).collect();
        let mut triangles = Vec::new();
        for i in 0..n - 1 {
            for j in 0..n - 1 {
                let k = i * n + j;
                triangles.push([k, k + n, k + 1]);
                triangles.push([k + 1, k + n, k + n + 1]);
            }
        }
        let edges = ContactMesh::edges_of(&triangles);
        let mut bounds = vec![Bound::FREE; x.len()];
        MotionBounds::default().compute(
            Surface { triangles: &triangles, edges: &edges },
            None,
            None,
            &x,
            1.0,
            &mut bounds,
        );
        let reach: f32 =
            edges.iter().map(|&[a, b]| x[a as usize].distance(x[b as usize])).sum::<f32>() / edges.len() as f32;
        assert!(reach > std::f32::consts::FRAC_1_SQRT_2);
        for (v, b) in bounds.iter().enumerate() {
            assert!((b.radius - GAMMA * std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-6, "vertex {v}: {b:?}");
        }
    }
}
