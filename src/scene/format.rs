//! Serde types of a scene file. They describe; they are never components. Every struct
//! refuses unknown fields, so a misspelt field is an error rather than a silent default.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::builders::Placement;
use crate::builders::pins::{GridEdge, PinSelection};
use crate::collision::collider::{ColliderShape, ContactResponse, Pose};
use crate::components::ClothMaterial;
use crate::fabrics::FabricDesc;
use crate::solver::descent::DescentSettings;
use crate::solver::integrate::{Integrator, MethodSettings};
use crate::solver::probes::ClothProbe;

/// A whole run: world, cloths, solver, duration and outputs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Name of the scene; the default output folder is `out/<name>`.
    pub name: String,
    /// Gravitational acceleration [m/s²].
    #[serde(default = "default_gravity")]
    pub gravity: Vec3,
    /// Drag and wind.
    #[serde(default)]
    pub air: AirDesc,
    /// Integrator and step.
    #[serde(default)]
    pub solver: SolverDesc,
    /// Frame rate and duration.
    pub time: TimeDesc,
    /// The cloths.
    pub cloths: Vec<ClothDesc>,
    /// The ground plane.
    #[serde(default)]
    pub ground: GroundDesc,
    /// Solid bodies: static, or moving along keyframes.
    #[serde(default)]
    pub colliders: Vec<ColliderDesc>,
    /// Rigid props (rapier3d): free bodies that cloth and colliders push, and that push
    /// cloth in turn.
    #[serde(default)]
    pub props: Vec<PropDesc>,
    /// What to write.
    #[serde(default)]
    pub output: OutputDesc,
    /// When to stop a run as diverged.
    #[serde(default)]
    pub divergence: DivergenceDesc,
    /// Changes to cloths at given times: tears, pins, releases.
    #[serde(default)]
    pub edits: Vec<EditDesc>,
    /// Measurements of particular cloths, reported beside the built-in probes.
    #[serde(default)]
    pub probes: Vec<ClothProbe>,
}

fn default_gravity() -> Vec3 {
    Vec3::new(0.0, -9.81, 0.0)
}

/// Air drag and wind.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AirDesc {
    /// Linear drag rate [1/s]: each particle feels `−drag · m · v`.
    pub drag: f32,
    /// Mean wind velocity [m/s].
    pub wind: Vec3,
    /// Normal drag coefficient of the cloth surface [kg/m³], about ½ ρ_air C_d (≈ 0.6 in
    /// air); 0 turns wind and aerodynamic drag off.
    pub wind_drag: f32,
    /// Periodic gusts.
    pub gust: Option<GustDesc>,
    /// Linear air damping per unit area η [kg/(m²·s)] (Zheng uses 2–3 times the areal
    /// density): each particle feels `−η a v` for the area `a` it represents.
    pub area_damping: f32,
}

/// Sinusoidal gusts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GustDesc {
    /// Relative amplitude of the wind speed [-].
    pub amplitude: f32,
    /// Period [s].
    pub period_s: f32,
}

