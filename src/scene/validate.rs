//! Checks of a parsed scene's physics and logic. Each failure names the field and says
//! what would be accepted. Checks that need the built cloth (pin indices against the
//! particle count, mesh files) happen when the scene is built.

use glam::Vec3;

use super::format::{DEFAULT_SUBSTEPS, EditActionDesc, RayleighDesc, Scene, ShapeDesc};
use super::load::SceneError;
use crate::builders::pins::PinSelection;
use crate::collision::collider::{ColliderShape, ContactResponse, Pose, Regimes};
use crate::components::{BendingLawDesc, MembraneDesc};
use crate::fabrics::{BendingMeasurement, FabricDesc};
use crate::solver::integrate::Integrator;
use crate::solver::probes::ClothProbe;

/// How a scene's time is cut into frames and steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimePlan {
    /// Frames per second [1/s].
    pub fps: f32,
    /// Step length [s].
    pub dt: f32,
    /// Steps per frame.
    pub substeps: u32,
    /// Frames in the run.
    pub frames: u32,
}

/// Relative mismatch tolerated between a given `dt` and the frame time it must divide.
const DT_MATCH: f32 = 1e-3;

/// Derives the frame count and step of `scene`.
pub fn time_plan(scene: &Scene) -> Result<TimePlan, SceneError> {
    let fps = positive("time.fps", scene.time.fps)?;
    let frame_time = 1.0 / fps;
    let substeps = match (scene.solver.dt, scene.solver.substeps) {
        (_, Some(0)) => return Err(SceneError::invalid("solver.substeps", "must be at least 1")),
        (None, Some(n)) => n,
        (None, None) => DEFAULT_SUBSTEPS,
        (Some(dt), given) => {
            let dt = positive("solver.dt", dt)?;
            let n = (frame_time / dt).round().max(1.0);
            let fits = ((frame_time / n) - dt).abs() <= DT_MATCH * dt;
            match given {
                Some(s) if s as f32 != n || !fits => {
                    return Err(SceneError::invalid(
                        "solver.dt",
                        format!(
                            "{dt} s does not agree with substeps = {s} at {fps} fps (1 / (fps · substeps) = {} s); give one of them",
                            frame_time / s as f32
                        ),
                    ));
                }
                _ if !fits => {
                    return Err(SceneError::invalid(
                        "solver.dt",
                        format!(
                            "{dt} s does not divide the frame time 1/{fps} s; use 1/({fps} · n) s, for example {} s",
                            frame_time / n
                        ),
                    ));
                }
                _ => n as u32,
            }
        }
    };
    let frames = match (scene.time.duration_s, scene.time.frames) {
        (Some(_), Some(_)) => {
            return Err(SceneError::invalid("time.frames", "give either duration_s or frames, not both"));
        }
        (None, None) => {
            return Err(SceneError::invalid("time", "give the length of the run as duration_s or frames"));
        }
        (Some(duration), None) => (positive("time.duration_s", duration)? * fps).round().max(1.0) as u32,
        (None, Some(0)) => return Err(SceneError::invalid("time.frames", "must be at least 1")),
        (None, Some(frames)) => frames,
    };
    Ok(TimePlan { fps, dt: frame_time / substeps as f32, substeps, frames })
}

