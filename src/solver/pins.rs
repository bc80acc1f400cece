//! Holding pinned particles.

use glam::Vec3;

/// Puts each pinned particle on its target at rest.
pub fn hold_pins(particles: &[u32], targets: &[Vec3], x: &mut [Vec3], v: &mut [Vec3]) {
    for (&p, &target) in particles.iter().zip(targets) {
        x[p as usize] = target;
        v[p as usize] = Vec3::ZERO;
    }
}

/// Total force the pins carry [N]: the reaction that keeps the pinned particles at rest
/// against the other forces on them, `−Σ f_i` over the `forces` on pinned `i`. At
/// equilibrium its magnitude is the weight of everything that hangs from the pins.
pub fn pin_reaction(forces: impl Iterator<Item = Vec3>) -> Vec3 {
    -forces.sum::<Vec3>()
}
