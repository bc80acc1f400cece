//! Solid bodies cloth collides with, and what contact did to a cloth over a frame.

use std::sync::Arc;

use bevy_ecs::prelude::*;
use parry3d::shape::SharedShape;

use crate::collision::body_contact::{ContactBody, ContactTotals, Touch};
use crate::collision::collider::{ColliderMotion, ContactResponse};
use crate::collision::features::SharpFeatures;
use crate::collision::motion_bounds::LayerContact;
use crate::solver::contact_springs::{Across, ContactSpring};

/// A static or kinematic solid body (E5, D11, B5): a parry3d shape that moves along its
/// motion. Its own entity.
#[derive(Component, Clone)]
pub struct Collider {
    /// Name from the scene.
    pub name: String,
    /// The shape in its local frame.
    pub shape: SharedShape,
    /// Where it is over time.
    pub motion: ColliderMotion,
    /// Coulomb friction coefficient against cloth [-].
    pub friction: f32,
    /// Extra distance cloth keeps from its surface [m].
    pub thickness: f32,
    /// How cloth responds to touching it.
    pub response: ContactResponse,
    /// Its sharp edges and corners, which cloth edges and triangles meet (polyhedral
    /// shapes only).
    pub features: Option<Arc<SharpFeatures>>,
}

impl Collider {
    /// A collider of `shape`, with the sharp features found on it.
    pub fn new(
        name: String,
        shape: SharedShape,
        motion: ColliderMotion,
        friction: f32,
        thickness: f32,
        response: ContactResponse,
    ) -> Collider {
        let features = SharpFeatures::of_shape(&shape).map(Arc::new);
        Collider { name, shape, motion, friction, thickness, response, features }
    }

    /// How far from its surface [m] it meets a cloth of contact thickness
    /// `cloth_thickness`: its own thickness and the cloth's.
    pub fn contact_thickness(&self, cloth_thickness: f32) -> f32 {
        self.thickness + cloth_thickness
    }

    /// The collider as the contact kernel sees it at time `t` [s] against a cloth of
    /// contact thickness `cloth_thickness` [m]; `prop` says whether it is a free prop.
    pub fn contact_body(&self, t: f32, cloth_thickness: f32, prop: bool) -> ContactBody {
        ContactBody {
            shape: self.shape.clone(),
            state: self.motion.state_at(t),
            friction: self.friction,
            thickness: self.contact_thickness(cloth_thickness),
            response: self.response,
            prop,
        }
    }
}

impl std::fmt::Debug for Collider {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Collider")
            .field("name", &self.name)
            .field("motion", &self.motion)
            .field("friction", &self.friction)
            .field("thickness", &self.thickness)
            .field("response", &self.response)
            .finish_non_exhaustive()
    }
}

/// The particles of a cloth left touching a body by the last step: the implicit
/// solvers keep them on the surface during the next one.
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct Touching(pub Vec<Touch>);

/// The pairs of a self-colliding cloth that the last step left closer than their
/// separation, with itself and with the held side (pinned, or resting on a body) of
/// another self-colliding cloth, as the springs that hold them apart in the next implicit
/// step (the cloth's particle numbers).
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct SelfTouching {
    /// The springs.
    pub springs: Vec<ContactSpring>,
    /// The held side of each spring of a pair with another cloth.
    pub across: Vec<Across>,
}

/// Contact of one cloth with the bodies, summed over the steps of the current frame.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactStats(pub ContactTotals);

/// A cloth that collides with itself and with every other cloth that has this component
/// (E3, Z5): the pairs keep `separation` apart between mid-surfaces.
#[derive(Component, Debug, Clone, Copy, PartialEq)]
#[require(SelfTouching)]
pub struct SelfCollision {
    /// Distance kept between two layers' mid-surfaces [m]; a pair of different cloths keeps
    /// the mean of their two separations.
    pub separation: f32,
    /// Coulomb friction coefficient between layers [-]; a pair uses the mean.
    pub friction: f32,
    /// Layer number: where cloths intersect, a higher layer is untangled onto the side a
    /// lower layer's triangle normals point to.
    pub layer: u32,
}

impl SelfCollision {
    /// How the cloth's layers meet, as the solver reads it.
    pub fn layers(&self) -> LayerContact {
        LayerContact { separation: self.separation, friction: self.friction }
    }
}
