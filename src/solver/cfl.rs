//! Zheng's adaptive explicit step (Z4, §3.1): `Δt = α Δx √(ρ / E)`, with Δx the shortest
//! current edge, ρ the areal density and E the largest in-plane stiffness: the time a
//! stretch wave takes to cross the smallest element, times a safety factor α < 1.

use glam::Vec3;

use crate::components::{MembraneTriangles, Springs};

/// The largest stable explicit step of a cloth [s] for Courant number `alpha`, or `None`
/// when nothing resists stretching. Recomputed from the current positions `x`, so it
/// shrinks as elements are compressed.
pub fn cfl_step(alpha: f32, x: &[Vec3], density: f32, springs: &Springs, membranes: &MembraneTriangles) -> Option<f32> {
    let spring_stiffness = springs.stiffness.iter().copied().fold(0.0f32, f32::max);
    let material = &membranes.material;
    let membrane_stiffness = if membranes.indices.is_empty() { 0.0 } else { material.d1.max(material.d2) };
    let stiffness = spring_stiffness.max(membrane_stiffness);
    if stiffness <= 0.0 {
        return None;
    }
    let length = |i: u32, j: u32| (x[i as usize] - x[j as usize]).length();
    let spring_lengths = springs.pairs.iter().map(|&[i, j]| length(i, j));
    let side_lengths = membranes.indices.iter().flat_map(|&[a, b, c]| [length(a, b), length(b, c), length(c, a)]);
    let shortest = spring_lengths.chain(side_lengths).fold(f32::INFINITY, f32::min);
    shortest.is_finite().then(|| alpha * shortest * (density / stiffness).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::components::SpringKind;

    #[test]
    fn zhengs_sphere_drape_numbers_give_his_step() {
        // Digest §2.6 check: d1 = 38.8 N/m, ρ = 0.144 kg/m², 6.25 mm spacing → 3.8e-4 α s.
        let mut springs = Springs::default();
        springs.push([0, 1], 0.00625, 38.8, 0.0, SpringKind::Structural);
        let x = [Vec3::ZERO, Vec3::new(0.00625, 0.0, 0.0)];
        let step = cfl_step(1.0, &x, 0.144, &springs, &MembraneTriangles::default()).expect("a stiffness");
        assert!((step - 3.8e-4).abs() < 0.05e-4, "step {step}");
    }
}
