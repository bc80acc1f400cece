//! Turning a scene into resources and garment entities: the only code that does.

use std::path::Path;

use bevy_ecs::prelude::*;
use glam::Vec3;
use rapier3d::prelude::{ColliderBuilder, PhysicsWorld, RigidBodyBuilder};

use super::format::{ClothDesc, EditActionDesc, LimitedEdgesDesc, Preconditioner, RayleighDesc, Scene, ShapeDesc};
use super::load::SceneError;
use super::validate::{TimePlan, time_plan};
use crate::builders::ClothData;
use crate::builders::disk::disk_mesh;
use crate::builders::grid::build_grid;
use crate::builders::mesh::{build_from_mesh, read_obj};
use crate::builders::pins::PinSelection;
use crate::builders::surface::limited_edges;
use crate::builders::tear::Cut;
use crate::collision::collider::{ColliderMotion, ColliderShape, ColliderState, ContactResponse, Pose};
use crate::collision::coupling::BodyCoupling;
use crate::components::{
    Cloth, ClothTopology, Collider, ContactStats, Grip, Grips, Pins, Prop, RenderMesh, RigidStandIn, SelfCollision,
    SolverWorkspace, StrainLimit, Touching, UserForces,
};
use crate::resources::{
    AdaptiveSteps, AirSettings, ClothContacts, DivergenceLimit, EditAction, Gravity, HealthReport, IntegratorStats,
    ProbeRequests, Probes, PropWorld, ScheduledEdit, ScheduledEdits, SimClock, SolverSettings, StepSettings,
};
use crate::solver::forces::{Air, Gust};
use crate::solver::implicit::{ImplicitSettings, LinearSolver, Rayleigh};
use crate::solver::integrate::MethodSettings;

/// What a scene builds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneCounts {
    /// How time is cut.
    pub time: TimePlan,
    /// Garment entities.
    pub cloths: usize,
    /// Particles over all cloths.
    pub particles: usize,
    /// Springs over all cloths.
    pub springs: usize,
    /// Triangles over all cloths.
    pub triangles: usize,
    /// Pinned particles over all cloths.
    pub pins: usize,
}

/// Builds the particles, springs and triangles of one cloth; mesh paths are relative to
/// `base_dir`. `index` is the cloth's place in the scene, for error messages.
pub fn build_cloth(desc: &ClothDesc, index: usize, base_dir: &Path) -> Result<ClothData, SceneError> {
    let placement = desc.placement.to_affine();
    let material = desc
        .resolved_material()
        .ok_or_else(|| SceneError::invalid(format!("cloths[{index}]"), "give a material or a fabric"))?;
    let mut data = match &desc.shape {
        ShapeDesc::Grid { size, resolution } => build_grid(*size, *resolution, placement, &material),
        ShapeDesc::Disk { radius, rings } => {
            let mut data = build_from_mesh(&disk_mesh(*radius, *rings), placement, &material, "disk")
                .map_err(|e| SceneError::invalid(format!("cloths[{index}].shape"), e.to_string()))?;
            data.renumber_for_locality();
            data
        }
        ShapeDesc::Mesh { path } => {
            let field = format!("cloths[{index}].shape.path");
            let file = base_dir.join(path);
            let mesh = read_obj(&file).map_err(|e| SceneError::invalid(&field, e.to_string()))?;
            let mut data = build_from_mesh(&mesh, placement, &material, &file.display().to_string())
                .map_err(|e| SceneError::invalid(&field, e.to_string()))?;
            data.renumber_for_locality();
            data
        }
    };
    data.particles.velocity.fill(desc.velocity);
    data.add_surface_elements(&material, desc.placement.warp(desc.grain_deg))
        .map_err(|e| SceneError::invalid(format!("cloths[{index}].material.bending.law"), e))?;
    Ok(data)
}

