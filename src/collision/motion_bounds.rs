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

use std::ops::Range;
use std::sync::atomic::{AtomicU32, Ordering};

use glam::{Vec3, Vec4};
use rayon::prelude::*;

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
    /// The cloths' vertices, one cloth after another.
    positions: Vec<Vec3>,
    /// Their triangles and edges, numbered in `positions`.
    triangles: Vec<[u32; 3]>,
    edges: Vec<[u32; 2]>,
    /// The first `count` are the cloths'; those after, kept for their trees' buffers.
    parts: Vec<SurfacePart>,
    count: usize,
}

/// One cloth of [`ClothSurfaces`]: where its vertices, triangles and edges begin and end
/// there, and the trees over its triangles and edges, numbered from its first.
#[derive(Debug, Default)]
struct SurfacePart {
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
        self.triangles.clear();
        self.edges.clear();
        self.count = 0;
    }

    /// Adds a cloth's `surface` at `positions` after the cloths added since the last
    /// [`ClothSurfaces::clear`], fitting its trees, and returns its number among them.
    pub fn add(&mut self, surface: Surface<'_>, positions: &[Vec3]) -> usize {
        let offset = self.positions.len() as u32;
        let (triangles, edges) = (self.triangles.len(), self.edges.len());
        self.triangles.extend(surface.triangles.iter().map(|t| t.map(|k| k + offset)));
        self.edges.extend(surface.edges.iter().map(|e| e.map(|k| k + offset)));
        self.positions.extend_from_slice(positions);
        if self.parts.len() == self.count {
            self.parts.push(SurfacePart::default());
        }
        let part = &mut self.parts[self.count];
        part.vertices = offset as usize..self.positions.len();
        part.triangles = triangles..self.triangles.len();
        part.edges = edges..self.edges.len();
        self.count += 1;
        self.refit(self.count - 1);
        self.count - 1
    }

    /// Moves cloth `cloth` to `positions`, where its step ended, and refits its trees.
    pub fn moved(&mut self, cloth: usize, positions: &[Vec3]) {
        let vertices = self.parts[cloth].vertices.clone();
        self.positions[vertices].copy_from_slice(positions);
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
    /// still, bound the vertices too.
    pub fn compute(
        &mut self,
        surface: Surface<'_>,
        others: Option<Others<'_>>,
        x: &[Vec3],
        wanted: f32,
        bounds: &mut [Bound],
    ) {
        let Surface { triangles, edges } = surface;
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
        let Self { triangle_tree, edge_tree, nearest } = &*self;
        let lower = |k: u32, d: f32| {
            nearest[k as usize].fetch_min(d.to_bits(), Ordering::Relaxed);
        };
        // A pair can lower no vertex's distance once it is at least the largest of its
        // vertices' distances so far, which only fall: skipping it where its boxes' gap
        // says so leaves every minimum, and so the bounds, as they were.
        let farthest = |vertices: &[u32]| {
            vertices.iter().map(|&k| f32::from_bits(nearest[k as usize].load(Ordering::Relaxed))).fold(0.0, f32::max)
        };
        // Each vertex against the triangles around it.
        (0..x.len() as u32).into_par_iter().with_min_len(PARALLEL_MIN_LEN).for_each(|v| {
            let p = x[v as usize];
            let mut own = reach;
            let point = Aabb::around([p]);
            triangle_tree.query(&point.inflated(reach), |t| {
                let triangle = triangles[t as usize];
                if triangle.contains(&v) || point.distance(&triangle_tree.aabb(t)) >= own.max(farthest(&triangle)) {
                    return;
                }
                let [a, b, c] = triangle.map(|k| x[k as usize]);
                let w = closest_on_triangle(p, a, b, c);
                let d = p.distance(w[0] * a + w[1] * b + w[2] * c);
                if d < reach {
                    own = own.min(d);
                    triangle.iter().for_each(|&k| lower(k, d));
                }
            });
            lower(v, own);
        });
        // Each edge against the edges after it.
        (0..edges.len() as u32).into_par_iter().with_min_len(PARALLEL_MIN_LEN).for_each(|e| {
            let [a, b] = edges[e as usize];
            let (pa, pb) = (x[a as usize], x[b as usize]);
            let own = edge_tree.aabb(e);
            edge_tree.query_from(&own.inflated(reach), e + 1, |f| {
                let [c, d] = edges[f as usize];
                if [a, b].contains(&c)
                    || [a, b].contains(&d)
                    || own.distance(&edge_tree.aabb(f)) >= farthest(&[a, b, c, d])
                {
                    return;
                }
                let (pc, pd) = (x[c as usize], x[d as usize]);
                let (s, t) = closest_between_segments(pa, pb, pc, pd);
                let distance = (pa + s * (pb - pa)).distance(pc + t * (pd - pc));
                if distance < reach {
                    [a, b, c, d].into_iter().for_each(|k| lower(k, distance));
                }
            });
        });
        if let Some(others) = others {
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
                        let [a, b, c] = their_triangles[t as usize].map(|k| y[k as usize]);
                        let w = closest_on_triangle(p, a, b, c);
                        own = own.min(p.distance(w[0] * a + w[1] * b + w[2] * c));
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
                        let [a, b, c] = triangle.map(|k| x[k as usize]);
                        let w = closest_on_triangle(p, a, b, c);
                        let d = p.distance(w[0] * a + w[1] * b + w[2] * c);
                        triangle.iter().for_each(|&k| lower(k, d));
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
                        let (s, t) = closest_between_segments(pa, pb, pc, pd);
                        let distance = (pa + s * (pb - pa)).distance(pc + t * (pd - pc));
                        [a, b].into_iter().for_each(|k| lower(k, distance));
                    });
                }
            });
        }
        bounds
            .par_iter_mut()
            .zip(nearest.par_iter())
            .with_min_len(PARALLEL_MIN_LEN)
            .for_each(|(bound, d)| *bound = Bound::within(GAMMA * f32::from_bits(d.load(Ordering::Relaxed))));
    }
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
        motion.compute(surface, None, &x0, 1.0, &mut bounds);
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
        motion.compute(surface, None, &x0, 1.0, &mut again);
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
        surfaces.add(Surface { triangles: lower, edges: &lower_edges }, x_lower);
        let own = surfaces.add(Surface { triangles: &upper, edges: &upper_edges }, x_upper);
        assert!(surfaces.others(own).is_some());
        let surface = Surface { triangles: &upper, edges: &upper_edges };
        let mut motion = MotionBounds::default();
        let (mut alone, mut bounds) = (vec![Bound::FREE; 36], vec![Bound::FREE; 36]);
        motion.compute(surface, None, x_upper, 1.0, &mut alone);
        motion.compute(surface, surfaces.others(own), x_upper, 1.0, &mut bounds);
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
        surfaces.moved(0, &away);
        let mut looser = vec![Bound::FREE; 36];
        motion.compute(surface, surfaces.others(own), x_upper, 1.0, &mut looser);
        assert_eq!(looser, alone);
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
        MotionBounds::default().compute(Surface { triangles: &triangles, edges: &edges }, None, &x, 1.0, &mut bounds);
        let reach: f32 =
            edges.iter().map(|&[a, b]| x[a as usize].distance(x[b as usize])).sum::<f32>() / edges.len() as f32;
        assert!(reach > std::f32::consts::FRAC_1_SQRT_2);
        for (v, b) in bounds.iter().enumerate() {
            assert!((b.radius - GAMMA * std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-6, "vertex {v}: {b:?}");
        }
    }
}
