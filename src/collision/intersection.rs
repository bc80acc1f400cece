//! Counting intersecting triangle pairs of a cloth: an exact test, independent of the
//! contact code, that measures whether the cloth has passed through itself.

use std::ops::Range;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::solver::PARALLEL_MIN_LEN;
use crate::solver::reduce::reduce;

/// Number of pairs of triangles that share no vertex and intersect: an edge of one
/// crosses the interior of the other. Candidate pairs come from a grid over the
/// triangles' bounding boxes; the crossing test runs in double precision.
pub fn count_self_intersections(x: &[Vec3], triangles: &[[u32; 3]]) -> usize {
    IntersectionCounter::default().count(x, triangles)
}

/// [`count_self_intersections`] with its buffers kept between counts, for a probe that
/// counts every frame.
#[derive(Debug, Clone, Default)]
pub struct IntersectionCounter {
    /// Each triangle's bounding box in the grid's units ([`GridBox`]), read for every
    /// candidate pair: computed there each time, the count took 5.5 ms on a 128² sheet
    /// instead of 4.7.
    boxes: Vec<GridBox>,
    /// The grid cell holding each triangle's bounding-box centre, as a key.
    cells: Vec<u32>,
    /// The triangles, grouped by the hash bucket of their cell, in index order within a
    /// bucket.
    slots: Vec<u32>,
    /// The end of each bucket's triangles in `slots` (the start of the next).
    ends: Vec<u32>,
}

impl IntersectionCounter {
    /// Number of pairs of triangles of `x` that share no vertex and intersect.
    ///
    /// Candidate pairs come from a uniform grid whose cells are as wide as the widest
    /// bounding box: two boxes overlap only if their centres lie in neighbouring cells,
    /// and a cell holds a handful of triangles, so the work grows with the triangle count.
    /// The cells are hashed into a table twice as long as the triangle list. (A sweep
    /// along one axis met every box of a strip across the sheet, √n of them: 61 ms a
    /// count on a 256² sheet on two threads. A box tree finds as few candidates but cost
    /// 260 bytes a particle of hang_64.) The boxes are kept in the grid's units, rounded
    /// outwards, and the cells' keys in 32 bits: 20 bytes a triangle where `f32` corners
    /// and 64-bit keys took 32 (24 bytes a particle of a sheet).
    pub fn count(&mut self, x: &[Vec3], triangles: &[[u32; 3]]) -> usize {
        let Self { boxes, cells, slots, ends } = self;
        let bounds = |t: usize| {
            let [a, b, c] = triangles[t].map(|p| x[p as usize]);
            (a.min(b).min(c), a.max(b).max(c))
        };
        let grid = Grid::around(triangles.len(), bounds);
        boxes.resize(triangles.len(), GridBox::default());
        cells.resize(triangles.len(), 0);
        boxes.par_iter_mut().zip(cells.par_iter_mut()).with_min_len(PARALLEL_MIN_LEN).enumerate().for_each(
            |(t, (grid_box, cell))| {
                let (min, max) = bounds(t);
                *grid_box = grid.grid_box(min, max);
                *cell = Grid::key(grid.cell(0.5 * (min + max)));
            },
        );
        // Counting sort by bucket, in index order within each.
        let buckets = (2 * triangles.len()).next_power_of_two();
        let bucket = |key: u32| (u64::from(key).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 32) as usize & (buckets - 1);
        ends.clear();
        ends.resize(buckets, 0);
        for &cell in cells.iter() {
            ends[bucket(cell)] += 1;
        }
        let mut start = 0;
        for end in ends.iter_mut() {
            (start, *end) = (start + *end, start);
        }
        slots.resize(triangles.len(), 0);
        for (t, &cell) in cells.iter().enumerate() {
            let b = &mut ends[bucket(cell)];
            slots[*b as usize] = t as u32;
            *b += 1;
        }
        let (boxes, cells, slots, ends) = (&*boxes, &*cells, &*slots, &*ends);
        let corners = |tri: [u32; 3]| tri.map(|p| x[p as usize].as_dvec3());
        (0..triangles.len())
            .into_par_iter()
            .with_min_len(PARALLEL_MIN_LEN)
            .map(|t| {
                let first = triangles[t];
                let mut count = 0;
                for neighbour in Grid::forward_neighbours(cells[t]) {
                    let b = bucket(neighbour);
                    let range = if b == 0 { 0 } else { ends[b - 1] as usize }..ends[b] as usize;
                    for &u in &slots[range] {
                        let u = u as usize;
                        if cells[u] != neighbour || (neighbour == cells[t] && u <= t) {
                            continue;
                        }
                        // Boxes that only touch are tested too: a triangle resting on
                        // another's plane touches it, which the test counts.
                        if !boxes[t].meets(&boxes[u]) {
                            continue;
                        }
                        let second = triangles[u];
                        if !first.iter().any(|v| second.contains(v))
                            && triangles_intersect(corners(first), corners(second))
                        {
                            count += 1;
                        }
                    }
                }
                count
            })
            .sum()
    }
}

