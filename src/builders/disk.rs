//! A disk of cloth: concentric rings of near-equilateral triangles (Bricis's disk drapes,
//! Cusick's drape tester).

use glam::Vec3;

use super::mesh::TriangleMesh;

/// A disk of `radius` [m] in the local XY plane around the origin: a centre vertex and
/// `rings` rings, ring k holding 6k vertices at radius `k · radius / rings`. Consecutive
/// rings are stitched by walking both around in angle order, so the triangles are
/// counter-clockwise seen from +Z.
pub fn disk_mesh(radius: f32, rings: u32) -> TriangleMesh {
    let mut mesh = TriangleMesh { positions: vec![Vec3::ZERO], triangles: Vec::new() };
    let mut previous: Vec<u32> = vec![0];
    for ring in 1..=rings {
        let count = 6 * ring;
        let r = radius * ring as f32 / rings as f32;
        let first = mesh.positions.len() as u32;
        let current: Vec<u32> = (0..count).map(|k| first + k).collect();
        for k in 0..count {
            let angle = std::f32::consts::TAU * k as f32 / count as f32;
            mesh.positions.push(Vec3::new(r * angle.cos(), r * angle.sin(), 0.0));
        }
        stitch(&previous, &current, &mut mesh.triangles);
        previous = current;
    }
    mesh
}

/// Triangles between an inner ring and an outer ring, both starting at angle 0.
fn stitch(inner: &[u32], outer: &[u32], triangles: &mut Vec<[u32; 3]>) {
    let (n, m) = (inner.len(), outer.len());
    if n == 1 {
        for j in 0..m {
            triangles.push([inner[0], outer[j], outer[(j + 1) % m]]);
        }
        return;
    }
    let (mut i, mut j) = (0, 0);
    while i < n || j < m {
        // Advance on whichever ring's next vertex comes first in angle.
        let next_inner = (i + 1) as f32 / n as f32;
        let next_outer = (j + 1) as f32 / m as f32;
        if j < m && (i == n || next_outer <= next_inner) {
            triangles.push([inner[i % n], outer[j], outer[(j + 1) % m]]);
            j += 1;
        } else {
            triangles.push([inner[i], outer[j % m], inner[(i + 1) % n]]);
            i += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::geometry::triangle_area;

    #[test]
    fn a_disk_covers_nearly_its_area_with_positive_triangles() {
        let mesh = disk_mesh(0.15, 10);
        assert_eq!(mesh.positions.len(), 1 + 6 * (10 * 11) / 2);
        // Euler: a disk triangulation has 2V − B − 2 triangles, B = 60 boundary vertices.
        assert_eq!(mesh.triangles.len(), 2 * mesh.positions.len() - 60 - 2);
        let mut area = 0.0;
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            assert!((b - a).cross(c - a).z > 0.0, "counter-clockwise");
            area += triangle_area(a, b, c);
        }
        // The polygon of 60 sides inscribed in the circle.
        let polygon = 0.5 * 60.0 * 0.15f32 * 0.15 * (std::f32::consts::TAU / 60.0).sin();
        assert!((area - polygon).abs() < 1e-5, "area {area}, polygon {polygon}");
    }
}
