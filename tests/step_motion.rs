//! Frames whose steps follow the motion (`solver.step_motion`): a falling cloth takes as
//! many steps as keep each particle within the limit, up to `substeps`, and still falls
//! as implicit Euler with those steps predicts; a cloth at rest takes one step, unless a
//! collider moves.

mod common;

use selvedge::components::Particles;

const G: f64 = 9.81;
const FPS: f64 = 60.0;

/// A 1 m square of 12 × 12 particles, flat, at rest at height 20 m, whose mean triangle
/// side is `(2 · 1/11 + √2/11) / 3`, under `gravity` [m/s²], with `colliders` (RON).
fn square(gravity: f64, colliders: &str) -> selvedge::Simulation {
    common::simulation(&format!(
        "Scene(name: \"motion\", gravity: (0.0, {}, 0.0),
          solver: (integrator: ImplicitEuler, substeps: 12, step_motion: 0.05), time: (fps: 60, frames: 60),
          cloths: [(name: \"c\", shape: Grid(size: (1.0, 1.0), resolution: (12, 12)),
                    placement: (translation: (0.0, 20.0, 0.0), rotation_deg: (90.0, 0.0, 0.0)),
                    material: {})],
          colliders: [{colliders}])",
        -gravity,
        common::material(200.0, 0.1)
    ))
}

fn mean_edge() -> f64 {
    (2.0 + 2f64.sqrt()) / (3.0 * 11.0)
}

/// The steps each of `frames` frames took.
fn steps_per_frame(sim: &mut selvedge::Simulation, frames: u32) -> Vec<u64> {
    (0..frames)
        .map(|_| {
            let before = sim.clock().step;
            common::run_frames(sim, 1);
            sim.clock().step - before
        })
        .collect()
}

#[test]
fn a_falling_cloth_takes_the_steps_its_speed_needs_and_falls_as_implicit_euler() {
    let mut sim = square(G, "");
    let frames = 30;
    let steps = steps_per_frame(&mut sim, frames);
    for (k, &taken) in steps.iter().enumerate() {
        // Frame k starts at g k / 60 m/s, and moves that far over 1/60 s, in edges.
        let reach = G * k as f64 / FPS / FPS / mean_edge();
        let wanted = (reach / 0.05).ceil().clamp(1.0, 12.0);
        // Rounding may tip a reach on a whole number of limits either way.
        assert!(
            (taken as f64 - wanted).abs() <= 1.0,
            "frame {k}: {taken} steps, the speed asks for {wanted} ({reach} edges)"
        );
    }
    assert_eq!(steps[0], 1, "a cloth at rest starts with one step");
    assert_eq!(steps.last(), Some(&12), "a fast cloth takes every step");
    // Implicit Euler moves each step by h v_{n+1}, g h² / 2 more than the exact fall:
    // over frames of n_k steps of 1/(60 n_k), g / (2 · 60²) · Σ 1 / n_k more.
    let t = f64::from(frames) / FPS;
    let extra = G / (2.0 * FPS * FPS) * steps.iter().map(|&n| 1.0 / n as f64).sum::<f64>();
    let expected = 20.0 - 0.5 * G * t * t - extra;
    let p = sim.world_mut().query::<&Particles>().single(sim.world()).expect("one cloth").clone();
    let mean_y = p.position.iter().map(|x| f64::from(x.y)).sum::<f64>() / p.len() as f64;
    let velocity = p.velocity.iter().map(|v| f64::from(v.y)).sum::<f64>() / p.len() as f64;
    assert!((velocity + G * t).abs() < 1e-3, "v = {velocity} m/s, g t = {}", G * t);
    // With every frame at 12 steps the cloth would be g (30 / 12 − Σ 1/n_k) / 7200 lower.
    assert!((mean_y - expected).abs() < 1e-4, "y = {mean_y} m, implicit Euler with these steps {expected}");
    assert!(sim.clock().time_s > t - 1e-6 && sim.clock().time_s < t + 1e-6, "the clock keeps the frames' time");
}

