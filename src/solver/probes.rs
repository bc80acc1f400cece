//! Measurements of a cloth's state, reported per frame.

use glam::Vec3;

use crate::components::{MembraneTriangles, Springs};

/// Kinetic energy `Σ ½ m |v|²` [J].
pub fn kinetic_energy(v: &[Vec3], inv_mass: &[f32]) -> f64 {
    v.iter().zip(inv_mass).map(|(v, w)| 0.5 * f64::from(v.length_squared() / w)).sum()
}

/// Strain (length over rest length, minus one) of every edge the cloth resists stretching
/// along: each spring, then each edge of each membrane triangle, with its two particles.
/// Rest lengths of membrane edges come from the rest positions `rest`.
pub fn edge_strains<'a>(
    x: &'a [Vec3],
    rest: &'a [Vec3],
    springs: &'a Springs,
    membranes: &'a MembraneTriangles,
) -> impl Iterator<Item = ([u32; 2], f32)> + 'a {
    let strain = |[i, j]: [u32; 2], rest_length: f32| (x[i as usize] - x[j as usize]).length() / rest_length - 1.0;
    let springs = springs.pairs.iter().zip(&springs.rest_length).map(move |(&pair, &r)| (pair, strain(pair, r)));
    let membranes = membranes.indices.iter().flat_map(move |&[a, b, c]| {
        [[a, b], [b, c], [c, a]]
            .map(|pair| (pair, strain(pair, (rest[pair[0] as usize] - rest[pair[1] as usize]).length())))
    });
    springs.chain(membranes)
}

/// Largest edge strain [-] (see [`edge_strains`]), or 0 without edges.
pub fn max_strain(x: &[Vec3], rest: &[Vec3], springs: &Springs, membranes: &MembraneTriangles) -> f32 {
    edge_strains(x, rest, springs, membranes).map(|(_, strain)| strain).reduce(f32::max).unwrap_or(0.0)
}