/// Forces [N] that spread `traction` [N/m] along the polyline of particles `edge` (in
/// order along the edge): each carries half of each rest segment beside it.
fn edge_loads(rest: &[Vec3], edge: &[u32], traction: Vec3) -> Vec<(u32, Vec3)> {
    let segment = |k: usize| (rest[edge[k + 1] as usize] - rest[edge[k] as usize]).length();
    (0..edge.len())
        .map(|k| {
            let before = if k > 0 { segment(k - 1) } else { 0.0 };
            let after = if k + 1 < edge.len() { segment(k) } else { 0.0 };
            (edge[k], 0.5 * (before + after) * traction)
        })
        .collect()
}

/// Spawns the scene's colliders, the ground plane among them.
fn spawn_colliders(world: &mut World, scene: &Scene, base_dir: &Path) -> Result<(), SceneError> {
    if scene.ground.enabled {
        world.spawn(Collider::new(
            "ground".into(),
            ColliderShape::Plane { normal: Vec3::Y }.build(None).expect("a plane always builds"),
            ColliderMotion::Static(Pose { translation: Vec3::new(0.0, scene.ground.height, 0.0), ..Pose::default() }),
            scene.ground.friction,
            0.0,
            ContactResponse::Slide,
        ));
    }
    for (k, desc) in scene.colliders.iter().enumerate() {
        let field = format!("colliders[{k}].shape");
        let mesh = match &desc.shape {
            ColliderShape::Mesh { path } => {
                Some(read_obj(&base_dir.join(path)).map_err(|e| SceneError::invalid(&field, e.to_string()))?)
            }
            _ => None,
        };
        let shape = desc.shape.build(mesh.as_ref()).map_err(|e| SceneError::invalid(&field, e.to_string()))?;
        let motion = if desc.keyframes.is_empty() {
            ColliderMotion::Static(desc.pose)
        } else {
            ColliderMotion::Keyframes(desc.keyframes.clone())
        };
        world.spawn(Collider::new(desc.name.clone(), shape, motion, desc.friction, desc.thickness, desc.response));
    }
    if !scene.props.is_empty() {
        spawn_props(world, scene)?;
    }
    Ok(())
}

/// Spawns the scene's rigid props in a new [`PropWorld`], with a fixed or kinematic
/// stand-in there for every collider so that props land on them.
fn spawn_props(world: &mut World, scene: &Scene) -> Result<(), SceneError> {
    let mut rigid = PhysicsWorld::new();
    let mut colliders = world.query::<(Entity, &Collider)>();
    let stand_ins: Vec<(Entity, Collider)> = colliders.iter(world).map(|(e, c)| (e, c.clone())).collect();
    for (entity, collider) in stand_ins {
        let builder = match &collider.motion {
            ColliderMotion::Keyframes(_) => RigidBodyBuilder::kinematic_position_based(),
            ColliderMotion::Static(_) | ColliderMotion::Driven(_) => RigidBodyBuilder::fixed(),
        };
        let body = rigid.bodies.insert(builder.pose(collider.motion.state_at(0.0).pose).build());
        let shape = ColliderBuilder::new(collider.shape.clone()).friction(collider.friction).build();
        rigid.colliders.insert_with_parent(shape, body, &mut rigid.bodies);
        world.entity_mut(entity).insert(RigidStandIn { body });
    }
    for (k, desc) in scene.props.iter().enumerate() {
        let field = format!("props[{k}].shape");
        let shape = desc.shape.build(None).map_err(|e| SceneError::invalid(&field, e.to_string()))?;
        let mut body =
            RigidBodyBuilder::dynamic().pose(desc.pose.to_pose3()).linvel(desc.velocity).ccd_enabled(true).build();
        body.add_force(desc.force, true);
        let body = rigid.bodies.insert(body);
        let collider = ColliderBuilder::new(shape.clone()).mass(desc.mass).friction(desc.friction).build();
        rigid.colliders.insert_with_parent(collider, body, &mut rigid.bodies);
        world.spawn((
            Collider::new(
                desc.name.clone(),
                shape,
                ColliderMotion::Driven(ColliderState::of_body(&rigid.bodies[body])),
                desc.friction,
                desc.thickness,
                ContactResponse::Slide,
            ),
            Prop { body, coupling: BodyCoupling::default() },
        ));
    }
    world.insert_resource(PropWorld(rigid));
    Ok(())
}

