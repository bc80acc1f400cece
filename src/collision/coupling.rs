//! How a free rigid body (a prop) takes the cloth's push, stably.
//!
//! The cloth and the rigid world are stepped one after the other: the cloth sees the body
//! moving as the rigid step left it, and the body then gets the opposite of the cloth's
//! impulse. Passed on as it is, that impulse makes the coupling explicit in the cloth's
//! stiffness: the implicit solve holds the particles resting on a body to the body's
//! normal velocity, so a body velocity error δ comes back as an impulse `S δ`, with `S`
//! the cloth's apparent inertia over the step, `M + h²K`-sized. A light box on a stiff
//! hammock has `S` many times its own mass and inertia, and the error grows by `1 − S/M`
//! a step: the box is thrown out within a few frames.
//!
//! So the body's velocity change `δ` is taken implicitly in that response, the added-mass
//! scheme of partitioned fluid–structure coupling: `(M + D) δ = −(J − E + D a)`, where `J`
//! is the impulse measured, `D ≥ S` an apparent inertia of the particles touching the
//! body, and `a` the velocity change the rigid world's own step gave the body, which the
//! cloth sees next. `E` is last step's `D (δ + a)`: the push back the body was given ahead
//! of the cloth, which the cloth's measured push now contains and must not give twice. So
//! over the steps the body gets exactly the opposite of what the cloth got (momentum is
//! conserved but for the last step's advance), and a velocity error `e` evolves as a heavy
//! ball, `e⁺ = e + β (e − e⁻) − S e/(M + D)` with `β = D/(M + D)`, which is stable for
//! every `0 ≤ S ≤ M + D`.
//!
//! `D` is the implicit system matrix `A = M − hD − h²K` restricted to the touching
//! particles moving rigidly with the body, along their contact normals (the directions the
//! solve holds them in), plus their own mass across (where only the contact's friction, a
//! change of velocity alone, acts). Moving the whole touching patch rigidly strains only
//! the cloth around it, and the rest of the cloth gives way, so this bounds `S`.

use glam::{Mat3, Vec3};

use super::body_contact::Touch;
use crate::solver::elements::block::{BlockMatrix, BlockPattern};
use crate::solver::elements::spring::outer;

/// A body's 6 × 6 apparent inertia, about the point it was taken about, in 3 × 3 blocks:
/// the impulse and moment `(J, L)` that the velocity change `(δv, δω)` costs is
/// `J = T δv + C δω`, `L = Cᵀ δv + R δω`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ApparentInertia {
    /// Impulse per velocity [kg].
    pub translation: Mat3,
    /// Impulse per angular velocity [kg·m].
    pub coupling: Mat3,
    /// Moment per angular velocity [kg·m²].
    pub rotation: Mat3,
}

impl Default for ApparentInertia {
    fn default() -> Self {
        Self { translation: Mat3::ZERO, coupling: Mat3::ZERO, rotation: Mat3::ZERO }
    }
}

impl ApparentInertia {
    /// Adds `Gᵢᵀ A Gⱼ` for the block `A` between particles `i` and `j`, each moving with
    /// the body as `Gₖ = (1, −skewₖ)`, `skewₖ = [xₖ − c]×`.
    fn add_block(&mut self, block: Mat3, skew_i: Mat3, skew_j: Mat3) {
        self.translation += block;
        self.coupling -= block * skew_j;
        self.rotation -= skew_i * block * skew_j;
    }
}

/// The cloth's implicit system over the last step, where the step had one.
#[derive(Clone, Copy)]
pub struct StepSystem<'a> {
    /// Which blocks exist.
    pub pattern: &'a BlockPattern,
    /// `A = (1 + hα) M − h ∂f/∂v − (hβ + h²θ²) ∂f/∂x`.
    pub matrix: &'a BlockMatrix,
}

