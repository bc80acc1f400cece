//! Cloth against solid bodies, at the end of each step. Each collider picks its response:
//! - slide (the default): every particle closer to a body than the contact thickness is put
//!   back at that distance, loses its velocity into the body (relative to the body's moving
//!   surface) and slides with Coulomb friction: the tangential velocity drops by at most μ
//!   times the normal velocity removed, and to zero if that suffices (sticking). This is
//!   Zheng's impulse response for a body of infinite mass (eq. 3.30), which gives exact
//!   Coulomb behaviour on a slope: the normal impulse per step is the weight's normal part;
//! - stick: Bricis's restrain-on-contact (B5);
//! - regimes: Durupınar's penalty and velocity corrections with two thresholds (D11).

use glam::Vec3;
use parry3d::query::Ray;
use parry3d::shape::SharedShape;
use rayon::prelude::*;

use super::collider::{ColliderState, ContactResponse, Regimes};
use crate::solver::PARALLEL_MIN_LEN;

/// A body as the contact kernel sees it at one instant.
#[derive(Clone)]
pub struct ContactBody {
    /// Its shape (shared with its collider: cloning it counts a reference, no more).
    pub shape: SharedShape,
    /// Pose and velocity.
    pub state: ColliderState,
    /// Coulomb friction coefficient [-].
    pub friction: f32,
    /// Distance kept between the cloth's mid-surface and the body [m]: the body's and the
    /// cloth's contact thicknesses together.
    pub thickness: f32,
    /// What touching it does.
    pub response: ContactResponse,
    /// Whether it is a prop, moved by the cloth's push: the implicit step's support through
    /// the strong coupling of [`super::coupling`], which it does not get here again, and
    /// the impulses given here. Cloth stays touching a prop within the [`TOUCH_SLACK`], as
    /// any body (without it a box resting on a hammock kept the cloth under one side of it
    /// at a time and rocked from side to side every step), but gets the plain response
    /// otherwise: no friction from the constraint's push, no static hold. Those were left
    /// out under the staggered coupling before it (a ball held by stuck cloth was thrown at
    /// 60 m/s) and have not been tried with the strong one.
    pub prop: bool,
}

/// Where a point stands against a body's surface ([`ContactBody::surface_near`]).
#[derive(Debug, Clone, Copy)]
pub struct SurfacePoint {
    /// The nearest point of the surface.
    pub point: Vec3,
    /// The point's signed distance from it, negative inside [m].
    pub signed: f32,
    /// The body's outward normal there; none for a point exactly on the surface, which has
    /// no side.
    pub outward: Option<Vec3>,
}

impl ContactBody {
    /// Where `p` stands against the body's surface, as the body stands now.
    pub fn surface_near(&self, p: Vec3) -> SurfacePoint {
        let projection = self.shape.project_point(&self.state.pose, p, false);
        let offset = p - projection.point;
        let distance = offset.length();
        let inside = projection.is_inside;
        SurfacePoint {
            point: projection.point,
            signed: if inside { -distance } else { distance },
            outward: offset.try_normalize().map(|n| if inside { -n } else { n }),
        }
    }
}

/// What the contacts of one step did to one cloth.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactTotals {
    /// Vector sum of the impulses the bodies gave the cloth [N·s].
    pub impulse: Vec3,
    /// Sum of the magnitudes of the normal impulses [N·s].
    pub normal_impulse: f32,
    /// Sum of the magnitudes of the friction impulses [N·s].
    pub friction_impulse: f32,
    /// Area of the particles in contact [m²].
    pub contact_area: f32,
    /// Deepest particle inside a body, before the response [m].
    pub max_penetration: f32,
    /// Particles found closer to a body than the contact thickness (by more than
    /// [`CAUGHT`] of it), or whose path crossed its surface, and put back: what the step
    /// before left for this stage to catch.
    pub corrections: u32,
}