/// Checks everything about `scene` that can be checked without building it.
pub fn validate(scene: &Scene) -> Result<(), SceneError> {
    if scene.name.is_empty()
        || !scene.name.chars().all(|c| c.is_alphanumeric() || "-_.".contains(c))
        || scene.name.starts_with('.')
    {
        return Err(SceneError::invalid(
            "name",
            "must be a non-empty file name of letters, digits, '-', '_' and '.' (it names the output folder)",
        ));
    }
    finite_vec("gravity", scene.gravity)?;
    non_negative("air.drag", scene.air.drag)?;
    finite_vec("air.wind", scene.air.wind)?;
    non_negative("air.wind_drag", scene.air.wind_drag)?;
    if let Some(gust) = scene.air.gust {
        finite("air.gust.amplitude", gust.amplitude)?;
        positive("air.gust.period_s", gust.period_s)?;
    }
    non_negative("air.area_damping", scene.air.area_damping)?;
    let integrator = scene.solver.integrator;
    only_with("solver.theta", scene.solver.theta.is_some(), integrator, Integrator::Newmark, "Newmark's θ")?;
    only_with(
        "solver.tolerance",
        scene.solver.tolerance.is_some(),
        integrator,
        Integrator::Rk45,
        "Rk45's error tolerance",
    )?;
    only_with(
        "solver.descent",
        scene.solver.descent.is_some(),
        integrator,
        Integrator::BlockDescent,
        "how BlockDescent solves a step",
    )?;
    let theta = finite("solver.theta", scene.solver.theta())?;
    if !(0.5..=1.0).contains(&theta) {
        return Err(SceneError::invalid(
            "solver.theta",
            format!("{theta} is outside [0.5, 1], where the θ-method is stable"),
        ));
    }
    match scene.solver.rayleigh {
        Some(RayleighDesc::Coefficients { alpha, beta }) => {
            non_negative("solver.rayleigh.alpha", alpha)?;
            non_negative("solver.rayleigh.beta", beta)?;
        }
        Some(RayleighDesc::Critical { omega1, omega2 }) => {
            positive("solver.rayleigh.omega1", omega1)?;
            positive("solver.rayleigh.omega2", omega2)?;
        }
        None => {}
    }
    let cg = positive("solver.cg_tolerance", scene.solver.cg_tolerance)?;
    if scene.solver.newton_iterations == 0 {
        return Err(SceneError::invalid("solver.newton_iterations", "must be at least 1"));
    }
    if cg >= 1.0 || scene.solver.cg_max_iterations == 0 {
        return Err(SceneError::invalid("solver.cg_tolerance", "needs a tolerance below 1 and at least one iteration"));
    }
    let descent = scene.solver.descent();
    if descent.sweeps == 0 {
        return Err(SceneError::invalid("solver.descent.sweeps", "must be at least 1"));
    }
    let radius = finite("solver.descent.spectral_radius", descent.spectral_radius)?;
    if !(0.0..1.0).contains(&radius) {
        return Err(SceneError::invalid(
            "solver.descent.spectral_radius",
            format!("{radius} is outside [0, 1); the default is 0.98, 0 turns Chebyshev off"),
        ));
    }
    if let Some(alpha) = scene.solver.cfl {
        if integrator.is_implicit() {
            // A scene written when the default was explicit would otherwise lose its
            // limit without a word.
            return Err(SceneError::invalid(
                "solver.cfl",
                format!(
                    "splits the steps of explicit methods, and {} (the default when no integrator is given) is \
                     implicit: remove cfl, or give an explicit integrator such as SymplecticEuler",
                    integrator.name()
                ),
            ));
        }
        if positive("solver.cfl", alpha)? > 1.0 {
            return Err(SceneError::invalid(
                "solver.cfl",
                format!("{alpha} is above 1; the CFL limit needs α ≤ 1 (0.5 is safe)"),
            ));
        }
    }
    if let Some(motion) = scene.solver.step_motion
        && positive("solver.step_motion", motion)? > 1.0
    {
        return Err(SceneError::invalid(
            "solver.step_motion",
            format!("{motion} edges a step lets a landing cloth tear (0.45 tore sphere_64's); give 0.25 or less"),
        ));
    }
    let tolerance = positive("solver.tolerance", scene.solver.tolerance())?;
    if tolerance >= 1.0 {
        return Err(SceneError::invalid(
            "solver.tolerance",
            format!("{tolerance} is a relative error and must be below 1, typically 1e-6 to 1e-3"),
        ));
    }
    let time = time_plan(scene)?;
    if let Some(least) = scene.solver.min_substeps {
        if scene.solver.step_motion.is_none() {
            return Err(SceneError::invalid(
                "solver.min_substeps",
                "bounds the steps that step_motion chooses, and without step_motion every frame takes all its \
                 substeps: remove min_substeps, or give step_motion (0.25, say)",
            ));
        }
        if least == 0 || least > time.substeps {
            return Err(SceneError::invalid(
                "solver.min_substeps",
                format!("{least} is outside 1 to {}, the steps a frame may take (substeps)", time.substeps),
            ));
        }
    }

    if scene.cloths.is_empty() {
        return Err(SceneError::invalid("cloths", "a scene needs at least one cloth"));
    }
    for (index, cloth) in scene.cloths.iter().enumerate() {
        let field = |name: &str| format!("cloths[{index}].{name}");
        if cloth.name.is_empty() {
            return Err(SceneError::invalid(field("name"), "must not be empty"));
        }
        if scene.cloths[..index].iter().any(|other| other.name == cloth.name) {
            return Err(SceneError::invalid(
                field("name"),
                format!("`{}` names two cloths; names must be unique", cloth.name),
            ));
        }
        match &cloth.shape {
            ShapeDesc::Grid { size, resolution } => {
                positive(&field("shape.size"), size.0)?;
                positive(&field("shape.size"), size.1)?;
                if resolution.0 < 2 || resolution.1 < 2 {
                    return Err(SceneError::invalid(
                        field("shape.resolution"),
                        "a grid needs at least 2 × 2 particles",
                    ));
                }
            }
            ShapeDesc::Disk { radius, rings } => {
                positive(&field("shape.radius"), *radius)?;
                if *rings == 0 {
                    return Err(SceneError::invalid(field("shape.rings"), "a disk needs at least one ring"));
                }
            }
            ShapeDesc::Mesh { path } => {
                if path.is_empty() {
                    return Err(SceneError::invalid(field("shape.path"), "must name an OBJ file"));
                }
            }
        }
        finite_vec(&field("placement.translation"), cloth.placement.translation)?;
        finite_vec(&field("placement.rotation_deg"), cloth.placement.rotation_deg)?;
        positive(&field("placement.scale"), cloth.placement.scale)?;
        let material = &match (&cloth.material, &cloth.fabric) {
            (Some(material), None) => *material,
            (None, Some(fabric)) => {
                check_fabric(&field("fabric"), fabric)?;
                fabric.measurements().material()
            }
            (Some(_), Some(_)) => {
                return Err(SceneError::invalid(field("fabric"), "give a material or a fabric, not both"));
            }
            (None, None) => {
                return Err(SceneError::invalid(
                    field("material"),
                    "give a material (elements) or a fabric (library or measured)",
                ));
            }
        };
        positive(&field("material.density"), material.density).map_err(|_| {
            SceneError::invalid(field("material.density"), format!("{} kg/m² would give particles no or negative mass; areal densities of fabric are about 0.05 to 0.5 kg/m²", material.density))
        })?;
        for (family, c) in [("stretch", material.stretch), ("shear", material.shear), ("bend", material.bend)] {
            if let Some(c) = c {
                non_negative(&field(&format!("material.{family}.stiffness")), c.stiffness)?;
                non_negative(&field(&format!("material.{family}.damping")), c.damping)?;
            }
        }
        if material.stretch.is_none() && material.membrane.is_none() {
            return Err(SceneError::invalid(
                field("material"),
                "the cloth resists no stretching: give stretch springs or a membrane",
            ));
        }
        match material.membrane {
            Some(MembraneDesc::Anisotropic { d1, d2, d3, d4 }) => {
                positive(&field("material.membrane.d1"), d1)?;
                positive(&field("material.membrane.d2"), d2)?;
                finite(&field("material.membrane.d3"), d3)?;
                positive(&field("material.membrane.d4"), d4)?;
                if d3 * d3 >= d1 * d2 {
                    return Err(SceneError::invalid(
                        field("material.membrane.d3"),
                        format!("d3² must be below d1·d2 ({}) for the membrane to be stable", d1 * d2),
                    ));
                }
            }
            Some(MembraneDesc::Isotropic { young, poisson }) => {
                positive(&field("material.membrane.young"), young)?;
                let poisson = non_negative(&field("material.membrane.poisson"), poisson)?;
                if poisson >= 0.5 {
                    return Err(SceneError::invalid(field("material.membrane.poisson"), "must be below 0.5"));
                }
            }
            None => {}
        }
        if let Some(bending) = material.bending {
            non_negative(&field("material.bending.warp"), bending.warp)?;
            non_negative(&field("material.bending.weft"), bending.weft)?;
            if let BendingLawDesc::Zheng { kappa0 } = bending.law {
                positive(&field("material.bending.law.kappa0"), kappa0)?;
            }
        }
        finite(&field("grain_deg"), cloth.grain_deg)?;
        finite_vec(&field("velocity"), cloth.velocity)?;
        if let Some(thickness) = cloth.thickness {
            non_negative(&field("thickness"), thickness)?;
        }
        for (k, grip) in cloth.grips.iter().enumerate() {
            let at = |name: &str| field(&format!("grips[{k}].{name}"));
            if grip.keyframes.is_empty() {
                return Err(SceneError::invalid(at("keyframes"), "a grip needs at least one keyframe"));
            }
            check_keyframes(&at("keyframes"), &grip.keyframes)?;
        }
        if let Some(collision) = cloth.self_collision {
            if let Some(separation) = collision.separation {
                positive(&field("self_collision.separation"), separation)?;
            }
            if let Some(friction) = collision.friction {
                non_negative(&field("self_collision.friction"), friction)?;
            }
        }
        if let Some(limit) = cloth.strain_limit {
            positive(&field("strain_limit.max_strain"), limit.max_strain)?;
            if limit.iterations == 0 {
                return Err(SceneError::invalid(field("strain_limit.iterations"), "must be at least 1"));
            }
        }
        for (k, traction) in cloth.tractions.iter().enumerate() {
            finite_vec(&field(&format!("tractions[{k}].traction")), traction.traction)?;
        }
        for (k, force) in cloth.user_forces.iter().enumerate() {
            finite_vec(&field(&format!("user_forces[{k}].force")), force.force)?;
        }
        for (k, pin) in cloth.pins.iter().enumerate() {
            check_selection(&field(&format!("pins[{k}]")), pin)?;
        }
    }

    for (k, collider) in scene.colliders.iter().enumerate() {
        let field = |name: &str| format!("colliders[{k}].{name}");
        if collider.name.is_empty() || scene.colliders[..k].iter().any(|c| c.name == collider.name) {
            return Err(SceneError::invalid(field("name"), "collider names must be unique and not empty"));
        }
        non_negative(&field("friction"), collider.friction)?;
        non_negative(&field("thickness"), collider.thickness)?;
        check_pose(&field("pose"), &collider.pose)?;
        check_keyframes(&field("keyframes"), &collider.keyframes)?;
        if let ContactResponse::Regimes(regimes) = &collider.response {
            check_regimes(&field("response"), regimes)?;
        }
        check_shape(&field("shape"), &collider.shape)?;
    }
    for (k, prop) in scene.props.iter().enumerate() {
        let field = |name: &str| format!("props[{k}].{name}");
        let taken = scene.colliders.iter().map(|c| &c.name).chain(scene.props[..k].iter().map(|p| &p.name));
        if prop.name.is_empty() || taken.into_iter().any(|name| *name == prop.name) {
            return Err(SceneError::invalid(field("name"), "prop names must be unique among colliders and props"));
        }
        if matches!(prop.shape, ColliderShape::Plane { .. } | ColliderShape::Mesh { .. }) {
            return Err(SceneError::invalid(
                field("shape"),
                "a prop must be a bounded solid: a Sphere, Capsule, Cuboid, Cylinder or ConvexHull",
            ));
        }
        check_shape(&field("shape"), &prop.shape)?;
        positive(&field("mass"), prop.mass)?;
        non_negative(&field("friction"), prop.friction)?;
        non_negative(&field("thickness"), prop.thickness)?;
        check_pose(&field("pose"), &prop.pose)?;
        finite_vec(&field("velocity"), prop.velocity)?;
        finite_vec(&field("force"), prop.force)?;
    }
    finite("ground.height", scene.ground.height)?;
    non_negative("ground.friction", scene.ground.friction)?;
    if scene.output.every == 0 {
        return Err(SceneError::invalid("output.every", "must be at least 1 (1 writes every frame)"));
    }
    positive("divergence.max_strain", scene.divergence.max_strain)?;

    for (k, probe) in scene.probes.iter().enumerate() {
        let field = |name: &str| format!("probes[{k}].{name}");
        if !scene.cloths.iter().any(|c| c.name == probe.cloth()) {
            return Err(SceneError::invalid(field("cloth"), format!("no cloth is named `{}`", probe.cloth())));
        }
        match probe {
            ClothProbe::CantileverAngle { edge, direction, .. } => {
                finite_vec(&field("edge"), *edge)?;
                nonzero_vec(&field("direction"), *direction)?;
            }
            ClothProbe::DrapeCoefficient { pedestal_radius, specimen_radius, .. } => {
                positive(&field("pedestal_radius"), *pedestal_radius)?;
                if positive(&field("specimen_radius"), *specimen_radius)? <= *pedestal_radius {
                    return Err(SceneError::invalid(
                        field("specimen_radius"),
                        "must be larger than the pedestal radius",
                    ));
                }
            }
            ClothProbe::MeanStress { direction, .. } => {
                nonzero_vec(&field("direction"), *direction)?;
            }
        }
    }
    for (k, edit) in scene.edits.iter().enumerate() {
        let field = |name: &str| format!("edits[{k}].{name}");
        non_negative(&field("at_s"), edit.at_s)?;
        if !scene.cloths.iter().any(|c| c.name == edit.cloth) {
            return Err(SceneError::invalid(field("cloth"), format!("no cloth is named `{}`", edit.cloth)));
        }
        match &edit.action {
            EditActionDesc::Tear { point, normal, radius } => {
                finite_vec(&field("action.point"), *point)?;
                nonzero_vec(&field("action.normal"), *normal)?;
                if let Some(radius) = radius {
                    positive(&field("action.radius"), *radius)?;
                }
            }
            EditActionDesc::Pin(selections) | EditActionDesc::Unpin(selections) => {
                for (s, selection) in selections.iter().enumerate() {
                    check_selection(&field(&format!("action[{s}]")), selection)?;
                }
            }
        }
    }
    Ok(())
}

