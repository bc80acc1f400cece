//! Numerical health: the check that stops a diverging run before it writes garbage.

use glam::Vec3;

use super::probes::spring_strains;
use crate::components::Springs;

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
    /// A spring stretched beyond the scene's divergence limit.
    Overstretched {
        /// The most stretched spring.
        spring: u32,
        /// Its two particles.
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
            Unhealthy::Overstretched {
                spring,
                particles,
                strain,
            } => write!(
                f,
                "spring {spring} (particles {} and {}) is stretched to strain {strain:.3}, beyond the divergence limit",
                particles[0], particles[1]
            ),
        }
    }
}

/// Checks positions and velocities for non-finite values, then every spring's strain
/// against `max_strain`. Reports the first problem found, in particle then spring order.
pub fn check_health(
    x: &[Vec3],
    v: &[Vec3],
    springs: &Springs,
    max_strain: f32,
) -> Result<(), Unhealthy> {
    for (quantity, values) in [("position", x), ("velocity", v)] {
        if let Some(particle) = values.iter().position(|p| !p.is_finite()) {
            return Err(Unhealthy::NonFinite {
                particle: particle as u32,
                quantity,
            });
        }
    }
    let worst = spring_strains(x, springs).enumerate().fold(
        None,
        |worst: Option<(usize, f32)>, (s, strain)| match worst {
            Some((_, w)) if w >= strain => worst,
            _ => Some((s, strain)),
        },
    );
    match worst {
        Some((spring, strain)) if strain > max_strain => Err(Unhealthy::Overstretched {
            spring: spring as u32,
            particles: springs.pairs[spring],
            strain,
        }),
        _ => Ok(()),
    }
}