impl ContactTotals {
    /// Adds `other`'s contacts to these: impulses and areas sum, the penetration is the
    /// deeper of the two.
    pub fn add(&mut self, other: &ContactTotals) {
        self.impulse += other.impulse;
        self.normal_impulse += other.normal_impulse;
        self.friction_impulse += other.friction_impulse;
        self.contact_area += other.contact_area;
        self.max_penetration = self.max_penetration.max(other.max_penetration);
        self.corrections += other.corrections;
    }
}

/// The fraction of the contact thickness by which a particle must be closer to a body to
/// count among the [`ContactTotals::corrections`]: an implicit step that held it on the
/// surface leaves it at the thickness only to round-off.
pub const CAUGHT: f32 = 0.01;

/// The push of the cloth on one body over a step: what a free body needs to be moved
/// by the cloth in turn (two-way coupling).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BodyLoad {
    /// Sum of the impulses the body gave the cloth [N·s]; the body gets the opposite.
    pub impulse: Vec3,
    /// Sum of their moments about the world origin, `Σ x × J` [N·m·s].
    pub moment: Vec3,
}

impl BodyLoad {
    /// The load of `impulse` given at `at`.
    pub fn at(at: Vec3, impulse: Vec3) -> BodyLoad {
        BodyLoad { impulse, moment: at.cross(impulse) }
    }

    /// Adds `other`'s impulses and moments to these.
    pub fn add(&mut self, other: &BodyLoad) {
        self.impulse += other.impulse;
        self.moment += other.moment;
    }

    /// The moment of the impulses about `centre` [N·m·s].
    pub fn moment_about(&self, centre: Vec3) -> Vec3 {
        self.moment - centre.cross(self.impulse)
    }
}

/// A body's share of one particle's contact: the body's index and the impulse it gave.
type Push = Option<(u32, Vec3)>;

/// What [`resolve_body_contacts`] leaves for the caller, in buffers kept from step to
/// step.
#[derive(Debug, Clone, Default)]
pub struct BodyContactOutput {
    /// Per body, what the cloth pushed it with.
    pub loads: Vec<BodyLoad>,
    /// Each particle's outcome, combined in particle order after the parallel pass.
    outcomes: Vec<ParticleContact>,
}

/// One particle's contact outcome, combined in particle order.
#[derive(Debug, Clone, Copy, Default)]
struct ParticleContact {
    totals: ContactTotals,
    touch: Option<Touch>,
    /// Impulses from at most two bodies (a third one's adds to the second's).
    pushes: [Push; 2],
    /// Where the particle ended.
    at: Vec3,
}

/// A particle touching a body at the end of a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Touch {
    /// The particle.
    pub particle: u32,
    /// The body's outward normal there.
    pub normal: Vec3,
    /// The body's surface velocity there [m/s].
    pub surface_velocity: Vec3,
    /// The body's index in the list given to [`resolve_body_contacts`].
    pub body: u32,
    /// How far beyond the contact thickness the particle ended [m], which the next
    /// implicit step closes: zero where the response put it back, up to [`TOUCH_SLACK`]
    /// of the thickness where it was left (and zero for Durupınar's regimes, whose
    /// penalty keeps the cloth off the surface).
    pub gap: f32,
    /// Whether static friction holds it: the next implicit step then keeps its whole
    /// velocity at the body's, not only the normal part.
    pub sticking: bool,
}

/// Where a particle is against a body.
#[derive(Debug, Clone, Copy)]
struct Proximity {
    /// Signed distance to the body's surface, negative inside [m].
    signed: f32,
    /// The body's outward normal there.
    outward: Vec3,
}

/// One particle as a response changes it.
struct Particle<'p> {
    x: &'p mut Vec3,
    v: &'p mut Vec3,
    mass: f32,
    area: f32,
    /// The impulse an implicit step's constraints gave it [N·s].
    support: Vec3,
    /// The body that step held it fast on (static friction), if any.
    held: Option<u32>,
}