fn check_fabric(field: &str, fabric: &FabricDesc) -> Result<(), SceneError> {
    let FabricDesc::Measured(m) = fabric else { return Ok(()) };
    let at = |name: &str| format!("{field}.{name}");
    positive(&at("areal_density"), m.areal_density)?;
    non_negative(&at("thickness"), m.thickness)?;
    match m.bending {
        BendingMeasurement::Rigidity { warp, weft } => {
            non_negative(&at("bending.warp"), warp)?;
            non_negative(&at("bending.weft"), weft)?;
        }
        BendingMeasurement::BendingLength { warp, weft } => {
            positive(&at("bending.warp"), warp)?;
            positive(&at("bending.weft"), weft)?;
        }
    }
    for (name, value) in [("tensile_warp", m.tensile_warp), ("tensile_weft", m.tensile_weft), ("shear", m.shear)] {
        if let Some(value) = value {
            positive(&at(name), value)?;
        }
    }
    if let Some(nu) = m.poisson
        && !(0.0..0.5).contains(&nu)
    {
        return Err(SceneError::invalid(at("poisson"), format!("{nu} is outside [0, 0.5)")));
    }
    Ok(())
}

/// A shape's dimensions must be positive and finite.
fn check_shape(field: &str, shape: &ColliderShape) -> Result<(), SceneError> {
    let field = |name: &str| format!("{field}.{name}");
    match shape {
        ColliderShape::Plane { normal } => {
            nonzero_vec(&field("normal"), *normal)?;
        }
        ColliderShape::Sphere { radius } => {
            positive(&field("radius"), *radius)?;
        }
        ColliderShape::Capsule { half_height, radius } | ColliderShape::Cylinder { half_height, radius } => {
            positive(&field("half_height"), *half_height)?;
            positive(&field("radius"), *radius)?;
        }
        ColliderShape::Cuboid { half_extents } => {
            if !(finite_vec(&field("half_extents"), *half_extents)?.cmpgt(Vec3::ZERO).all()) {
                return Err(SceneError::invalid(field("half_extents"), "every half extent must be positive"));
            }
        }
        ColliderShape::ConvexHull { points } => {
            for point in points {
                finite_vec(&field("points"), *point)?;
            }
        }
        ColliderShape::Mesh { path } => {
            if path.is_empty() {
                return Err(SceneError::invalid(field("path"), "must name an OBJ file"));
            }
        }
    }
    Ok(())
}