/// Inserts the scene's resources into `world` and spawns its cloths.
pub fn spawn_scene(world: &mut World, scene: &Scene, base_dir: &Path) -> Result<SceneCounts, SceneError> {
    let time = time_plan(scene)?;
    let mut counts = SceneCounts { time, cloths: 0, particles: 0, springs: 0, triangles: 0, pins: 0 };
    for (index, desc) in scene.cloths.iter().enumerate() {
        let data = build_cloth(desc, index, base_dir)?;
        let mut pins = Pins::default();
        for (k, selection) in desc.pins.iter().enumerate() {
            let chosen = selection
                .resolve(&data.particles.position, &data.layout)
                .map_err(|e| SceneError::invalid(format!("cloths[{index}].pins[{k}]"), e.to_string()))?;
            for particle in chosen {
                pins.insert(particle, data.particles.position[particle as usize]);
            }
        }
        let mut grips = Vec::with_capacity(desc.grips.len());
        for (k, grip) in desc.grips.iter().enumerate() {
            let motion = ColliderMotion::Keyframes(grip.keyframes.clone());
            let frame = grip.keyframes[0].1.to_pose3().inverse();
            let mut held = Vec::new();
            for (j, selection) in grip.particles.iter().enumerate() {
                held.extend(selection.resolve(&data.particles.position, &data.layout).map_err(|e| {
                    SceneError::invalid(format!("cloths[{index}].grips[{k}].particles[{j}]"), e.to_string())
                })?);
            }
            held.sort_unstable();
            held.dedup();
            let local = held.iter().map(|&p| frame * data.particles.position[p as usize]).collect();
            for &particle in &held {
                pins.insert(particle, data.particles.position[particle as usize]);
            }
            grips.push(Grip { particles: held, local, motion });
        }
        let count = data.particles.len();
        let mut user_forces = Vec::with_capacity(desc.user_forces.len());
        for (k, force) in desc.user_forces.iter().enumerate() {
            // The same numbering as pins by index: a mesh file's vertex numbers.
            let particle =
                PinSelection::Indices(vec![force.particle]).resolve(&data.particles.position, &data.layout).map_err(
                    |e| SceneError::invalid(format!("cloths[{index}].user_forces[{k}].particle"), e.to_string()),
                )?;
            user_forces.push((particle[0], force.force));
        }
        for (k, traction) in desc.tractions.iter().enumerate() {
            let edge = PinSelection::Edge(traction.edge)
                .resolve(&data.particles.rest_position, &data.layout)
                .map_err(|e| SceneError::invalid(format!("cloths[{index}].tractions[{k}].edge"), e.to_string()))?;
            user_forces.extend(edge_loads(&data.particles.rest_position, &edge, traction.traction));
        }
        let strain_limit = desc.strain_limit.map_or_else(StrainLimit::default, |limit| {
            let (pairs, rest_length) = limited_edges(
                &data.particles.rest_position,
                &data.springs,
                &data.triangles.indices,
                desc.placement.warp(desc.grain_deg),
                limit.edges == LimitedEdgesDesc::Grain,
            );
            StrainLimit { pairs, rest_length, max_strain: limit.max_strain, iterations: limit.iterations }
        });
        let self_collision = desc
            .self_collision()
            .map(|(separation, friction, layer)| {
                let shortest =
                    data.triangles.side_lengths(&data.particles.rest_position).flatten().fold(f32::INFINITY, f32::min);
                if separation <= 0.0 || separation >= 0.5 * shortest {
                    return Err(SceneError::invalid(
                        format!("cloths[{index}].self_collision.separation"),
                        format!(
                            "{separation} m must be above zero and below half the cloth's shortest edge ({shortest} m): \
                             neighbouring triangles of the flat cloth would push each other; give a smaller separation or a \
                             coarser mesh"
                        ),
                    ));
                }
                Ok(SelfCollision { separation, friction, layer })
            })
            .transpose()?;
        counts.cloths += 1;
        counts.particles += count;
        counts.springs += data.springs.len();
        counts.triangles += data.triangles.len();
        counts.pins += pins.len();
        let mut cloth = world.spawn((
            (
                Cloth { name: desc.name.clone(), layout: data.layout, thickness: desc.contact_thickness() },
                desc.resolved_material().expect("build_cloth refused cloths without one"),
                data.particles,
                data.springs,
                data.triangles,
                pins,
                UserForces { forces: user_forces },
            ),
            (
                data.hinges,
                data.membranes,
                Grips(grips),
                strain_limit,
                ContactStats::default(),
                Touching::default(),
                ClothTopology::default(),
                SolverWorkspace::default(),
                RenderMesh::default(),
            ),
        ));
        if let Some(collision) = self_collision {
            cloth.insert(collision);
        }
    }

    world.insert_resource(StepSettings { dt: time.dt, substeps: time.substeps });
    if let Some(motion) = scene.solver.step_motion {
        let least = scene.solver.min_substeps.unwrap_or(1);
        world.insert_resource(AdaptiveSteps { frame_time: 1.0 / time.fps, least, most: time.substeps, motion });
    }
    world.insert_resource(Gravity(scene.gravity));
    world.insert_resource(AirSettings(Air {
        drag: scene.air.drag,
        wind: scene.air.wind,
        wind_drag: scene.air.wind_drag,
        gust: scene.air.gust.map(|g| Gust { amplitude: g.amplitude, period_s: g.period_s }),
        area_damping: scene.air.area_damping,
    }));
    let rayleigh = match scene.solver.rayleigh {
        Some(RayleighDesc::Coefficients { alpha, beta }) => Rayleigh { alpha, beta },
        Some(RayleighDesc::Critical { omega1, omega2 }) => Rayleigh::from_frequencies(omega1, omega2, 1.0),
        None => Rayleigh::default(),
    };
    world.insert_resource(SolverSettings {
        integrator: scene.solver.integrator,
        method: MethodSettings {
            cfl: scene.solver.cfl,
            tolerance: scene.solver.tolerance(),
            implicit: ImplicitSettings {
                theta: scene.solver.theta(),
                rayleigh,
                cg_tolerance: scene.solver.cg_tolerance,
                cg_max_iterations: scene.solver.cg_max_iterations,
                newton_iterations: scene.solver.newton_iterations,
                linear_solver: match scene.solver.preconditioner {
                    Preconditioner::BlockJacobi => LinearSolver::ConjugateGradient,
                    Preconditioner::Multigrid => LinearSolver::Multigrid,
                },
            },
            descent: scene.solver.descent().into(),
        },
    });
    spawn_colliders(world, scene, base_dir)?;
    world.insert_resource(DivergenceLimit { max_strain: scene.divergence.max_strain });
    world.insert_resource(SimClock::default());
    world.insert_resource(HealthReport::default());
    world.insert_resource(Probes::default());
    world.insert_resource(IntegratorStats::default());
    world.insert_resource(ClothContacts::default());
    let mut pending: Vec<ScheduledEdit> = scene
        .edits
        .iter()
        .map(|edit| ScheduledEdit {
            at_s: f64::from(edit.at_s),
            cloth: edit.cloth.clone(),
            action: match &edit.action {
                EditActionDesc::Tear { point, normal, radius } => {
                    EditAction::Tear(Cut { point: *point, normal: *normal, radius: *radius })
                }
                EditActionDesc::Pin(selections) => EditAction::Pin(selections.clone()),
                EditActionDesc::Unpin(selections) => EditAction::Unpin(selections.clone()),
            },
        })
        .collect();
    pending.sort_by(|a, b| a.at_s.total_cmp(&b.at_s));
    world.insert_resource(ScheduledEdits { pending });
    world.insert_resource(ProbeRequests(scene.probes.clone()));
    Ok(counts)
}