/// Resolves the contacts of particles `x`, `v` (masses `1/inv_mass`, areas `area`) with
/// `bodies` at the end of a step of `h` [s] that started at positions `start`. The
/// particles left touching a body are listed in `touching`, in particle order, for the
/// next implicit step to keep them there; `support` is the impulse such a step's
/// constraints gave each particle [N·s] (zero for explicit steps), which counts as contact
/// force, given to the body the particle touched at the end of the last step (`touching`
/// as it comes in) unless that is a prop, which took it within the step.
/// `output.loads` receives, per body, what the cloth pushed it with here.
///
/// A particle that moved further than the contact thickness in the step is first traced
/// along its path (a ray from `start`): if the path enters a body, the particle is put
/// back where it entered, so fast cloth cannot tunnel through thin bodies. Pinned particles
/// (`free_inv_mass` zero) are left alone.
pub fn resolve_body_contacts(
    bodies: &[ContactBody],
    inv_mass: &[f32],
    free_inv_mass: &[f32],
    area: impl Fn(usize) -> f32 + Sync,
    h: f32,
    start: &[Vec3],
    support: &[Vec3],
    x: &mut [Vec3],
    v: &mut [Vec3],
    touching: &mut Vec<Touch>,
    output: &mut BodyContactOutput,
) -> ContactTotals {
    let BodyContactOutput { loads, outcomes } = output;
    let previous: &[Touch] = touching;
    x.par_iter_mut()
        .zip(v.par_iter_mut())
        .enumerate()
        .with_min_len(PARALLEL_MIN_LEN)
        .map(|(i, (x, v))| {
            let mut outcome = ParticleContact::default();
            if free_inv_mass[i] == 0.0 {
                return outcome;
            }
            let before = *v;
            // The body whose surface the implicit constraint held the particle on.
            let held_on = (support[i] != Vec3::ZERO)
                .then(|| previous.binary_search_by_key(&(i as u32), |t| t.particle).ok().map(|k| previous[k]))
                .flatten();
            // A prop took its support within the step (strong coupling): only a fixed or
            // keyframed body is pushed by it here.
            if let Some(touch) = held_on.filter(|t| !bodies.get(t.body as usize).is_some_and(|b| b.prop)) {
                outcome.pushes[0] = Some((touch.body, support[i]));
            }
            let held = held_on.filter(|t| t.sticking).map(|t| t.body);
            let mut particle = Particle { x, v, mass: 1.0 / inv_mass[i], area: area(i), support: support[i], held };
            for (b, body) in bodies.iter().enumerate() {
                let Some(near) = locate(body, h, start[i], particle.x) else {
                    continue;
                };
                let body_index = b as u32;
                let before_body = *particle.v;
                outcome.totals.max_penetration = outcome.totals.max_penetration.max(-near.signed);
                outcome.totals.corrections += u32::from(near.signed < (1.0 - CAUGHT) * body.thickness);
                outcome.totals.contact_area = particle.area;
                // Whether it touches, whether it sticks, and the gap the next step closes.
                let (touches, sticking, gap) = match body.response {
                    ContactResponse::Slide => {
                        // Only a particle that stuck to this body can be held on it.
                        let held =
                            particle.held == Some(body_index) && hold(body, near, &particle, &mut outcome.totals);
                        let stopped = slide(body, near, &mut particle, h, &mut outcome.totals);
                        (true, held || (stopped && !body.prop), (near.signed - body.thickness).max(0.0))
                    }
                    ContactResponse::Stick => (stick(body, near, &mut particle, h, &mut outcome.totals), false, 0.0),
                    ContactResponse::Regimes(regimes) => {
                        let touches = respond_in_regimes(body, &regimes, near, &mut particle, h, &mut outcome.totals);
                        (touches, false, 0.0)
                    }
                };
                if touches {
                    outcome.touch = Some(Touch {
                        particle: i as u32,
                        normal: near.outward,
                        surface_velocity: body.state.velocity_at(*particle.x),
                        body: body_index,
                        gap,
                        sticking,
                    });
                }
                let impulse = (*particle.v - before_body) * particle.mass;
                match &mut outcome.pushes {
                    [Some((k, total)), _] | [_, Some((k, total))] if *k == body_index => *total += impulse,
                    [first @ None, _] => *first = Some((body_index, impulse)),
                    [_, second @ None] => *second = Some((body_index, impulse)),
                    [_, Some((_, total))] => *total += impulse,
                }
            }
            outcome.totals.impulse = (*particle.v - before) * particle.mass + particle.support;
            outcome.at = *particle.x;
            outcome
        })
        .collect_into_vec(outcomes);
    touching.clear();
    // Room made once for all: contact beginning (a cloth landing on the ground) grew this
    // list, and the four made from it each step, by doubling, 29 allocations in a frame.
    touching.reserve(outcomes.iter().filter(|o| o.touch.is_some()).count());
    touching.extend(outcomes.iter().filter_map(|o| o.touch));
    loads.clear();
    loads.resize(bodies.len(), BodyLoad::default());
    for outcome in outcomes.iter() {
        for &(body, impulse) in outcome.pushes.iter().flatten() {
            // A touch left by a body that is no longer listed has no one to push.
            if let Some(load) = loads.get_mut(body as usize) {
                load.add(&BodyLoad::at(outcome.at, impulse));
            }
        }
    }
    outcomes.iter().fold(ContactTotals::default(), |mut totals, o| {
        totals.add(&o.totals);
        totals
    })
}