/// A bounding box in a [`Grid`]'s units, [`Grid::UNITS`] across the span of all the
/// boxes along each axis, its corners truncated to whole units: boxes that overlap or
/// touch still do, and boxes less than a unit apart do too.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct GridBox {
    low: [u16; 3],
    high: [u16; 3],
}

impl GridBox {
    /// Whether the boxes overlap or touch.
    fn meets(&self, other: &GridBox) -> bool {
        let [a0, a1, a2] = self.low;
        let [b0, b1, b2] = other.high;
        let [c0, c1, c2] = other.low;
        let [d0, d1, d2] = self.high;
        (a0 <= b0) & (a1 <= b1) & (a2 <= b2) & (c0 <= d0) & (c1 <= d1) & (c2 <= d2)
    }
}

/// A uniform grid over a set of boxes, with cells a little wider than the widest box.
struct Grid {
    /// The low corner of all the boxes [m].
    origin: Vec3,
    /// The inverse of the cells' width [1/m].
    inverse_width: f32,
    /// A [`GridBox`]'s units a metre along each axis.
    units: Vec3,
}

impl Grid {
    /// Cells a grid has at most along an axis, so that a cell's three coordinates pack
    /// into a 32-bit key. A sheet of 256² particles a metre wide spans some 250 cells; a
    /// cloth of more cells than this along an axis gets cells wider than its widest box,
    /// each holding more triangles.
    const CELLS: u32 = 1 << 10;

    /// Units of a [`GridBox`] across the boxes' span along an axis: 16 bits' worth, less
    /// a margin for the rounding at the far end. On a metre-wide sheet a unit is 15 µm.
    const UNITS: f32 = 65_000.0;

    /// The grid over the `count` boxes `bounds(t)` (low and high corner).
    fn around(count: usize, bounds: impl Fn(usize) -> (Vec3, Vec3) + Sync) -> Self {
        let extent = |range: Range<usize>| {
            range.map(&bounds).fold((Vec3::INFINITY, Vec3::NEG_INFINITY, 0.0f32), |(low, high, widest), (min, max)| {
                (low.min(min), high.max(max), widest.max((max - min).max_element()))
            })
        };
        let (low, high, widest) = reduce(0..count, &extent, &|a, b| (a.0.min(b.0), a.1.max(b.1), a.2.max(b.2)));
        // Wider than the widest box by a margin that round-off cannot cross, no
        // narrower than the span allows, and of some width when every box is a point.
        let span = (high - low).max_element();
        let width = (1.001 * widest).max(span / (Self::CELLS - 2) as f32).max(f32::MIN_POSITIVE);
        let units = Vec3::splat(Self::UNITS) / (high - low).max(Vec3::splat(f32::MIN_POSITIVE));
        Self { origin: low, inverse_width: 1.0 / width, units }
    }

    /// The coordinates of the cell holding point `p`.
    fn cell(&self, p: Vec3) -> [u32; 3] {
        ((p - self.origin) * self.inverse_width).to_array().map(|c| (c as u32).min(Self::CELLS - 1))
    }

    /// The box from `min` to `max` in the grid's units.
    fn grid_box(&self, min: Vec3, max: Vec3) -> GridBox {
        // Rounding, each step of the scaling keeps the order of what it scales, and so
        // does truncation (the conversion, which saturates at 0 and 2¹⁶ − 1): a corner at
        // or beyond another is so in units too.
        let units = |p: Vec3| ((p - self.origin) * self.units).to_array().map(|u| u as u16);
        GridBox { low: units(min), high: units(max) }
    }

    /// A cell's coordinates packed into one key.
    fn key([i, j, k]: [u32; 3]) -> u32 {
        (i << 20) | (j << 10) | k
    }

    /// The keys of the cell `key` and of the (up to 13) cells around it on one side of it,
    /// the side that the cells beyond, taking this one as their neighbour, do not see: a
    /// pair of neighbouring cells is visited from one of them.
    fn forward_neighbours(key: u32) -> impl Iterator<Item = u32> {
        let mask = Self::CELLS - 1;
        let centre = [key >> 20, (key >> 10) & mask, key & mask];
        // Offset n in base 3 is (i, j, k) + (n % 3, n / 3 % 3, n / 9) − 1: n = 13 is the
        // cell itself, and n and 26 − n are opposite.
        (13..27u32).filter_map(move |n| {
            let mut cell = [0u32; 3];
            for (axis, c) in cell.iter_mut().enumerate() {
                let step = (n / 3u32.pow(axis as u32)) % 3;
                *c = (centre[axis] + step).checked_sub(1).filter(|&c| c < Self::CELLS)?;
            }
            Some(Self::key(cell))
        })
    }
}