/// The integrator and the step. Give `substeps` (steps per frame) or `dt` (the step [s]),
/// or both if they agree; the step is `1 / (fps · substeps)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverDesc {
    /// Integration method; by default `ImplicitEuler`, stable on stiff fabric up to frame-sized steps.
    pub integrator: Integrator,
    /// Step length [s]; must divide the frame time.
    pub dt: Option<f32>,
    /// Steps per frame.
    pub substeps: Option<u32>,
    /// Relative error tolerance of `Rk45` [-] (default 1e-4; refused with another
    /// integrator, which would ignore it).
    pub tolerance: Option<f32>,
    /// θ of `Newmark`, in [0.5, 1] (default 0.5: constant average acceleration, Bricis's
    /// choice; refused with another integrator).
    pub theta: Option<f32>,
    /// Rayleigh damping `C = αM + βK` of the implicit methods.
    pub rayleigh: Option<RayleighDesc>,
    /// Relative residual at which the implicit methods' conjugate gradients stop [-].
    pub cg_tolerance: f32,
    /// Iteration cap of the conjugate gradients.
    pub cg_max_iterations: u32,
    /// Preconditioner of the conjugate gradients.
    pub preconditioner: Preconditioner,
    /// Newton iterations per implicit step (1: linearly implicit).
    pub newton_iterations: u32,
    /// How `BlockDescent` solves each step (refused with another integrator).
    pub descent: Option<DescentDesc>,
    /// Courant number α of Zheng's adaptive step for explicit methods (Z4): each step is
    /// split so that no sub-step exceeds `α Δx √(ρ/E)`, Δx the shortest current edge.
    pub cfl: Option<f32>,
    /// How far a particle may move in one step towards what it may touch within the
    /// frame (a collider, or a cloth that collides), in mean edge lengths of its cloth
    /// [-]: when given, each frame takes the fewest steps, up to `substeps`, that keep
    /// every particle within it, so a cloth landing on a body takes them all, and one at
    /// rest on it, or falling or swinging far from anything, one.
    pub step_motion: Option<f32>,
    /// The fewest steps a frame takes with `step_motion` (default 1; refused without it).
    /// At one step a frame, a particle that static friction stops on a body is held for
    /// the whole frame while its neighbours slide on: over the last 90 frames of seven
    /// runs of sphere_64 the worst strain was 0.096 to 0.245 at one step a frame, 0.035 to
    /// 0.080 at two or more, 0.023 to 0.060 at a fixed ten (README, Choosing an integrator).
    pub min_substeps: Option<u32>,
}

impl Default for SolverDesc {
    /// The library's defaults ([`MethodSettings::default`]), with `ImplicitEuler`.
    fn default() -> Self {
        let method = MethodSettings::default();
        Self {
            integrator: Integrator::ImplicitEuler,
            dt: None,
            substeps: None,
            tolerance: None,
            theta: None,
            rayleigh: None,
            cg_tolerance: method.implicit.cg_tolerance,
            cg_max_iterations: method.implicit.cg_max_iterations,
            preconditioner: Preconditioner::BlockJacobi,
            newton_iterations: method.implicit.newton_iterations,
            descent: None,
            cfl: None,
            step_motion: None,
            min_substeps: None,
        }
    }
}

impl SolverDesc {
    /// `Rk45`'s tolerance, given or the library's default.
    pub fn tolerance(&self) -> f32 {
        self.tolerance.unwrap_or(MethodSettings::default().tolerance)
    }

    /// `Newmark`'s θ, given or the library's default.
    pub fn theta(&self) -> f32 {
        self.theta.unwrap_or(MethodSettings::default().implicit.theta)
    }

    /// `BlockDescent`'s settings, given or default.
    pub fn descent(&self) -> DescentDesc {
        self.descent.unwrap_or_default()
    }
}

/// How the implicit methods precondition their conjugate gradients.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Preconditioner {
    /// Each particle's diagonal block: cheap per iteration, but the iterations grow with
    /// the cloth's size and stiffness.
    BlockJacobi,
    /// A smoothed-aggregation multigrid V-cycle: about four times the cost per iteration,
    /// and few iterations on any size.
    Multigrid,
}

/// Block descent's effort per step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DescentDesc {
    /// Coloured Gauss–Seidel sweeps per Newton iteration (≥ 1): the cost of a step.
    pub sweeps: u32,
    /// Chebyshev's estimate of a sweep's spectral radius, in [0, 1) (0: no acceleration).
    pub spectral_radius: f32,
    /// Whether a self-colliding cloth's contact with itself and with the other
    /// self-colliding cloths bounds how far each sweep moves each particle, so that no
    /// sweep passes a vertex through a triangle (default true; false leaves crossings to
    /// the contact stage after the step).
    pub contact_bounds: bool,
}

impl Default for DescentDesc {
    fn default() -> Self {
        let settings = DescentSettings::default();
        Self {
            sweeps: settings.sweeps,
            spectral_radius: settings.spectral_radius,
            contact_bounds: settings.contact_bounds,
        }
    }
}