/// Fraction of the contact thickness beyond it within which a particle still touches a
/// body, so that the next implicit step keeps it on the surface (closing the gap). A
/// particle that step held on the surface ends at the thickness only to round-off (a
/// quarter of a 0.26 mm thickness is one float step at 0.75 m), or a little off a body
/// that accelerated during the step; without this slack it fell out of contact every
/// other step, was let fall into the body, and was stopped there by friction: a table
/// drape at 1/30 s rang at 100 % strain.
const TOUCH_SLACK: f32 = 0.25;

/// Where the particle at `x` is against the body, if within the body's reach (or within
/// [`TOUCH_SLACK`] beyond it): the point
/// its path from `start` entered the body if it crossed the surface this step (`x` is
/// moved there and the distance is zero), else its nearest surface point. The path is
/// taken relative to the body (its start carried along by the body's motion over the
/// step `h`), so a body moving onto resting cloth meets it with the face it moves with,
/// not with whichever face the cloth ends nearest.
fn locate(body: &ContactBody, h: f32, start: Vec3, x: &mut Vec3) -> Option<Proximity> {
    let start = start + h * body.state.velocity_at(start);
    let path = *x - start;
    let entry = (path.length() > body.thickness && !body.shape.contains_point(&body.state.pose, start))
        .then(|| {
            let ray = Ray::new(start, path);
            body.shape
                .cast_ray_and_get_normal(&body.state.pose, &ray, 1.0, true)
                .map(|hit| (ray.point_at(hit.time_of_impact), hit.normal))
        })
        .flatten();
    if let Some((point, outward)) = entry {
        *x = point;
        return Some(Proximity { signed: 0.0, outward });
    }
    let near = body.surface_near(*x);
    let signed = near.signed;
    let slack = match body.response {
        ContactResponse::Slide | ContactResponse::Stick => TOUCH_SLACK * body.thickness,
        ContactResponse::Regimes(_) => 0.0,
    };
    if signed >= body.thickness + slack + body.response.reach() {
        return None;
    }
    // A particle exactly on the surface has no direction to leave by.
    Some(Proximity { signed, outward: near.outward? })
}

/// Moves a particle closer to the body than the contact thickness out to it along the
/// normal, and returns the body's surface velocity there and the particle's velocity
/// relative to it.
fn put_back(body: &ContactBody, near: Proximity, p: &mut Particle<'_>) -> (Vec3, Vec3) {
    *p.x += (body.thickness - near.signed).max(0.0) * near.outward;
    let surface = body.state.velocity_at(*p.x);
    (surface, *p.v - surface)
}