/// Durupınar's thresholds must nest (0 ≤ T_surface < T_outside) and the corrections must
/// not add energy.
fn check_regimes(field: &str, regimes: &Regimes) -> Result<(), SceneError> {
    let at = |name: &str| format!("{field}.{name}");
    positive(&at("outside"), regimes.outside)?;
    if non_negative(&at("surface"), regimes.surface)? >= regimes.outside {
        return Err(SceneError::invalid(at("surface"), "T_surface must be below T_outside"));
    }
    non_negative(&at("stiffness"), regimes.stiffness)?;
    non_negative(&at("damping"), regimes.damping)?;
    for (name, value) in [("tangential", regimes.tangential), ("restitution", regimes.restitution)] {
        if !(0.0..=1.0).contains(&non_negative(&at(name), value)?) {
            return Err(SceneError::invalid(at(name), "must be a fraction between 0 and 1"));
        }
    }
    Ok(())
}

fn check_selection(field: &str, selection: &PinSelection) -> Result<(), SceneError> {
    if let PinSelection::WithinRadius { centre, radius } = selection {
        finite_vec(field, *centre)?;
        positive(field, *radius)?;
    }
    if let PinSelection::InBox { min, max } = selection {
        finite_vec(field, *min)?;
        finite_vec(field, *max)?;
        if !min.cmple(*max).all() {
            return Err(SceneError::invalid(field, format!("box min {min} must be below max {max} on every axis")));
        }
    }
    Ok(())
}

