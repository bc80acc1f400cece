//! Numerical health: the check that stops a diverging run before it writes garbage.

use glam::Vec3;

use super::probes::most_stretched_edge;
use crate::components::{MembraneTriangles, Springs};

/// What went wrong in a cloth's state.
#[derive(Debug, Clone, PartialEq)]
pub enum Unhealthy {
    /// A position or velocity is NaN or infinite.
    NonFinite {
        /// The first particle found with a non-finite value.
        particle: u32,
        /// Which quantity: `"position"` or `"velocity"`.
        quantity: &'static str,
    },
    /// An edge (a spring or a membrane triangle's side) stretched beyond the scene's
    /// divergence limit.
    Overstretched {
        /// The edge's two particles.
        particles: [u32; 2],
        /// Its strain (elongation ratio minus one).
        strain: f32,
    },
}

impl std::fmt::Display for Unhealthy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unhealthy::NonFinite { particle, quantity } => {
                write!(f, "particle {particle} has a non-finite {quantity}")
            }
            Unhealthy::Overstretched { particles, strain } => write!(
                f,
                "the edge between particles {} and {} is stretched to strain {strain:.3}, beyond the divergence limit",
                particles[0], particles[1]
            ),
        }
    }
}

/// Checks positions and velocities for non-finite values, then every edge's strain
/// against `max_strain`. Reports the first problem found: the first bad particle, or the
/// most stretched edge; else returns the largest edge strain (0 without edges), which the
/// `max_strain` probe reports, so that the frame measures it once.
pub fn check_health(
    x: &[Vec3],
    v: &[Vec3],
    rest: &[Vec3],
    springs: &Springs,
    membranes: &MembraneTriangles,
    max_strain: f32,
) -> Result<f32, Unhealthy> {
    for (quantity, values) in [("position", x), ("velocity", v)] {
        if let Some(particle) = values.iter().position(|p| !p.is_finite()) {
            return Err(Unhealthy::NonFinite { particle: particle as u32, quantity });
        }
    }
    match most_stretched_edge(x, rest, springs, membranes) {
        Some((particles, strain)) if strain > max_strain => Err(Unhealthy::Overstretched { particles, strain }),
        worst => Ok(worst.map_or(0.0, |(_, strain)| strain)),
    }
}
