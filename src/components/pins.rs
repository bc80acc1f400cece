//! Particles held in place.

use bevy_ecs::prelude::*;
use glam::Vec3;

use crate::collision::collider::ColliderMotion;

/// Particles held at fixed targets. A pin added holds its particle from the next step on;
/// a pin removed releases it. Kept sorted by particle so results never depend on the order
/// pins were added in.
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct Pins {
    /// Pinned particle indices, sorted and unique.
    pub particles: Vec<u32>,
    /// Where each pinned particle is held [m], parallel to `particles`.
    pub targets: Vec<Vec3>,
}

impl Pins {
    /// Pins `particle` at `target`, or moves its target if it is pinned already.
    pub fn insert(&mut self, particle: u32, target: Vec3) {
        match self.particles.binary_search(&particle) {
            Ok(slot) => self.targets[slot] = target,
            Err(slot) => {
                self.particles.insert(slot, particle);
                self.targets.insert(slot, target);
            }
        }
    }

    /// Releases `particle`; returns whether it was pinned.
    pub fn remove(&mut self, particle: u32) -> bool {
        match self.particles.binary_search(&particle) {
            Ok(slot) => {
                self.particles.remove(slot);
                self.targets.remove(slot);
                true
            }
            Err(_) => false,
        }
    }

    /// Whether `particle` is pinned.
    pub fn contains(&self, particle: u32) -> bool {
        self.particles.binary_search(&particle).is_ok()
    }

    /// Number of pins.
    pub fn len(&self) -> usize {
        self.particles.len()
    }

    /// Whether nothing is pinned.
    pub fn is_empty(&self) -> bool {
        self.particles.is_empty()
    }
}

/// Pinned particles carried rigidly along a motion: a clamp or a hand.
#[derive(Debug, Clone, PartialEq)]
pub struct Grip {
    /// The held particles (all of them also in [`Pins`]).
    pub particles: Vec<u32>,
    /// Each particle's place in the grip's frame [m].
    pub local: Vec<Vec3>,
    /// Where the grip is over time.
    pub motion: ColliderMotion,
}

/// The grips of a cloth; each step moves their particles' pin targets.
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct Grips(pub Vec<Grip>);