/// Adds to `inertia[b]` the apparent inertia of the particles `touching` body `b` about
/// `centres[b]`, for the bodies with a centre (the free ones). `x` are the particles'
/// positions, `inv_mass` their inverse masses; without a `system` (an explicit step) a
/// particle's apparent inertia is its mass.
pub fn add_apparent_inertia(
    touching: &[Touch],
    system: Option<StepSystem<'_>>,
    inv_mass: &[f32],
    x: &[Vec3],
    centres: &[Option<Vec3>],
    inertia: &mut [ApparentInertia],
) {
    // A particle at x moves with the body as δv − [x − c]× δω.
    let skew = |i: usize, centre: Vec3| {
        let r = x[i] - centre;
        Mat3::from_cols(r.cross(Vec3::X), r.cross(Vec3::Y), r.cross(Vec3::Z))
    };
    for touch in touching {
        let body = touch.body as usize;
        let Some(centre) = centres.get(body).copied().flatten() else {
            continue;
        };
        let i = touch.particle as usize;
        let share = &mut inertia[body];
        let skew_i = skew(i, centre);
        let mass = 1.0 / inv_mass[i];
        let Some(system) = system else {
            share.add_block(mass * Mat3::IDENTITY, skew_i, skew_i);
            continue;
        };
        // Across the normal, friction: the particle's mass.
        let normal = outer(touch.normal, touch.normal);
        share.add_block(mass * (Mat3::IDENTITY - normal), skew_i, skew_i);
        // Along the normals, the system's blocks between particles on this body.
        for slot in system.pattern.slots(i) {
            let j = system.pattern.columns[slot];
            let Ok(k) = touching.binary_search_by_key(&j, |t| t.particle) else {
                continue;
            };
            if touching[k].body == touch.body {
                let along = touch.normal.dot(system.matrix.blocks[slot] * touching[k].normal);
                let block = along * outer(touch.normal, touching[k].normal);
                share.add_block(block, skew_i, skew(j as usize, centre));
            }
        }
    }
}

/// What a free body's coupling carries from step to step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BodyCoupling {
    /// What the rigid world's last step did to the body's velocity and angular velocity
    /// [m/s, rad/s]: a change the cloth will see, whose push back is anticipated.
    pub rigid_change: (Vec3, Vec3),
    /// The impulse and moment [N·s, N·m·s] the body was given ahead of the cloth: the
    /// anticipated push back, `D (δ + a)`, taken out of the next step's measured push so
    /// that, over the steps, the body gets exactly what the cloth got.
    pub advance: (Vec3, Vec3),
}