/// The solver's settings a scene's [`DescentDesc`] gives, field for field.
impl From<DescentDesc> for DescentSettings {
    fn from(desc: DescentDesc) -> Self {
        Self { sweeps: desc.sweeps, spectral_radius: desc.spectral_radius, contact_bounds: desc.contact_bounds }
    }
}

/// Rayleigh damping, by its coefficients or by two frequencies to damp critically.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum RayleighDesc {
    /// `C = alpha M + beta K`: α [1/s], β [s].
    Coefficients {
        /// Mass-proportional coefficient [1/s].
        alpha: f32,
        /// Stiffness-proportional coefficient [s].
        beta: f32,
    },
    /// The α, β that damp both angular frequencies [rad/s] critically (Bricis: 0.3 and 0.9
    /// give α = 0.45, β = 1.667).
    Critical {
        /// First angular frequency [rad/s].
        omega1: f32,
        /// Second angular frequency [rad/s].
        omega2: f32,
    },
}

/// Steps per frame when a scene gives neither `dt` nor `substeps`.
pub const DEFAULT_SUBSTEPS: u32 = 10;

/// Frame rate and length of the run: give `duration_s` or `frames`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TimeDesc {
    /// Frames per second [1/s].
    pub fps: f32,
    /// Length of the run [s].
    pub duration_s: Option<f32>,
    /// Number of frames.
    pub frames: Option<u32>,
}

impl Default for TimeDesc {
    fn default() -> Self {
        Self { fps: 60.0, duration_s: None, frames: None }
    }
}

/// One cloth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClothDesc {
    /// Unique name.
    pub name: String,
    /// How to build it.
    pub shape: ShapeDesc,
    /// Where it goes.
    #[serde(default)]
    pub placement: Placement,
    /// Direction of the warp in the cloth's local XY plane, from local +X [degrees]: how
    /// the piece is cut from the fabric. The weft is perpendicular to it.
    #[serde(default)]
    pub grain_deg: f32,
    /// What it is made of, element by element. Give this or `fabric`.
    #[serde(default)]
    pub material: Option<ClothMaterial>,
    /// What it is made of, as a library fabric or textile measurements. Give this or
    /// `material`.
    #[serde(default)]
    pub fabric: Option<FabricDesc>,
    /// Particles held in place from the start.
    #[serde(default)]
    pub pins: Vec<PinSelection>,
    /// Particles held by hands or clamps that move along keyframes.
    #[serde(default)]
    pub grips: Vec<GripDesc>,
    /// Initial velocity of every particle [m/s].
    #[serde(default)]
    pub velocity: Vec3,
    /// Distance the cloth's mid-surface keeps from solid bodies [m]; the fabric's
    /// thickness, or 1 mm, when not given.
    #[serde(default)]
    pub thickness: Option<f32>,
    /// Constant forces on chosen particles.
    #[serde(default)]
    pub user_forces: Vec<UserForceDesc>,
    /// Constant loads per unit length along edges of a grid cloth.
    #[serde(default)]
    pub tractions: Vec<TractionDesc>,
    /// A bound on warp and weft strain, enforced after every step.
    #[serde(default)]
    pub strain_limit: Option<StrainLimitDesc>,
    /// Contact of the cloth with itself and with the other cloths that have it.
    #[serde(default)]
    pub self_collision: Option<SelfCollisionDesc>,
}

/// A grip: the selected particles are pinned and carried rigidly along keyframed poses,
/// as if held in a clamp. Each particle keeps its place in the grip's frame, taken at the
/// first keyframe.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GripDesc {
    /// The held particles.
    pub particles: Vec<PinSelection>,
    /// `(time [s], pose)`, at least one, in increasing time; the grip moves linearly in
    /// translation and spherically in rotation between them (less than half a turn
    /// between two keyframes) and rests outside them.
    pub keyframes: Vec<(f32, Pose)>,
}

