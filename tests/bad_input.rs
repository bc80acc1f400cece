//! Bad input gets a clear error that names the file, the line and column, and the field.

use std::path::Path;

use selvedge::Simulation;
use selvedge::scene::{SceneError, parse_scene};

const GOOD: &str = r#"Scene(
    name: "good",
    solver: (integrator: SymplecticEuler, substeps: 10),
    time: (fps: 60, frames: 10),
    cloths: [
        (
            name: "sheet",
            shape: Grid(size: (1.0, 1.0), resolution: (8, 8)),
            material: (density: 0.2, stretch: (stiffness: 100.0), shear: (stiffness: 10.0), bend: (stiffness: 1.0)),
            pins: [Indices([0, 7])],
        ),
    ],
)"#;

/// The error for GOOD with `from` replaced by `to`, from parsing or else from building.
fn error(from: &str, to: &str) -> String {
    assert!(GOOD.contains(from), "test bug: {from} is not in the scene");
    let text = GOOD.replacen(from, to, 1);
    let path = Path::new("scenes/broken.ron");
    let result: Result<Simulation, SceneError> = parse_scene(&text, path)
        .and_then(|scene| Simulation::new(&scene, Path::new("scenes")).map_err(|e| e.located(path, &text)));
    match result {
        Ok(_) => panic!("{to} was accepted"),
        Err(e) => e.to_string(),
    }
}

fn assert_mentions(message: &str, parts: &[&str]) {
    for part in parts {
        assert!(message.contains(part), "`{message}` does not mention `{part}`");
    }
}

#[test]
fn the_good_scene_is_good() {
    let scene = parse_scene(GOOD, Path::new("good.ron")).expect("valid");
    Simulation::new(&scene, Path::new("scenes")).expect("builds");
}

#[test]
fn a_syntax_error_names_file_line_and_column() {
    let message = error("time: (fps: 60, frames: 10),", "time: (fps: 60 frames: 10),");
    assert_mentions(&message, &["scenes/broken.ron:4:"]);
}

#[test]
fn an_unknown_field_is_an_error_at_its_place() {
    let message = error("density: 0.2", "densty: 0.2");
    assert_mentions(&message, &["scenes/broken.ron:9:", "densty"]);
}

#[test]
fn an_unknown_integrator_is_named_with_the_known_ones() {
    let message = error("integrator: SymplecticEuler", "integrator: Leapfrog");
    assert_mentions(&message, &["scenes/broken.ron:3:", "Leapfrog", "VelocityVerlet"]);
}

#[test]
fn negative_and_zero_mass_name_the_density_field() {
    for density in ["-0.2", "0.0"] {
        let message = error("density: 0.2", &format!("density: {density}"));
        assert_mentions(&message, &["scenes/broken.ron:9:24", "cloths[0].material.density", "mass"]);
    }
}

#[test]
fn nan_is_refused() {
    let message = error("stiffness: 100.0", "stiffness: NaN");
    assert_mentions(&message, &["cloths[0].material.stretch.stiffness", "not a finite number"]);
}

#[test]
fn a_cfl_limit_without_an_explicit_integrator_is_refused_with_the_default_named() {
    let message = error("integrator: SymplecticEuler, substeps: 10", "substeps: 10, cfl: 0.5");
    assert_mentions(&message, &["scenes/broken.ron:3:", "solver.cfl", "ImplicitEuler", "default", "SymplecticEuler"]);
}

#[test]
fn a_zero_size_cloth_is_refused() {
    let message = error("size: (1.0, 1.0)", "size: (0.0, 1.0)");
    assert_mentions(&message, &["scenes/broken.ron:8:", "cloths[0].shape.size", "greater than 0"]);
}

#[test]
fn a_pin_index_out_of_range_names_the_pin_and_the_range() {
    let message = error("Indices([0, 7])", "Indices([0, 64])");
    assert_mentions(
        &message,
        &["scenes/broken.ron:10:20", "cloths[0].pins[0]", "particle 64 does not exist", "0 to 63"],
    );
}

#[test]
fn a_missing_mesh_file_names_the_field_and_the_file() {
    let message = error("Grid(size: (1.0, 1.0), resolution: (8, 8))", "Mesh(path: \"meshes/nowhere.obj\")");
    assert_mentions(&message, &["scenes/broken.ron:8:", "cloths[0].shape.path", "nowhere.obj"]);
}

#[test]
fn a_step_that_does_not_divide_the_frame_is_refused_with_a_suggestion() {
    let message = error("substeps: 10", "dt: 0.007");
    assert_mentions(&message, &["solver.dt", "does not divide the frame time", "0.0083"]);
}

#[test]
fn an_edit_of_an_unknown_cloth_is_refused() {
    let message =
        error("    ],\n)", "    ],\n    edits: [(at_s: 1.0, cloth: \"shet\", action: Unpin([Indices([0])]))],\n)");
    assert_mentions(&message, &["scenes/broken.ron:13:25", "edits[0].cloth", "no cloth is named `shet`"]);
}

