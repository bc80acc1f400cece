//! Distances and continuous collision times between the primitives of triangle meshes:
//! a point against a triangle and an edge against an edge (Bridson et al. 2002; Zheng
//! §3.2–3.3). Distances in single precision; the coplanarity cubic in double.

use glam::{DVec3, Vec3};

/// Barycentric weights `[wa, wb, wc]` of the point of triangle `abc` closest to `p`
/// (Ericson, *Real-Time Collision Detection*, §5.1.5).
pub fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> [f32; 3] {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    [1.0 - v - w, v, w]
}

/// Parameters `(s, t)` of the closest points `p0 + s (p1 − p0)` and `q0 + t (q1 − q0)` of
/// two segments (Ericson §5.1.9), both clamped to [0, 1].
pub fn closest_between_segments(p0: Vec3, p1: Vec3, q0: Vec3, q1: Vec3) -> (f32, f32) {
    let (d1, d2, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, e, f) = (d1.dot(d1), d2.dot(d2), d2.dot(r));
    if a <= f32::EPSILON && e <= f32::EPSILON {
        return (0.0, 0.0);
    }
    if a <= f32::EPSILON {
        return (0.0, (f / e).clamp(0.0, 1.0));
    }
    let c = d1.dot(r);
    if e <= f32::EPSILON {
        return ((-c / a).clamp(0.0, 1.0), 0.0);
    }
    let b = d1.dot(d2);
    let denom = a * e - b * b;
    let mut s = if denom > f32::EPSILON * a * e { ((b * f - c * e) / denom).clamp(0.0, 1.0) } else { 0.0 };
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    (s, t)
}

/// Four vertices moving on straight lines over a step, from `start` to `end`.
#[derive(Debug, Clone, Copy)]
pub struct Sweep {
    /// Positions at the start of the step.
    pub start: [Vec3; 4],
    /// Positions at the end.
    pub end: [Vec3; 4],
}

impl Sweep {
    fn at(&self, t: f64) -> [DVec3; 4] {
        std::array::from_fn(|k| {
            let (a, b) = (self.start[k].as_dvec3(), self.end[k].as_dvec3());
            a + (b - a) * t
        })
    }

    /// Coefficients `[c0, c1, c2, c3]` of the cubic in `t` ∈ [0, 1] that vanishes when
    /// the four points are coplanar: `(x1 − x0) × (x2 − x0) · (x3 − x0)`.
    fn coplanarity(&self) -> [f64; 4] {
        let [s0, s1, s2, s3] = self.start.map(Vec3::as_dvec3);
        let [e0, e1, e2, e3] = self.end.map(Vec3::as_dvec3);
        let (a0, b0, c0) = (s1 - s0, s2 - s0, s3 - s0);
        let (a1, b1, c1) = ((e1 - e0) - a0, (e2 - e0) - b0, (e3 - e0) - c0);
        let triple = |a: DVec3, b: DVec3, c: DVec3| a.cross(b).dot(c);
        [
            triple(a0, b0, c0),
            triple(a1, b0, c0) + triple(a0, b1, c0) + triple(a0, b0, c1),
            triple(a1, b1, c0) + triple(a1, b0, c1) + triple(a0, b1, c1),
            triple(a1, b1, c1),
        ]
    }

    /// A lower bound of the distance between the side of points `..first` and the side of
    /// the others during the sweep: their distance at the start less the largest motion
    /// of a point of one side relative to a point of the other. (The relative position of
    /// any two points of the sides is a convex combination of the corners' relative
    /// positions, so it moves no more than they do.) Cheap; lets most pairs of a cloth
    /// moving smoothly skip the cubic.
    fn distance_bound(&self, start_distance: f32, first: usize) -> f32 {
        let motion = |k: usize| self.end[k] - self.start[k];
        let mut largest = 0.0f32;
        for i in 0..first {
            for j in first..4 {
                largest = largest.max((motion(i) - motion(j)).length());
            }
        }
        start_distance - largest
    }