/// Cloth–cloth contact: `self_collision: ()` turns it on with the defaults.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SelfCollisionDesc {
    /// Distance kept between layers' mid-surfaces [m]; the cloth's contact thickness when
    /// not given. Must be below half the shortest edge of the cloth, or neighbouring
    /// triangles of a flat cloth would push each other.
    pub separation: Option<f32>,
    /// Coulomb friction between layers [-]; 0.2 when not given.
    pub friction: Option<f32>,
    /// Layer number: where cloths start intersecting, a cloth of a higher layer is
    /// untangled onto the side its lower neighbour's triangle normals point to (outside).
    pub layer: u32,
}

/// Friction between layers when a scene does not give one.
pub const DEFAULT_CLOTH_FRICTION: f32 = 0.2;

/// Strain limiting: edges are projected back to at most `max_strain` after every step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StrainLimitDesc {
    /// Largest strain [-], for example 0.01 for 1 %.
    pub max_strain: f32,
    /// Which edges: all of them (Provot's edge limiting, the default) or those along the
    /// warp and weft (Zheng's, leaving shear free).
    #[serde(default)]
    pub edges: LimitedEdgesDesc,
    /// Most projection sweeps per step.
    #[serde(default = "default_limit_iterations")]
    pub iterations: u32,
}

/// The edges a strain limit bounds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum LimitedEdgesDesc {
    /// Every spring, or every triangle side.
    #[default]
    All,
    /// Structural springs, or triangle sides along the warp or weft.
    Grain,
}

fn default_limit_iterations() -> u32 {
    100
}

/// A constant load spread along an edge of a grid cloth: each particle of the edge carries
/// the traction times half the rest length of the edge segments beside it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TractionDesc {
    /// The loaded edge.
    pub edge: GridEdge,
    /// Force per unit length [N/m].
    pub traction: Vec3,
}

/// Contact thickness of a cloth without a fabric that gives one [m].
pub const DEFAULT_THICKNESS: f32 = 1e-3;

impl ClothDesc {
    /// The contact thickness: as given, else the fabric's, else [`DEFAULT_THICKNESS`].
    pub fn contact_thickness(&self) -> f32 {
        self.thickness.or_else(|| self.fabric.map(|f| f.measurements().thickness)).unwrap_or(DEFAULT_THICKNESS)
    }

    /// The separation, friction and layer of its self-collision, with defaults filled in.
    pub fn self_collision(&self) -> Option<(f32, f32, u32)> {
        self.self_collision.map(|c| {
            let separation = c.separation.unwrap_or_else(|| self.contact_thickness());
            (separation, c.friction.unwrap_or(DEFAULT_CLOTH_FRICTION), c.layer)
        })
    }

    /// The element material: the one given, or the fabric's.
    pub fn resolved_material(&self) -> Option<ClothMaterial> {
        self.material.or_else(|| self.fabric.map(|f| f.measurements().material()))
    }
}

/// How a cloth's particles, springs and triangles are made.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ShapeDesc {
    /// A rectangle of `resolution.0 × resolution.1` particles, `size` [m] wide and high, in
    /// the local XY plane centred on the origin.
    Grid {
        /// Width and height [m].
        size: (f32, f32),
        /// Particles along the width and the height, each ≥ 2.
        resolution: (u32, u32),
    },
    /// A disk of `radius` [m] in the local XY plane, centred on the origin: a centre
    /// particle and `rings` concentric rings, ring k holding 6k particles, so triangles stay
    /// near equilateral from the centre out.
    Disk {
        /// Radius [m].
        radius: f32,
        /// Number of rings, ≥ 1.
        rings: u32,
    },
    /// A triangle mesh from an OBJ file, relative to the scene file's folder.
    Mesh {
        /// Path of the OBJ file.
        path: String,
    },
}

/// A constant force on one particle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UserForceDesc {
    /// Particle number.
    pub particle: u32,
    /// Force [N].
    pub force: Vec3,
}

