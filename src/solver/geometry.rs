//! Geometry of triangle meshes: areas, lumped masses, normals.

use glam::Vec3;

/// Area of a triangle [m²].
#[inline]
pub fn triangle_area(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    0.5 * (b - a).cross(c - a).length()
}

/// Lumped particle masses [kg] of a surface of areal density `density` [kg/m²]: each
/// triangle gives a third of its mass to each of its corners.
pub fn lumped_masses(positions: &[Vec3], triangles: &[[u32; 3]], density: f32) -> Vec<f32> {
    let mut masses = vec![0.0f32; positions.len()];
    for tri in triangles {
        let [a, b, c] = tri.map(|p| positions[p as usize]);
        let third = density * triangle_area(a, b, c) / 3.0;
        for &p in tri {
            masses[p as usize] += third;
        }
    }
    masses
}

/// Area-weighted unit vertex normals written to `normals`; a vertex on no triangle (or
/// only on degenerate ones) gets +Y.
pub fn vertex_normals(positions: &[Vec3], triangles: &[[u32; 3]], normals: &mut Vec<Vec3>) {
    normals.clear();
    normals.resize(positions.len(), Vec3::ZERO);
    for tri in triangles {
        let [a, b, c] = tri.map(|p| positions[p as usize]);
        // The cross product's length is twice the area: the weighting comes for free.
        let n = (b - a).cross(c - a);
        for &p in tri {
            normals[p as usize] += n;
        }
    }
    for n in normals.iter_mut() {
        *n = n.try_normalize().unwrap_or(Vec3::Y);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lumped_masses_add_up_to_density_times_area() {
        let positions = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let masses = lumped_masses(&positions, &[[0, 1, 2], [0, 2, 3]], 0.3);
        let total: f32 = masses.iter().sum();
        assert!((total - 0.3).abs() < 1e-6);
        assert!((masses[0] - 0.1).abs() < 1e-6, "vertex 0 is on both triangles");
    }

    #[test]
    fn normals_of_a_flat_counter_clockwise_square_point_up_z() {
        let positions = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let mut normals = Vec::new();
        vertex_normals(&positions, &[[0, 1, 2], [0, 2, 3]], &mut normals);
        assert!(normals.iter().all(|n| (*n - Vec3::Z).length() < 1e-6));
    }
}
