//! Counting intersecting triangle pairs of a cloth: an exact test, independent of the
//! contact code, that measures whether the cloth has passed through itself.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::solver::PARALLEL_MIN_LEN;

/// Number of pairs of triangles that share no vertex and intersect: an edge of one
/// crosses the interior of the other. Candidate pairs come from a sweep over the
/// triangles' bounding boxes along X; the crossing test runs in double precision.
pub fn count_self_intersections(x: &[Vec3], triangles: &[[u32; 3]]) -> usize {
    IntersectionCounter::default().count(x, triangles)
}

/// [`count_self_intersections`] with its buffer kept between counts, for a probe that
/// counts every frame.
#[derive(Debug, Clone, Default)]
pub struct IntersectionCounter {
    /// Each triangle's bounding box and index.
    boxes: Vec<(Vec3, Vec3, usize)>,
}

impl IntersectionCounter {
    /// Number of pairs of triangles of `x` that share no vertex and intersect. Each box
    /// sweeps the boxes after it in parallel: on a flat sheet a box meets about √n others
    /// along the axis, which serially was 4 % of a frame of the 256² hang scene. (A box
    /// tree finds fewer candidates, but cost 260 bytes a particle of hang_64.)
    pub fn count(&mut self, x: &[Vec3], triangles: &[[u32; 3]]) -> usize {
        let boxes = &mut self.boxes;
        boxes.clear();
        boxes.extend(triangles.iter().enumerate().map(|(t, tri)| {
            let [a, b, c] = tri.map(|p| x[p as usize]);
            (a.min(b).min(c), a.max(b).max(c), t)
        }));
        // Unstable sort: the index breaks ties, and a stable sort would allocate.
        boxes.par_sort_unstable_by(|p, q| p.0.x.total_cmp(&q.0.x).then(p.2.cmp(&q.2)));
        let boxes = &self.boxes;
        let corners = |tri: [u32; 3]| tri.map(|p| x[p as usize].as_dvec3());
        (0..boxes.len())
            .into_par_iter()
            .with_min_len(PARALLEL_MIN_LEN)
            .map(|k| {
                let (min, max, t) = boxes[k];
                let first = triangles[t];
                let mut count = 0;
                for &(other_min, other_max, u) in boxes[k + 1..].iter().take_while(|b| b.0.x <= max.x) {
                    if other_min.cmpgt(max).any() || min.cmpgt(other_max).any() {
                        continue;
                    }
                    let second = triangles[u];
                    if !first.iter().any(|v| second.contains(v)) && triangles_intersect(corners(first), corners(second))
                    {
                        count += 1;
                    }
                }
                count
            })
            .sum()
    }
}

/// Whether two triangles intersect: some edge of one crosses the other.
pub fn triangles_intersect(first: [DVec3; 3], second: [DVec3; 3]) -> bool {
    let edges = |t: [DVec3; 3]| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])];
    edges(first).iter().any(|&(p, q)| segment_crosses_triangle(p, q, second))
        || edges(second).iter().any(|&(p, q)| segment_crosses_triangle(p, q, first))
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

    /// The sweep finds every crossing pair that testing all pairs finds, in a sheet whose
    /// particles are scattered in a box (so its triangles cross each other in many
    /// places), with its buffer reused for a second sheet.
    #[test]
    fn the_sweep_counts_what_testing_every_pair_counts() {
        let n = 12u32;
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
        for seed in [1u32, 2] {
            // Knuth's multiplicative hash: fixed, irregular coordinates in [0, 4).
            let scatter = |p: u32, axis: u32| (p * 3 + axis + 1000 * seed).wrapping_mul(2_654_435_761) >> 24;
            let x: Vec<Vec3> = (0..n * n)
                .map(|p| Vec3::new(scatter(p, 0) as f32, scatter(p, 1) as f32, scatter(p, 2) as f32) / 64.0)
                .collect();
            let expected = brute(&x);
            assert!(expected > 10, "the crumpled sheet crosses itself ({expected} pairs)");
            assert_eq!(counter.count(&x, &triangles), expected);
        }
    }
}
