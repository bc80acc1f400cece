//! Counting intersecting triangle pairs of a cloth: an exact test, independent of the
//! contact code, that measures whether the cloth has passed through itself.

use glam::{DVec3, Vec3};

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
    /// Number of pairs of triangles of `x` that share no vertex and intersect.
    pub fn count(&mut self, x: &[Vec3], triangles: &[[u32; 3]]) -> usize {
        let boxes = &mut self.boxes;
        boxes.clear();
        boxes.extend(triangles.iter().enumerate().map(|(t, tri)| {
            let [a, b, c] = tri.map(|p| x[p as usize]);
            (a.min(b).min(c), a.max(b).max(c), t)
        }));
        // Unstable sort: the index breaks ties, and a stable sort would allocate.
        boxes.sort_unstable_by(|p, q| p.0.x.total_cmp(&q.0.x).then(p.2.cmp(&q.2)));
        let mut count = 0;
        for (k, &(min, max, t)) in boxes.iter().enumerate() {
            for &(other_min, other_max, u) in boxes[k + 1..].iter().take_while(|b| b.0.x <= max.x) {
                if other_min.cmpgt(max).any() || min.cmpgt(other_max).any() {
                    continue;
                }
                let (first, second) = (triangles[t], triangles[u]);
                if first.iter().any(|v| second.contains(v)) {
                    continue;
                }
                let corners = |tri: [u32; 3]| tri.map(|p| x[p as usize].as_dvec3());
                if triangles_intersect(corners(first), corners(second)) {
                    count += 1;
                }
            }
        }
        count
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
}