/// Whether two triangles intersect: some edge of one crosses the other.
pub fn triangles_intersect(first: [DVec3; 3], second: [DVec3; 3]) -> bool {
    !separated(first, second) && edges_cross(first, second)
}

/// Whether some edge of one triangle passes through the other (the intersection test
/// without [`separated`]'s quick answers).
fn edges_cross(first: [DVec3; 3], second: [DVec3; 3]) -> bool {
    let edges = |t: [DVec3; 3]| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])];
    edges(first).iter().any(|&(p, q)| segment_crosses_triangle(p, q, second))
        || edges(second).iter().any(|&(p, q)| segment_crosses_triangle(p, q, first))
}

/// Whether a plane strictly separates the triangles, tried along the two normals and the
/// six directions in a triangle's plane across one of its edges: a triangle wholly on one
/// side of the other's plane, or beyond one of the other's edges within its plane. Two
/// triangles of a sheet that share no vertex lie nearly in one plane, so only the second
/// kind separates them, for less than the six edge–triangle tests it spares (the count
/// on a 128² sheet took 5.5 ms instead of 8.0 on two threads).
fn separated(first: [DVec3; 3], second: [DVec3; 3]) -> bool {
    let beyond = |t: [DVec3; 3], [a, b, c]: [DVec3; 3]| {
        let normal = (b - a).cross(c - a);
        let side = t.map(|p| normal.dot(p - a));
        if side.iter().all(|&d| d > 0.0) || side.iter().all(|&d| d < 0.0) {
            return true;
        }
        // Across edge (p, q), the triangle lies on the side of its third corner r.
        [(a, b, c), (b, c, a), (c, a, b)].iter().any(|&(p, q, r)| {
            let across = normal.cross(q - p);
            let inside = across.dot(r - p);
            t.iter().all(|&u| across.dot(u - p) * inside < 0.0)
        })
    };
    beyond(second, first) || beyond(first, second)
}

