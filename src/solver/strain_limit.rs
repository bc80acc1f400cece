//! Strain limiting (Z8): after each step, edges stretched beyond a limit are shortened back
//! to it by iterated projection, each end moving in proportion to its inverse mass, and the
//! velocities take the correction over the step (`v += Δx / h`). Soft stretch stiffness can
//! then be used with large steps without the cloth stretching like rubber (Provot 1995; Zheng
//! ch. 5 uses a fast projection to the same end).

use glam::Vec3;

/// The edges a cloth limits.
#[derive(Debug, Clone, Copy)]
pub struct LimitedEdges<'a> {
    /// Particle pairs.
    pub pairs: &'a [[u32; 2]],
    /// Rest lengths [m].
    pub rest_length: &'a [f32],
    /// Largest strain allowed [-].
    pub max_strain: f32,
    /// Most projection sweeps per step.
    pub iterations: u32,
}

/// Below this excess over the limit, an edge counts as satisfied.
const SLACK: f32 = 1e-4;

/// Projects positions `x` so that no edge exceeds its limit (within a small slack, or
/// until the sweeps run out), then adds the displacement over `h` [s] to the velocities.
/// `free_inv_mass` is zero for pinned particles, which do not move. `start` is scratch
/// space. Returns the sweeps used.
pub fn limit_strain(
    edges: &LimitedEdges<'_>,
    free_inv_mass: &[f32],
    h: f32,
    x: &mut [Vec3],
    v: &mut [Vec3],
    start: &mut Vec<Vec3>,
) -> u32 {
    start.clear();
    start.extend_from_slice(x);
    let mut sweeps = 0;
    while sweeps < edges.iterations {
        sweeps += 1;
        let mut satisfied = true;
        for (&[i, j], &rest) in edges.pairs.iter().zip(edges.rest_length) {
            let (i, j) = (i as usize, j as usize);
            let (wi, wj) = (free_inv_mass[i], free_inv_mass[j]);
            if wi + wj == 0.0 {
                continue;
            }
            let d = x[j] - x[i];
            let length = d.length();
            let longest = (1.0 + edges.max_strain) * rest;
            if length <= longest * (1.0 + SLACK) {
                continue;
            }
            satisfied = false;
            let correction = (length - longest) / (length * (wi + wj)) * d;
            x[i] += wi * correction;
            x[j] -= wj * correction;
        }
        if satisfied {
            break;
        }
    }
    for ((v, x), start) in v.iter_mut().zip(x.iter()).zip(start.iter()) {
        *v += (*x - *start) / h;
    }
    sweeps
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_overstretched_chain_is_pulled_back_to_the_limit_towards_its_pin() {
        // Three particles in a line, the first pinned, edges stretched to 1.5.
        let mut x = vec![Vec3::ZERO, Vec3::new(1.5, 0.0, 0.0), Vec3::new(3.0, 0.0, 0.0)];
        let mut v = vec![Vec3::ZERO; 3];
        let edges =
            LimitedEdges { pairs: &[[0, 1], [1, 2]], rest_length: &[1.0, 1.0], max_strain: 0.01, iterations: 100 };
        let sweeps = limit_strain(&edges, &[0.0, 1.0, 1.0], 0.1, &mut x, &mut v, &mut Vec::new());
        assert!(sweeps < 100);
        assert_eq!(x[0], Vec3::ZERO, "the pinned end stays");
        assert!(((x[1] - x[0]).length() - 1.01).abs() < 2e-4 && ((x[2] - x[1]).length() - 1.01).abs() < 2e-4);
        assert!((v[2].x - (x[2].x - 3.0) / 0.1).abs() < 1e-4, "the velocity carries the correction");
    }
}