#[test]
fn a_cloth_at_rest_takes_one_step_a_frame_unless_a_collider_moves() {
    let mut resting = square(0.0, "");
    assert!(steps_per_frame(&mut resting, 5).iter().all(|&n| n == 1), "nothing moves: one step a frame");
    // A sphere 5 m below moving at 0.5 m/s: 0.5/60 m a frame, 0.092 edges, two limits.
    let sphere = "(name: \"ball\", shape: Sphere(radius: 0.1),
                   keyframes: [(0.0, (translation: (0.0, 15.0, 0.0))), (10.0, (translation: (5.0, 15.0, 0.0)))])";
    let mut passing = square(0.0, sphere);
    let wanted = (0.5 / FPS / mean_edge() / 0.05).ceil() as u64;
    assert_eq!(wanted, 2);
    assert!(
        steps_per_frame(&mut passing, 5).iter().all(|&n| n == wanted),
        "a collider moving at 0.5 m/s asks for {wanted} steps a frame"
    );
}

#[test]
fn a_step_motion_beyond_an_edge_or_not_above_zero_is_refused() {
    for (motion, says) in [("0.0", "greater than 0"), ("1.5", "tear")] {
        let text = format!(
            "Scene(name: \"m\", solver: (integrator: ImplicitEuler, substeps: 10, step_motion: {motion}),
              time: (fps: 60, frames: 1),
              cloths: [(name: \"c\", shape: Grid(size: (1.0, 1.0), resolution: (4, 4)), material: {})])",
            common::material(200.0, 0.1)
        );
        let path = std::path::Path::new("motion.ron");
        let error = selvedge::scene::parse_scene(&text, path)
            .and_then(|scene| selvedge::Simulation::new(&scene, std::path::Path::new("scenes")))
            .err()
            .expect("refused")
            .to_string();
        assert!(error.contains("step_motion") && error.contains(says), "{motion}: {error}");
    }
}

/// A self-contact spring restores `SPRING_RECOVERY` = 0.95 of its pair's missing gap in
/// the step it serves, at rest and with no other force: `k h² w / (1 + k h² w)` for the
/// pair's inverse mass `w`. The springs the last step left are made for its length; when
/// the next frame takes another number of steps they must be made over, or a spring made
/// at ten steps a frame serves a frame of one a hundred times too stiff.
#[test]
fn self_contact_springs_are_made_over_when_the_frame_takes_another_number_of_steps() {
    use bevy_ecs::system::RunSystemOnce;
    use selvedge::components::{ClothTopology, SelfTouching};
    use selvedge::resources::StepSettings;
    use selvedge::systems::substeps::plan_frame_steps;

    // The upper layer of layer_slope slides ever faster, so frames take ever more steps.
    let mut sim = common::bundled_with("layer_slope.ron", |scene| {
        scene.solver.substeps = Some(20);
        scene.solver.step_motion = Some(0.02);
    });
    let (mut checked, mut changes) = (0, 0);
    let mut last_dt = sim.world().resource::<StepSettings>().dt;
    for _ in 0..30 {
        sim.world_mut().run_system_once(plan_frame_steps).expect("the planner runs");
        let world = sim.world_mut();
        let h = world.resource::<StepSettings>().dt;
        let (springs, topology) = world.query::<(&SelfTouching, &ClothTopology)>().single(world).expect("one cloth");
        let live: Vec<_> = springs.0.iter().filter(|s| s.stiffness > 0.0).collect();
        changes += usize::from(h != last_dt && !live.is_empty());
        for spring in live {
            let khw = spring.stiffness * h * h * spring.stencil.inverse_mass(&topology.free_inv_mass);
            let recovery = khw / (1.0 + khw);
            assert!((recovery - 0.95).abs() < 1e-4, "a spring restores {recovery} of its gap in a step of {h} s");
            checked += 1;
        }
        last_dt = h;
        sim.step_frame().unwrap_or_else(|e| panic!("{e}"));
    }
    assert!(changes >= 3, "the step changed only {changes} times with springs to make over");
    assert!(checked > 100, "only {checked} springs checked");
}