/// Refuses a setting `given` for one integrator, `owner`, while the scene's is another,
/// which would ignore it without a word: a scene switched from `Rk45` to `ImplicitEuler`
/// would keep a tolerance that no longer controls anything.
fn only_with(
    field: &str,
    given: bool,
    integrator: Integrator,
    owner: Integrator,
    what: &str,
) -> Result<(), SceneError> {
    if !given || integrator == owner {
        return Ok(());
    }
    let name = field.rsplit('.').next().unwrap_or(field);
    Err(SceneError::invalid(
        field,
        format!(
            "is {what}, which the scene's integrator, {} (the default when none is given), ignores: remove {name}, \
             or give integrator: {}",
            integrator.name(),
            owner.name()
        ),
    ))
}

fn finite(field: &str, value: f32) -> Result<f32, SceneError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(SceneError::invalid(field, format!("{value} is not a finite number")))
    }
}

fn positive(field: &str, value: f32) -> Result<f32, SceneError> {
    if finite(field, value)? > 0.0 {
        Ok(value)
    } else {
        Err(SceneError::invalid(field, format!("must be greater than 0, got {value}")))
    }
}

fn non_negative(field: &str, value: f32) -> Result<f32, SceneError> {
    if finite(field, value)? >= 0.0 {
        Ok(value)
    } else {
        Err(SceneError::invalid(field, format!("must not be negative, got {value}")))
    }
}