/// Static friction for a particle the last implicit step held fast on the body (its whole
/// velocity kept at the body's): it stays held while the tangential impulse that took
/// lies within the Coulomb cone of the normal one, and is let go to slide from the next
/// step otherwise. (Giving the impulse beyond the cone back to it at once is an explicit
/// step of the stiff forces that pulled it, and diverged.) The friction impulse is what the
/// hold took, even where that left the cone for this one step. Returns whether it stays
/// held.
///
/// A hold lasts a whole step, so at frame-sized steps a particle held while its
/// neighbours slide stretches their edges until the next step lets it go. (Much of the
/// stretch at sphere_64's corners at one step a frame once put down to this came from
/// the take-back of [`slide`], traced step by step in the tenth session.) Letting go
/// within the step and solving again, the particle free along the surface, slid it
/// there without friction and was worse (ARCHITECTURE, "Steps that follow the motion").
fn hold(body: &ContactBody, near: Proximity, p: &Particle<'_>, totals: &mut ContactTotals) -> bool {
    let normal = p.support.dot(near.outward);
    let tangential = (p.support - normal * near.outward).length();
    totals.friction_impulse += tangential;
    tangential <= body.friction * normal.max(0.0)
}

/// Zheng's response: put back at the contact thickness, the approach velocity relative to
/// the surface removed, and Coulomb friction bounded by μ times the velocity removed (to
/// zero if that suffices: sticking). Friction also takes back the sliding the step made
/// (`Δx = h Δv_t`), so a sticking particle does not creep by `h² g sin θ` a step. Returns
/// whether friction stopped the particle on the body (it sticks).
///
/// After an implicit step the normal velocity removed includes the push its constraint
/// gave a particle resting on the body (`support`), but only the part this response
/// removes itself (an impact) takes back sliding: the constraint's share slows the
/// particle and no more, and the next step holds it fast if it stuck. Taking back that
/// share too moved the particle alone, by up to `h μ support / m` (2 mm at one step a
/// frame on sphere_64's corners, pressed some 20 times their weight), against neighbours
/// the solve had balanced without it; the next solve pulled it out again, and the sheet
/// at rest kept edges 5 to 14 % stretched, step after step (ARCHITECTURE, "Steps that
/// follow the motion").
fn slide(body: &ContactBody, near: Proximity, p: &mut Particle<'_>, h: f32, totals: &mut ContactTotals) -> bool {
    let outward = near.outward;
    let (surface, relative) = put_back(body, near, p);
    let approach = relative.dot(outward);
    // What an implicit solve's constraint pushed along the normal counts as contact force
    // (signed: its pulls cancel its pushes across the cloth).
    totals.normal_impulse += p.support.dot(outward);
    // The normal velocity this response removes, and the one the constraint's push gave
    // a particle resting on the body, bound kinetic friction.
    let removed = (-approach).max(0.0);
    let pressed = match (body.prop, p.held) {
        (false, None) => (p.support.dot(outward) / p.mass).max(0.0),
        _ => 0.0,
    };
    if removed + pressed == 0.0 {
        return false;
    }
    let tangential = relative - approach * outward;
    let speed = tangential.length();
    let bound = body.friction * (removed + pressed);
    let sticks = speed <= bound;
    let slip = if sticks { Vec3::ZERO } else { tangential * (1.0 - bound / speed) };
    *p.v = surface + approach.max(0.0) * outward + slip;
    *p.x += h * removed / (removed + pressed) * (slip - tangential);
    totals.normal_impulse += p.mass * removed;
    totals.friction_impulse += p.mass * (tangential - slip).length();
    sticks && body.friction > 0.0
}

/// Bricis's restrain-on-contact (B5): put back at the contact thickness, the whole step's
/// motion relative to the body taken back, and moving with the body from then on.
fn stick(body: &ContactBody, near: Proximity, p: &mut Particle<'_>, h: f32, totals: &mut ContactTotals) -> bool {
    let outward = near.outward;
    let (surface, relative) = put_back(body, near, p);
    let approach = relative.dot(outward);
    let tangential = relative - approach * outward;
    *p.x -= h * tangential;
    *p.v = surface;
    totals.normal_impulse += p.mass * approach.abs();
    totals.friction_impulse += p.mass * tangential.length();
    true
}