/// Whether the segment `p → q` passes through the triangle (Möller–Trumbore), ends
/// included.
pub fn segment_crosses_triangle(p: DVec3, q: DVec3, [a, b, c]: [DVec3; 3]) -> bool {
    let direction = q - p;
    let (e1, e2) = (b - a, c - a);
    let h = direction.cross(e2);
    let det = e1.dot(h);
    if det.abs() < 1e-18 {
        return false;
    }
    let s = p - a;
    let u = s.dot(h) / det;
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let r = s.cross(e1);
    let v = direction.dot(r) / det;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let t = e2.dot(r) / det;
    (0.0..=1.0).contains(&t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_triangles_count_once_and_neighbours_never() {
        // Two triangles piercing each other, and a third sharing a vertex with the first.
        let x = [
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.5),
            Vec3::new(-1.0, 1.0, 1.0),
        ];
        assert_eq!(count_self_intersections(&x, &[[0, 1, 2], [3, 4, 5]]), 1);
        assert_eq!(count_self_intersections(&x, &[[0, 1, 2], [2, 4, 6]]), 0, "adjacent triangles are not counted");
        // Lifted above the plane, the second one misses.
        let lifted: Vec<Vec3> =
            x.iter().enumerate().map(|(i, p)| if i >= 3 { *p + Vec3::Y * 1.5 } else { *p }).collect();
        assert_eq!(count_self_intersections(&lifted, &[[0, 1, 2], [3, 4, 5]]), 0);
    }

    /// The separating planes never part triangles whose edges cross: over pairs of a
    /// jittered sheet's triangles, near each other and nearly in one plane, and over
    /// pairs scattered in a box.
    #[test]
    fn separated_triangles_never_have_crossing_edges() {
        // Knuth's multiplicative hash: fixed, irregular numbers in [0, 1).
        let scatter = |k: u32| f64::from(k.wrapping_mul(2_654_435_761) >> 8) / f64::from(1u32 << 24);
        let (mut parted, mut crossing) = (0, 0);
        for pair in 0..20_000u32 {
            let flat = pair % 2 == 0;
            let corner = |k: u32| {
                let jitter = DVec3::new(
                    scatter(12 * pair + 3 * k),
                    scatter(12 * pair + 3 * k + 1),
                    scatter(12 * pair + 3 * k + 2),
                );
                if flat { DVec3::new(2.0 * jitter.x, 2.0 * jitter.y, 1e-3 * jitter.z) } else { jitter }
            };
            let (first, second) = ([corner(0), corner(1), corner(2)], [corner(3), corner(4), corner(5)]);
            let crosses = edges_cross(first, second);
            assert!(!(separated(first, second) && crosses), "pair {pair}: {first:?} {second:?}");
            parted += usize::from(separated(first, second));
            crossing += usize::from(crosses);
        }
        assert!(parted > 5_000 && crossing > 1_000, "{parted} pairs parted, {crossing} crossing");
    }

    /// Boxes in the grid's units meet wherever the boxes touch, whatever the scaling
    /// rounds, and not where a few units part them: boxes of up to a centimetre scattered
    /// over two metres, each with a neighbour whose low corner is its high corner along one
    /// axis, and another three units beyond.
    #[test]
    fn grid_boxes_meet_where_boxes_touch_and_not_beyond() {
        // Knuth's multiplicative hash: fixed, irregular numbers in [0, 1).
        let scatter = |k: u32| (k.wrapping_mul(2_654_435_761) >> 8) as f32 / (1u32 << 24) as f32;
        let point = |k: u32| Vec3::new(scatter(3 * k), scatter(3 * k + 1), scatter(3 * k + 2));
        let boxes: Vec<(Vec3, Vec3)> = (0..1000).map(|k| (2.0 * point(2 * k) - 0.3, 0.01 * point(2 * k + 1))).collect();
        // Over the neighbours too, as a count's grid is over every box it holds.
        let grid = Grid::around(boxes.len(), |k| (boxes[k].0, boxes[k].0 + 0.05));
        let unit = grid.units.recip();
        let (mut met, mut parted) = (0, 0);
        for (k, &(min, size)) in boxes.iter().enumerate() {
            let max = min + size;
            let axis = k % 3;
            let along = Vec3::AXES[axis];
            // The neighbour starts where this box ends along the axis, and shares its span
            // across it.
            let touching = (min + along * (max - min), max + along * size);
            let apart = (touching.0 + 3.0 * along * unit, touching.1 + 3.0 * along * unit);
            let this = grid.grid_box(min, max);
            met += usize::from(this.meets(&grid.grid_box(touching.0, touching.1)));
            parted += usize::from(!this.meets(&grid.grid_box(apart.0, apart.1)));
        }
        assert_eq!((met, parted), (boxes.len(), boxes.len()));
    }

    /// The grid finds every crossing pair that testing all pairs finds: in a sheet whose
    /// particles are scattered in a box (its triangles cross each other in many places,
    /// in a grid of few cells), and in a sheet lying flat with its particles jittered
    /// across its plane (crossings between neighbours, in a grid of many cells), with the
    /// buffer reused from count to count.
    #[test]
    fn the_grid_counts_what_testing_every_pair_counts() {
        let n = 24u32;
        let triangles: Vec<[u32; 3]> = (0..n - 1)
            .flat_map(|i| (0..n - 1).map(move |j| (i * n + j, i * n + j + 1, (i + 1) * n + j)))
            .flat_map(|(a, b, c)| [[a, b, c], [b, c + 1, c]])
            .collect();
        let brute = |x: &[Vec3]| {
            let corners = |t: [u32; 3]| t.map(|p| x[p as usize].as_dvec3());
            let mut count = 0;
            for (k, &t) in triangles.iter().enumerate() {
                for &u in &triangles[k + 1..] {
                    count +=
                        usize::from(!t.iter().any(|v| u.contains(v)) && triangles_intersect(corners(t), corners(u)));
                }
            }
            count
        };
        let mut counter = IntersectionCounter::default();
        for seed in [1u32, 2, 3] {
            // Knuth's multiplicative hash: fixed, irregular numbers in [0, 1).
            let scatter =
                |p: u32, axis: u32| ((p * 3 + axis + 1000 * seed).wrapping_mul(2_654_435_761) >> 24) as f32 / 256.0;
            let jitter = |p: u32| Vec3::new(scatter(p, 0), scatter(p, 1), scatter(p, 2));
            let x: Vec<Vec3> = (0..n * n)
                .map(|p| match seed {
                    3 => Vec3::new((p % n) as f32, (p / n) as f32, 0.0) + 3.0 * (jitter(p) - 0.5),
                    _ => 4.0 * jitter(p),
                })
                .collect();
            let expected = brute(&x);
            assert!(expected > 10, "seed {seed}: the sheet crosses itself ({expected} pairs)");
            assert_eq!(counter.count(&x, &triangles), expected, "seed {seed}");
        }
    }
}