    /// Earliest time in [0, 1] at which point 0 comes within `tolerance` of the triangle
    /// of points 1, 2, 3, with the triangle's barycentric weights there.
    pub fn point_triangle_hit(&self, tolerance: f32) -> Option<(f32, [f32; 3])> {
        let [p, a, b, c] = self.start;
        let w = closest_on_triangle(p, a, b, c);
        if self.distance_bound(p.distance(a * w[0] + b * w[1] + c * w[2]), 1) > tolerance {
            return None;
        }
        coplanar_times(self.coplanarity()).into_iter().flatten().find_map(|t| {
            let [p, a, b, c] = self.at(t).map(|q| q.as_vec3());
            let w = closest_on_triangle(p, a, b, c);
            let closest = a * w[0] + b * w[1] + c * w[2];
            (p.distance(closest) <= tolerance).then_some((t as f32, w))
        })
    }

    /// Earliest time in [0, 1] at which edge 0–1 comes within `tolerance` of edge 2–3,
    /// with the parameters of the closest points.
    pub fn edge_edge_hit(&self, tolerance: f32) -> Option<(f32, (f32, f32))> {
        let [p0, p1, q0, q1] = self.start;
        let (s, u) = closest_between_segments(p0, p1, q0, q1);
        if self.distance_bound(p0.lerp(p1, s).distance(q0.lerp(q1, u)), 2) > tolerance {
            return None;
        }
        coplanar_times(self.coplanarity()).into_iter().flatten().find_map(|t| {
            let [p0, p1, q0, q1] = self.at(t).map(|q| q.as_vec3());
            let (s, u) = closest_between_segments(p0, p1, q0, q1);
            (p0.lerp(p1, s).distance(q0.lerp(q1, u)) <= tolerance).then_some((t as f32, (s, u)))
        })
    }
}