/// Durupınar's four regimes (D11), with distances measured from the surface grown by the
/// contact thickness. Interference (behind that surface) is corrected in position and
/// velocity; a particle within `surface` gets the penalty and the velocity correction;
/// one within `outside` only the penalty. The penalty acts over the step as a force would
/// (`Δv = h F / m`, and the position moves by `h Δv`). Returns whether the particle is in
/// contact (cases 2 and 3) rather than only near.
fn respond_in_regimes(
    body: &ContactBody,
    regimes: &Regimes,
    near: Proximity,
    p: &mut Particle<'_>,
    h: f32,
    totals: &mut ContactTotals,
) -> bool {
    let outward = near.outward;
    let interference = near.signed <= body.thickness;
    let distance = (near.signed - body.thickness).max(0.0);
    let (surface, relative) = put_back(body, near, p);
    let approach = relative.dot(outward);
    let before = *p.v;
    let corrected = distance < regimes.surface;
    if corrected && approach < 0.0 {
        let tangential = relative - approach * outward;
        *p.v = surface + regimes.tangential * tangential - regimes.restitution * approach * outward;
        *p.x += h * (regimes.tangential - 1.0) * tangential;
    }
    if !interference {
        // Backward Euler on the penalty: its pressure is taken where the kick leaves the
        // particle (distance + h kick) and at the velocity after the kick. A cloth at rest
        // then rests exactly where k × depth = ρ g, rather than lower by the step's own fall
        // g h², and no stiffness makes the penalty unstable.
        let per_pressure = h * p.area / p.mass;
        let approach = (*p.v - surface).dot(outward);
        let pressure = regimes.stiffness * (regimes.outside - distance) - regimes.damping * approach;
        let give = 1.0 + per_pressure * (regimes.damping + h * regimes.stiffness);
        let kick = (per_pressure * pressure / give).max(0.0) * outward;
        *p.v += kick;
        *p.x += h * kick;
    }
    let change = (*p.v - before) * p.mass;
    let normal = change.dot(outward);
    totals.normal_impulse += normal.abs();
    totals.friction_impulse += (change - normal * outward).length();
    corrected
}

#[cfg(test)]
mod tests {
    use parry3d::math::Pose3;
    use parry3d::shape::{Cuboid, HalfSpace};

    use super::*;

    /// Resolves one body against particles `x`, `v` of unit inverse mass and area, with no
    /// implicit support, after a step of `h` from `start`.
    fn resolve(body: ContactBody, h: f32, start: &[Vec3], x: &mut [Vec3], v: &mut [Vec3]) -> ContactTotals {
        let ones = vec![1.0; x.len()];
        let support = vec![Vec3::ZERO; x.len()];
        resolve_body_contacts(
            &[body],
            &ones,
            &ones,
            |_| 1.0,
            h,
            start,
            &support,
            x,
            v,
            &mut Vec::new(),
            &mut BodyContactOutput::default(),
        )
    }

    fn ground() -> (HalfSpace, ColliderState) {
        (HalfSpace::new(Vec3::Y), ColliderState { pose: Pose3::IDENTITY, linear: Vec3::ZERO, angular: Vec3::ZERO })
    }

