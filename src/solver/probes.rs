//! Measurements of a cloth's state, reported per frame.

use glam::Vec3;

use crate::components::Springs;

/// Kinetic energy `Σ ½ m |v|²` [J].
pub fn kinetic_energy(v: &[Vec3], inv_mass: &[f32]) -> f64 {
    v.iter()
        .zip(inv_mass)
        .map(|(v, w)| 0.5 * f64::from(v.length_squared() / w))
        .sum()
}

/// Strain of each spring: its length over its rest length, minus one [-].
pub fn spring_strains<'a>(x: &'a [Vec3], springs: &'a Springs) -> impl Iterator<Item = f32> + 'a {
    springs
        .pairs
        .iter()
        .zip(&springs.rest_length)
        .map(|(&[i, j], &rest)| (x[i as usize] - x[j as usize]).length() / rest - 1.0)
}

/// Largest spring strain [-], or 0 without springs.
pub fn max_strain(x: &[Vec3], springs: &Springs) -> f32 {
    spring_strains(x, springs).reduce(f32::max).unwrap_or(0.0)
}