fn nonzero_vec(field: &str, value: Vec3) -> Result<Vec3, SceneError> {
    if finite_vec(field, value)? == Vec3::ZERO {
        return Err(SceneError::invalid(field, "must not be zero"));
    }
    Ok(value)
}

/// A pose with finite translation and angles.
fn check_pose(field: &str, pose: &Pose) -> Result<(), SceneError> {
    finite_vec(field, pose.translation)?;
    finite_vec(field, pose.rotation_deg)?;
    Ok(())
}

/// Keyframes `(time, pose)` of a collider or a grip: finite poses at finite times that
/// increase.
fn check_keyframes(field: &str, keyframes: &[(f32, Pose)]) -> Result<(), SceneError> {
    for (j, (_, pose)) in keyframes.iter().enumerate() {
        check_pose(&format!("{field}[{j}]"), pose)?;
    }
    if keyframes.windows(2).any(|w| w[1].0 <= w[0].0) || keyframes.iter().any(|k| !k.0.is_finite()) {
        return Err(SceneError::invalid(field, "keyframe times must be finite and increase"));
    }
    Ok(())
}

fn finite_vec(field: &str, value: Vec3) -> Result<Vec3, SceneError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(SceneError::invalid(field, format!("{value} has a non-finite component")))
    }
}
