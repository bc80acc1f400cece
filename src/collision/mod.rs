//! Contact of cloth with solid bodies: collider shapes and motions ([`collider`]) and the
//! contact response kernel ([`body_contact`]), and how free bodies take the cloth's push
//! ([`coupling`]). Pure: no ECS.

pub mod body_bounds;
pub mod body_contact;
pub mod bvh;
pub mod collider;
pub mod coupling;
pub mod features;
pub mod intersection;
pub mod motion_bounds;
pub mod primitives;
pub mod self_contact;
pub mod untangle;