#[test]
fn a_self_collision_separation_as_large_as_the_cells_is_refused_with_the_edge_length() {
    // The 8 × 8 grid over 1 m has edges of 1/7 m; half of that is the largest separation.
    let message = error("pins: [Indices([0, 7])],", "pins: [Indices([0, 7])], self_collision: (separation: 0.1),");
    assert_mentions(&message, &["cloths[0].self_collision.separation", "shortest edge", "0.142"]);
    let message = error("pins: [Indices([0, 7])],", "pins: [Indices([0, 7])], self_collision: (friction: -0.1),");
    assert_mentions(&message, &["cloths[0].self_collision.friction"]);
}

#[test]
fn grip_keyframes_out_of_order_are_refused() {
    let grip = "grips: [(particles: [Indices([0])], keyframes: [(1.0, ()), (0.5, ())])],";
    let message = error("pins: [Indices([0, 7])],", grip);
    assert_mentions(&message, &["cloths[0].grips[0].keyframes", "increase"]);
}

#[test]
fn response_regimes_whose_thresholds_do_not_nest_are_refused() {
    let floor = |regimes: &str| {
        format!(
            "    ],\n    colliders: [(name: \"floor\", shape: Plane(normal: (0.0, 1.0, 0.0)), response: Regimes({regimes}))],\n)"
        )
    };
    let message = error("    ],\n)", &floor("outside: 0.01, surface: 0.02, stiffness: 100.0"));
    assert_mentions(&message, &["colliders[0].response.surface", "T_surface must be below T_outside"]);
    let message = error("    ],\n)", &floor("outside: 0.01, surface: 0.002, stiffness: 100.0, restitution: 1.5"));
    assert_mentions(&message, &["colliders[0].response.restitution", "between 0 and 1"]);
}

#[test]
fn a_prop_that_is_a_plane_or_has_no_mass_is_refused() {
    let prop = |fields: &str| format!("    ],\n    props: [(name: \"p\", {fields})],\n)");
    let message = error("    ],\n)", &prop("shape: Plane(normal: (0.0, 1.0, 0.0)), mass: 1.0"));
    assert_mentions(&message, &["props[0].shape", "bounded solid"]);
    let message = error("    ],\n)", &prop("shape: Sphere(radius: 0.1), mass: 0.0"));
    assert_mentions(&message, &["props[0].mass"]);
    let message = error("    ],\n)", &prop("shape: Sphere(radius: -0.1), mass: 1.0"));
    assert_mentions(&message, &["props[0].shape.radius"]);
}

#[test]
fn block_descent_needs_sweeps_and_a_chebyshev_radius_below_one() {
    let solver = "integrator: SymplecticEuler, substeps: 10)";
    let descent = |settings: &str| format!("integrator: BlockDescent, substeps: 10, descent: ({settings}))");
    let message = error(solver, &descent("sweeps: 0"));
    assert_mentions(&message, &["scenes/broken.ron", "solver.descent.sweeps", "at least 1"]);
    let message = error(solver, &descent("spectral_radius: 1.2"));
    assert_mentions(&message, &["solver.descent.spectral_radius", "outside [0, 1)", "scenes/broken.ron:3:"]);
}

#[test]
fn a_setting_of_another_integrator_is_refused_rather_than_ignored() {
    let solver = "integrator: SymplecticEuler, substeps: 10)";
    // With no integrator given, ImplicitEuler, which has no use for block descent's.
    let message = error(solver, "substeps: 10, descent: (sweeps: 20))");
    assert_mentions(&message, &["scenes/broken.ron:3:", "solver.descent", "ImplicitEuler", "integrator: BlockDescent"]);
    let message = error(solver, "integrator: Newmark, substeps: 10, tolerance: 1e-6)");
    assert_mentions(&message, &["solver.tolerance", "Newmark", "remove tolerance", "integrator: Rk45"]);
    let message = error(solver, "integrator: BlockDescent, substeps: 10, theta: 0.6)");
    assert_mentions(&message, &["solver.theta", "BlockDescent", "integrator: Newmark"]);
}

#[test]
fn quadratic_bending_on_a_curved_rest_shape_is_refused_with_the_linear_law_named() {
    // Two triangles folded 30° along their shared edge, the x axis.
    let obj = std::env::temp_dir().join(format!("selvedge_folded_{}.obj", std::process::id()));
    let folded = "v 0 0 0\nv 1 0 0\nv 0.5 -1 0\nv 0.5 0.8660254 0.5\nf 1 2 3\nf 2 1 4\n";
    std::fs::write(&obj, folded).expect("writes");
    let material =
        "material: (density: 0.2, stretch: (stiffness: 100.0), shear: (stiffness: 10.0), bend: (stiffness: 1.0)),";
    let text = GOOD
        .replacen(
            "Grid(size: (1.0, 1.0), resolution: (8, 8))",
            &format!("Mesh(path: {:?})", obj.display().to_string()),
            1,
        )
        .replacen(
            material,
            "material: (density: 0.2, stretch: (stiffness: 100.0), bending: (warp: 1e-5, weft: 1e-5, law: Quadratic)),",
            1,
        )
        .replacen("pins: [Indices([0, 7])],", "", 1);
    let path = Path::new("scenes/folded.ron");
    let scene = parse_scene(&text, path).expect("parses");
    let built = Simulation::new(&scene, Path::new("scenes")).map_err(|e| e.located(path, &text));
    let message = built.err().expect("refused").to_string();
    std::fs::remove_file(&obj).ok();
    assert_mentions(&message, &["scenes/folded.ron:", "cloths[0].material.bending.law", "30.00°", "law: Linear"]);
}