/// A solid body cloth collides with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColliderDesc {
    /// Unique name.
    pub name: String,
    /// Shape in the collider's local frame.
    pub shape: ColliderShape,
    /// Where it is (or where it starts, with keyframes).
    #[serde(default)]
    pub pose: Pose,
    /// Keyframes `(time [s], pose)`: the collider moves linearly between them and rests
    /// outside them. Empty: it stays at `pose`.
    #[serde(default)]
    pub keyframes: Vec<(f32, Pose)>,
    /// Coulomb friction coefficient against cloth [-].
    #[serde(default = "default_friction")]
    pub friction: f32,
    /// Extra distance cloth keeps from its surface [m].
    #[serde(default)]
    pub thickness: f32,
    /// How cloth responds to touching it.
    #[serde(default)]
    pub response: ContactResponse,
}

/// A free rigid body (E5), simulated by rapier3d with the scene's gravity and step, coupled
/// both ways with cloth: contact pushes cloth out of it, and the opposite impulses move it.
/// It also collides with the colliders, the ground and other props.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PropDesc {
    /// Unique name among colliders and props.
    pub name: String,
    /// A bounded shape: not a plane; a mesh only if closed.
    pub shape: ColliderShape,
    /// Where it starts.
    #[serde(default)]
    pub pose: Pose,
    /// Mass [kg]; the inertia is the shape's, uniformly filled.
    pub mass: f32,
    /// Initial velocity of its centre of mass [m/s].
    #[serde(default)]
    pub velocity: Vec3,
    /// A constant force on its centre of mass besides gravity, such as a pull [N].
    #[serde(default)]
    pub force: Vec3,
    /// Coulomb friction coefficient against cloth and other bodies [-].
    #[serde(default = "default_friction")]
    pub friction: f32,
    /// Extra distance cloth keeps from its surface [m].
    #[serde(default)]
    pub thickness: f32,
}

fn default_friction() -> f32 {
    0.5
}

/// The ground plane y = `height`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GroundDesc {
    /// Whether there is a ground.
    pub enabled: bool,
    /// Its height [m].
    pub height: f32,
    /// Coulomb friction coefficient [-].
    pub friction: f32,
}

impl Default for GroundDesc {
    fn default() -> Self {
        Self { enabled: false, height: 0.0, friction: 0.5 }
    }
}

/// Mesh file formats for frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum FrameFormat {
    /// Wavefront OBJ with vertex normals.
    Obj,
    /// Binary little-endian PLY with vertex normals.
    Ply,
}

/// What a run writes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputDesc {
    /// Output folder; `out/<scene name>` when not given. The `--out` flag overrides it.
    pub directory: Option<String>,
    /// Write every Nth frame (the first and last are always written).
    pub every: u32,
    /// Formats of the frame files; empty writes no frames.
    pub formats: Vec<FrameFormat>,
}

impl Default for OutputDesc {
    fn default() -> Self {
        Self { directory: None, every: 1, formats: vec![FrameFormat::Obj] }
    }
}

/// When a run counts as diverged (non-finite values always do).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DivergenceDesc {
    /// Largest spring strain (elongation ratio minus one) tolerated [-].
    pub max_strain: f32,
}

impl Default for DivergenceDesc {
    fn default() -> Self {
        Self { max_strain: 10.0 }
    }
}

/// A change at a given time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EditDesc {
    /// When [s].
    pub at_s: f32,
    /// Name of the cloth.
    pub cloth: String,
    /// What to do.
    pub action: EditActionDesc,
}

/// What an edit does.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum EditActionDesc {
    /// Cut springs and triangles crossing the plane through `point` with normal `normal`,
    /// within `radius` [m] of `point` if given.
    Tear {
        /// A point on the cut [m].
        point: Vec3,
        /// The cutting plane's normal.
        normal: Vec3,
        /// Reach of the cut [m].
        #[serde(default)]
        radius: Option<f32>,
    },
    /// Pin the selected particles where they are at that time.
    Pin(Vec<PinSelection>),
    /// Release the selected particles.
    Unpin(Vec<PinSelection>),
}