    #[test]
    fn a_particle_below_the_ground_is_put_back_and_slowed_by_friction() {
        let (shape, state) = ground();
        let body = ContactBody {
            shape: SharedShape::new(shape),
            state,
            friction: 0.5,
            thickness: 0.0,
            response: ContactResponse::Slide,
            prop: false,
        };
        let mut x = [Vec3::new(0.3, -0.01, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let mut v = [Vec3::new(2.0, -1.0, 0.0), Vec3::new(0.0, -1.0, 0.0)];
        let mut output = BodyContactOutput::default();
        let totals = resolve_body_contacts(
            &[body],
            &[2.0, 2.0],
            &[2.0, 2.0],
            |_| 0.25,
            0.0,
            &x.clone(),
            &[Vec3::ZERO; 4][..x.len()],
            &mut x,
            &mut v,
            &mut Vec::new(),
            &mut output,
        );
        let loads = output.loads;
        assert!(x[0].y.abs() < 1e-7);
        assert!((v[0] - Vec3::new(1.5, 0.0, 0.0)).length() < 1e-6);
        assert_eq!(v[1], Vec3::new(0.0, -1.0, 0.0), "particles above the plane are untouched");
        // Impulse on a 0.5 kg particle: +0.5 N·s up, −0.25 N·s along x.
        assert!((totals.impulse - Vec3::new(-0.25, 0.5, 0.0)).length() < 1e-6);
        assert!((totals.normal_impulse - 0.5).abs() < 1e-6 && (totals.friction_impulse - 0.25).abs() < 1e-6);
        assert!((totals.contact_area - 0.25).abs() < 1e-7 && (totals.max_penetration - 0.01).abs() < 1e-7);
        // The ground's load is that impulse, applied at (0.3, 0, 0): moment x × J about the origin.
        assert_eq!(loads.len(), 1);
        assert!((loads[0].impulse - totals.impulse).length() < 1e-6);
        assert!((loads[0].moment - Vec3::new(0.0, 0.0, 0.3 * 0.5)).length() < 1e-6, "{}", loads[0].moment);
        assert!(loads[0].moment_about(Vec3::new(0.3, 0.0, 0.0)).length() < 1e-6);
    }

    #[test]
    fn enough_friction_makes_a_particle_stick_and_a_moving_surface_carries_it() {
        let (shape, mut state) = ground();
        state.linear = Vec3::new(0.3, 0.0, 0.0);
        let body = ContactBody {
            shape: SharedShape::new(shape),
            state,
            friction: 2.0,
            thickness: 0.001,
            response: ContactResponse::Slide,
            prop: false,
        };
        let mut x = [Vec3::new(0.0, 0.0005, 0.0)];
        let mut v = [Vec3::new(0.5, -0.2, 0.0)];
        resolve(body, 0.0, &x.clone(), &mut x, &mut v);
        assert!((x[0].y - 0.001).abs() < 1e-7, "kept at the contact thickness");
        assert!((v[0] - Vec3::new(0.3, 0.0, 0.0)).length() < 1e-6, "moves with the surface");
    }

    #[test]
    fn a_fast_particle_is_stopped_at_a_thin_plate_it_would_have_crossed() {
        // A 2 mm plate; the particle jumps from 5 cm above to 5 cm below in one step.
        let plate = Cuboid::new(Vec3::new(1.0, 0.001, 1.0));
        let state = ColliderState { pose: Pose3::IDENTITY, linear: Vec3::ZERO, angular: Vec3::ZERO };
        let body = ContactBody {
            shape: SharedShape::new(plate),
            state,
            friction: 0.0,
            thickness: 0.0005,
            response: ContactResponse::Slide,
            prop: false,
        };
        let start = [Vec3::new(0.1, 0.05, 0.0)];
        let mut x = [Vec3::new(0.1, -0.05, 0.0)];
        let mut v = [Vec3::new(0.0, -10.0, 0.0)];
        resolve(body, 0.01, &start, &mut x, &mut v);
        assert!((x[0].y - 0.0015).abs() < 1e-5, "stopped on the upper face: {}", x[0].y);
        assert!(v[0].y.abs() < 1e-6, "its approach velocity removed");
    }

    #[test]
    fn in_stick_mode_a_touching_particle_moves_with_the_body_even_when_pulled_away() {
        let (shape, mut state) = ground();
        state.linear = Vec3::new(0.2, 0.0, 0.0);
        let body = ContactBody {
            shape: SharedShape::new(shape),
            state,
            friction: 0.0,
            thickness: 0.001,
            response: ContactResponse::Stick,
            prop: false,
        };
        let start = [Vec3::new(0.0, 0.0008, 0.0)];
        let mut x = [Vec3::new(0.01, 0.0009, 0.0)];
        let mut v = [Vec3::new(1.0, 0.1, 0.0)];
        resolve(body, 0.01, &start, &mut x, &mut v);
        assert_eq!(v[0], Vec3::new(0.2, 0.0, 0.0));
        assert!((x[0] - Vec3::new(0.002, 0.001, 0.0)).length() < 1e-6, "moved with the body: {}", x[0]);
    }
    /// The frictionless ground, 1 mm thick, in Durupınar's regimes: thresholds 10 mm and
    /// 2 mm, penalty stiffness 100 and the given damping, C_fric 0.5, C_refl 0.2.
    fn regimes_ground(damping: f32) -> ContactBody {
        let (shape, state) = ground();
        let regimes =
            Regimes { outside: 0.01, surface: 0.002, stiffness: 100.0, damping, tangential: 0.5, restitution: 0.2 };
        ContactBody {
            shape: SharedShape::new(shape),
            state,
            friction: 0.0,
            thickness: 0.001,
            response: ContactResponse::Regimes(regimes),
            prop: false,
        }
    }

    #[test]
    fn within_t_outside_only_the_damped_penalty_acts() {
        for (damping, kick) in [(0.0, 0.004 / 1.01), (2.0, 0.006 / 1.03)] {
            // 6 mm from the grown surface: pressure k (T_out − d) + c v_approach over h = 10 ms,
            // taken after the kick (backward Euler): divided by 1 + h (c + h k) = 1.01 + h c.
            let body = regimes_ground(damping);
            let mut x = [Vec3::new(0.0, 0.007, 0.0)];
            let mut v = [Vec3::new(0.3, -0.1, 0.0)];
            let totals = resolve(body, 0.01, &x.clone(), &mut x, &mut v);
            assert!((v[0] - Vec3::new(0.3, -0.1 + kick, 0.0)).length() < 1e-6, "{}", v[0]);
            assert!((x[0].y - (0.007 + 0.01 * kick)).abs() < 1e-7);
            assert!((totals.normal_impulse - kick).abs() < 1e-6 && totals.contact_area == 1.0);
        }
    }

    #[test]
    fn within_t_surface_the_velocity_is_corrected_as_vassilev_and_spanlang_do() {
        let body = regimes_ground(0.0);
        let mut x = [Vec3::new(0.0, 0.002, 0.0)];
        let mut v = [Vec3::new(1.0, -0.5, 0.0)];
        let mut touching = Vec::new();
        let ones = [1.0];
        resolve_body_contacts(
            &[body],
            &ones,
            &ones,
            |_| 1.0,
            0.01,
            &x.clone(),
            &[Vec3::ZERO],
            &mut x,
            &mut v,
            &mut touching,
            &mut BodyContactOutput::default(),
        );
        // v = C_fric v_t − C_refl v_n, then the penalty 100 × 9 mm over 10 ms (backward Euler).
        assert!((v[0] - Vec3::new(0.5, 0.1 + 0.009 / 1.01, 0.0)).length() < 1e-6, "{}", v[0]);
        assert!((x[0].x + 0.005).abs() < 1e-7, "the step's sliding is taken back by the correction");
        assert_eq!(touching.len(), 1, "case 2 is a contact");
    }

    #[test]
    fn interference_is_corrected_in_position_and_velocity() {
        let body = regimes_ground(0.0);
        let mut x = [Vec3::new(0.0, -0.003, 0.0)];
        let mut v = [Vec3::new(0.0, -1.0, 0.0)];
        let totals = resolve(body, 0.01, &x.clone(), &mut x, &mut v);
        assert!((x[0].y - 0.001).abs() < 1e-7, "put back on the grown surface");
        assert!((v[0].y - 0.2).abs() < 1e-6, "reflected with C_refl = 0.2, no penalty");
        assert!((totals.max_penetration - 0.003).abs() < 1e-7);
    }
}
