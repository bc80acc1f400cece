//! Contact with the ground plane.

use glam::Vec3;

/// A horizontal ground plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundPlane {
    /// Height of the plane [m] along +Y.
    pub height: f32,
    /// Coulomb friction coefficient [-].
    pub friction: f32,
}

/// Pushes particles below the plane back onto it, removes their velocity into the plane
/// (an inelastic contact) and applies Coulomb friction to the sliding velocity: the normal
/// impulse per unit mass `|v_n|` can remove at most `μ |v_n|` of tangential speed.
/// Returns how many particles were in contact.
pub fn resolve_ground(plane: GroundPlane, x: &mut [Vec3], v: &mut [Vec3]) -> usize {
    let mut contacts = 0;
    for (x, v) in x.iter_mut().zip(v.iter_mut()) {
        if x.y >= plane.height {
            continue;
        }
        contacts += 1;
        x.y = plane.height;
        if v.y < 0.0 {
            let normal_speed = -v.y;
            v.y = 0.0;
            let tangential = Vec3::new(v.x, 0.0, v.z);
            let speed = tangential.length();
            if speed > 0.0 {
                let kept = (speed - plane.friction * normal_speed).max(0.0) / speed;
                v.x *= kept;
                v.z *= kept;
            }
        }
    }
    contacts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_particle_below_the_ground_is_put_back_and_slowed_by_friction() {
        let plane = GroundPlane { height: 0.0, friction: 0.5 };
        let mut x = [Vec3::new(0.0, -0.01, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let mut v = [Vec3::new(2.0, -1.0, 0.0), Vec3::new(0.0, -1.0, 0.0)];
        assert_eq!(resolve_ground(plane, &mut x, &mut v), 1);
        assert_eq!(x[0].y, 0.0);
        assert!((v[0] - Vec3::new(1.5, 0.0, 0.0)).length() < 1e-6);
        assert_eq!(v[1], Vec3::new(0.0, -1.0, 0.0), "particles above the plane are untouched");
    }
}