/// The times in [0, 1] where the cubic `c0 + c1 t + c2 t² + c3 t³` vanishes, ascending:
/// the interval is cut at the cubic's turning points so that each piece is monotone,
/// and a root in a piece is found by bisection. A piece whose ends are within rounding of
/// zero counts as a root there (grazing contact).
fn coplanar_times(c: [f64; 4]) -> [Option<f64>; 3] {
    let f = |t: f64| ((c[3] * t + c[2]) * t + c[1]) * t + c[0];
    let scale = c.iter().fold(0.0f64, |m, k| m.max(k.abs()));
    let zero = 1e-12 * scale;
    // Turning points: roots of 3 c3 t² + 2 c2 t + c1.
    let mut cuts = [0.0, 1.0, 1.0, 1.0];
    let (qa, qb, qc) = (3.0 * c[3], 2.0 * c[2], c[1]);
    let mut count = 1;
    if qa.abs() > 1e-300 {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            let root = disc.sqrt();
            let q = -0.5 * (qb + qb.signum() * root);
            for t in [q / qa, if q != 0.0 { qc / q } else { f64::NAN }] {
                if t > 0.0 && t < 1.0 {
                    cuts[count] = t;
                    count += 1;
                }
            }
        }
    } else if qb.abs() > 1e-300 {
        let t = -qc / qb;
        if t > 0.0 && t < 1.0 {
            cuts[count] = t;
            count += 1;
        }
    }
    cuts[1..=count].sort_by(f64::total_cmp);
    cuts[count] = 1.0;
    let mut roots = [None; 3];
    let mut found = 0;
    for k in 0..count {
        let (mut lo, mut hi) = (cuts[k], cuts[k + 1]);
        let (flo, fhi) = (f(lo), f(hi));
        let root = if flo.abs() <= zero {
            Some(lo)
        } else if fhi.abs() <= zero && k + 1 == count {
            Some(hi)
        } else if (flo < 0.0) != (fhi < 0.0) && fhi.abs() > zero {
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if (f(mid) < 0.0) == (flo < 0.0) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            Some(0.5 * (lo + hi))
        } else {
            None
        };
        if let Some(t) = root
            && found < 3
            && (found == 0 || roots[found - 1] != Some(t))
        {
            roots[found] = Some(t);
            found += 1;
        }
    }
    roots
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_points_on_a_triangle_cover_its_regions() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        assert_eq!(closest_on_triangle(Vec3::new(0.25, 0.25, 1.0), a, b, c), [0.5, 0.25, 0.25]);
        assert_eq!(closest_on_triangle(Vec3::new(-1.0, -1.0, 0.0), a, b, c), [1.0, 0.0, 0.0]);
        assert_eq!(closest_on_triangle(Vec3::new(0.5, -1.0, 0.0), a, b, c), [0.5, 0.5, 0.0]);
        let w = closest_on_triangle(Vec3::new(1.0, 1.0, 0.0), a, b, c);
        assert!((w[1] - 0.5).abs() < 1e-6 && (w[2] - 0.5).abs() < 1e-6);
    }

    #[test]
    fn closest_points_between_crossing_and_parallel_segments() {
        let (s, t) = closest_between_segments(
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::X,
            Vec3::new(0.5, -1.0, 1.0),
            Vec3::new(0.5, 1.0, 1.0),
        );
        assert!((s - 0.75).abs() < 1e-6 && (t - 0.5).abs() < 1e-6);
        let (s, t) = closest_between_segments(Vec3::ZERO, Vec3::X, Vec3::new(2.0, 1.0, 0.0), Vec3::new(3.0, 1.0, 0.0));
        assert_eq!((s, t), (1.0, 0.0));
    }

    #[test]
    fn a_point_falling_through_a_triangle_hits_it_at_the_crossing_time() {
        let tri = [Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0)];
        let sweep = Sweep {
            start: [Vec3::new(0.0, 0.3, 0.0), tri[0], tri[1], tri[2]],
            end: [Vec3::new(0.0, -0.1, 0.0), tri[0], tri[1], tri[2]],
        };
        let (t, w) = sweep.point_triangle_hit(1e-6).expect("hit");
        assert!((t - 0.75).abs() < 1e-6, "t = {t}");
        assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        // The same point falling beside the triangle misses it.
        let beside = Sweep { start: [Vec3::new(3.0, 0.3, 0.0), tri[0], tri[1], tri[2]], ..sweep };
        let beside = Sweep { end: [Vec3::new(3.0, -0.1, 0.0), tri[0], tri[1], tri[2]], ..beside };
        assert!(beside.point_triangle_hit(1e-6).is_none());
    }

    #[test]
    fn a_rotating_triangle_sweeping_over_a_still_point_is_caught() {
        // The triangle turns about the x axis through the point: the cubic is not linear.
        let p = Vec3::new(0.2, 0.05, 0.1);
        let start = [p, Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 0.5, 1.0)];
        let end = [p, Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, -0.5, 1.0)];
        let (t, _) = Sweep { start, end }.point_triangle_hit(1e-5).expect("hit");
        // Plane through the x axis edge at z = −1 and (0, y(t), 1): contains p when
        // y(t) · (p.z + 1) / 2 = p.y, y(t) = 0.5 − t.
        let expected = 0.5 - p.y * 2.0 / (p.z + 1.0);
        assert!((t - expected).abs() < 1e-5, "t = {t}, expected {expected}");
    }

    #[test]
    fn crossing_edges_hit_and_parallel_edges_passing_apart_miss() {
        let start =
            [Vec3::new(-1.0, 0.2, 0.0), Vec3::new(1.0, 0.2, 0.0), Vec3::new(0.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0)];
        let end = [Vec3::new(-1.0, -0.2, 0.0), Vec3::new(1.0, -0.2, 0.0), start[2], start[3]];
        let (t, (s, u)) = Sweep { start, end }.edge_edge_hit(1e-6).expect("hit");
        assert!((t - 0.5).abs() < 1e-6 && (s - 0.5).abs() < 1e-6 && (u - 0.5).abs() < 1e-6);
        // Moved 3 m along x, the first edge passes the second's plane beside it.
        let aside = |q: [Vec3; 4]| [q[0] + 3.0 * Vec3::X, q[1] + 3.0 * Vec3::X, q[2], q[3]];
        assert!(Sweep { start: aside(start), end: aside(end) }.edge_edge_hit(1e-6).is_none());
    }
}