impl BodyCoupling {
    /// The velocity change `(δv, δω)` a free body takes from the cloth's push over a step:
    /// the cloth gave it `−impulse` and `−moment` about its centre of mass, it has inverse
    /// mass `inv_mass` (per axis, zero where locked) and inverse inertia `inv_inertia` about
    /// that centre, and `inertia` is the cloth's apparent inertia on it about the same
    /// centre. Solves `(M + D) δ = −(J − E + D a)` with `E` the advance given last step,
    /// and keeps the new advance `D (δ + a)` (see the module's comment).
    pub fn velocity_change(
        &mut self,
        impulse: Vec3,
        moment: Vec3,
        inv_mass: Vec3,
        inv_inertia: Mat3,
        inertia: &ApparentInertia,
    ) -> (Vec3, Vec3) {
        let ApparentInertia { translation: t, coupling: c, rotation: r } = *inertia;
        let apply = |(v, w): (Vec3, Vec3)| (t * v + c * w, c.transpose() * v + r * w);
        let (a_v, a_w) = self.rigid_change;
        let (anticipated, anticipated_moment) = apply(self.rigid_change);
        let inv_m = Mat3::from_diagonal(inv_mass);
        // Rows scaled by M⁻¹ and I⁻¹, so that locked axes (zero inverse) simply stay still:
        // [1 + M⁻¹T, M⁻¹C; I⁻¹Cᵀ, 1 + I⁻¹R] δ = −[M⁻¹(J − E + T a_v + C a_w); I⁻¹(…)].
        let top_left = Mat3::IDENTITY + inv_m * t;
        let top_right = inv_m * c;
        let bottom_left = inv_inertia * c.transpose();
        let bottom_right = Mat3::IDENTITY + inv_inertia * r;
        let f = -(inv_m * (impulse - self.advance.0 + anticipated));
        let g = -(inv_inertia * (moment - self.advance.1 + anticipated_moment));
        let top_inverse = top_left.inverse();
        let schur = bottom_right - bottom_left * top_inverse * top_right;
        let dw = schur.inverse() * (g - bottom_left * top_inverse * f);
        let dv = top_inverse * (f - top_right * dw);
        self.advance = apply((dv + a_v, dw + a_w));
        (dv, dw)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_touches() -> [Touch; 2] {
        [
            Touch { particle: 0, normal: Vec3::Y, surface_velocity: Vec3::ZERO, body: 0, gap: 0.0, sticking: false },
            Touch { particle: 1, normal: Vec3::Y, surface_velocity: Vec3::ZERO, body: 0, gap: 0.0, sticking: false },
        ]
    }

    #[test]
    fn without_cloth_the_change_is_the_impulse_over_the_mass() {
        let mut coupling = BodyCoupling { rigid_change: (Vec3::Y, Vec3::X), advance: (Vec3::ZERO, Vec3::ZERO) };
        let (dv, dw) = coupling.velocity_change(
            Vec3::new(0.0, -1.0, 0.5),
            Vec3::new(0.1, 0.0, 0.0),
            Vec3::splat(0.5),
            Mat3::from_diagonal(Vec3::new(2.0, 4.0, 8.0)),
            &ApparentInertia::default(),
        );
        assert!((dv - Vec3::new(0.0, 0.5, -0.25)).length() < 1e-6, "{dv}");
        assert!((dw - Vec3::new(-0.2, 0.0, 0.0)).length() < 1e-6, "{dw}");
    }

    #[test]
    fn a_resting_body_carries_exactly_the_measured_impulse() {
        // At rest the rigid step adds g h and the coupling takes it back, δ = −a, and then
        // M δ = −J whatever the apparent inertia: the anticipated push is zero.
        let mass = 0.15;
        let a = Vec3::new(0.0, -9.81 / 240.0, 0.0);
        let mut inertia = [ApparentInertia::default()];
        add_apparent_inertia(
            &two_touches(),
            None,
            &[100.0, 50.0],
            &[Vec3::new(0.1, 0.0, 0.0), Vec3::new(-0.1, 0.0, 0.05)],
            &[Some(Vec3::new(0.0, 0.1, 0.0))],
            &mut inertia,
        );
        let mut coupling = BodyCoupling { rigid_change: (a, Vec3::ZERO), advance: (Vec3::ZERO, Vec3::ZERO) };
        let (dv, dw) = coupling.velocity_change(
            mass * a,
            Vec3::ZERO,
            Vec3::splat(1.0 / mass),
            Mat3::IDENTITY * 100.0,
            &inertia[0],
        );
        assert!((dv + a).length() < 1e-6 && dw.length() < 1e-5, "{dv} {dw}");
        assert!(coupling.advance.0.length() < 1e-7 && coupling.advance.1.length() < 1e-7);
    }

    #[test]
    fn what_is_given_ahead_is_taken_from_the_next_push() {
        // A 1 kg body with 3 kg of apparent inertia gets a 4 N·s push, then nothing: it
        // moves at 1 m/s after the first step (1 N·s given, 3 N·s ahead of the cloth),
        // and the second step's push, 3 N·s less than the advance, gives it the rest.
        let inertia = ApparentInertia { translation: 3.0 * Mat3::IDENTITY, ..ApparentInertia::default() };
        let mut coupling = BodyCoupling::default();
        let (first, _) = coupling.velocity_change(-4.0 * Vec3::X, Vec3::ZERO, Vec3::ONE, Mat3::IDENTITY, &inertia);
        assert!((first - Vec3::X).length() < 1e-6, "{first}");
        assert!((coupling.advance.0 - 3.0 * Vec3::X).length() < 1e-6);
        let (second, _) = coupling.velocity_change(Vec3::ZERO, Vec3::ZERO, Vec3::ONE, Mat3::IDENTITY, &inertia);
        // (1 + 3) δ = 3: δ = 0.75, the body now at 1.75 m/s, 2.25 N·s still ahead.
        assert!((second - 0.75 * Vec3::X).length() < 1e-6, "{second}");
    }

    #[test]
    fn mass_alone_gives_the_rigid_inertia_of_the_touching_particles() {
        // Two 10 g particles at ±0.1 m along x about the centre: 0.02 kg, and about y and z
        // an inertia 2 × 0.01 × 0.1² = 2e-4 kg·m².
        let mut inertia = [ApparentInertia::default(), ApparentInertia::default()];
        add_apparent_inertia(
            &two_touches(),
            None,
            &[100.0, 100.0],
            &[Vec3::new(1.1, 0.0, 0.0), Vec3::new(0.9, 0.0, 0.0)],
            &[Some(Vec3::new(1.0, 0.0, 0.0)), None],
            &mut inertia,
        );
        let share = inertia[0];
        assert!((share.translation - 0.02 * Mat3::IDENTITY).abs_diff_eq(Mat3::ZERO, 1e-7));
        assert!(share.coupling.abs_diff_eq(Mat3::ZERO, 1e-7), "symmetric about the centre");
        let expected = Mat3::from_diagonal(Vec3::new(0.0, 2e-4, 2e-4));
        assert!(share.rotation.abs_diff_eq(expected, 1e-8), "{}", share.rotation);
        assert_eq!(inertia[1], ApparentInertia::default(), "bodies without a centre get nothing");
    }
}
