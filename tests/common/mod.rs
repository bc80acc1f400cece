//! Helpers shared by the integration tests.
#![allow(dead_code, reason = "each test binary uses a different subset")]

use std::path::Path;

use selvedge::Simulation;
use selvedge::scene::{Scene, parse_scene};

/// Parses and validates scene text.
pub fn scene(text: &str) -> Scene {
    parse_scene(text, Path::new("test.ron")).unwrap_or_else(|e| panic!("test scene is invalid: {e}"))
}

/// Builds a simulation from scene text.
pub fn simulation(text: &str) -> Simulation {
    Simulation::new(&scene(text), Path::new("scenes")).unwrap_or_else(|e| panic!("test scene does not build: {e}"))
}

/// Steps `frames` frames, panicking on divergence.
pub fn run_frames(simulation: &mut Simulation, frames: u32) {
    for _ in 0..frames {
        simulation.step_frame().unwrap_or_else(|e| panic!("{e}"));
    }
}

/// Runs `work` on a thread pool of its own with `threads` threads, so that everything it
/// steps runs on that many.
pub fn on_threads<T: Send>(threads: usize, work: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a thread pool").install(work)
}

/// The value of a probe after the last frame.
pub fn probe(simulation: &Simulation, name: &str) -> f64 {
    simulation.probes().get(name).unwrap_or_else(|| panic!("no probe {name}"))
}

/// A cotton-like test material with the given stretch stiffness [N/m] and damping.
pub fn material(stiffness: f32, damping: f32) -> String {
    format!(
        "(density: 0.2, stretch: (stiffness: {stiffness}, damping: {damping}), \
         shear: (stiffness: {}, damping: {}), bend: (stiffness: {}, damping: {}))",
        stiffness / 10.0,
        damping / 10.0,
        stiffness / 100.0,
        damping / 100.0
    )
}
pub mod oscillator;

/// A 1 m square of 12 × 12 particles, flat, at rest at height 20 m, under `gravity`
/// [m/s²], with `colliders` (RON), a ground at `ground` [m] if given, colliding with itself
/// if `self_colliding`; its frames take the steps the motion needs, up to 12
/// (`step_motion: 0.05`).
pub fn square_scene(gravity: f64, colliders: &str, ground: Option<f64>, self_colliding: bool) -> String {
    let ground = ground.map_or(String::new(), |height| format!("ground: (enabled: true, height: {height}),"));
    let self_collision = if self_colliding { "self_collision: (separation: 0.002)," } else { "" };
    format!(
        "Scene(name: \"motion\", gravity: (0.0, {}, 0.0),
          solver: (integrator: ImplicitEuler, substeps: 12, step_motion: 0.05), time: (fps: 60, frames: 60),
          cloths: [(name: \"c\", shape: Grid(size: (1.0, 1.0), resolution: (12, 12)),
                    placement: (translation: (0.0, 20.0, 0.0), rotation_deg: (90.0, 0.0, 0.0)),
                    {self_collision} material: {})],
          colliders: [{colliders}], {ground})",
        -gravity,
        material(200.0, 0.1)
    )
}

/// Builds the bundled scene `scenes/<name>`.
pub fn bundled(name: &str) -> Simulation {
    bundled_with(name, |_| {})
}

/// Builds the bundled scene `scenes/<name>` after `edit` has changed it.
pub fn bundled_with(name: &str, edit: impl FnOnce(&mut Scene)) -> Simulation {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
    let mut file = selvedge::scene::load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    edit(&mut file.scene);
    Simulation::from_file(&file).unwrap_or_else(|e| panic!("{e}"))
}

/// Pairs of a cloth triangle and a face of the polyhedral collider `name` (cuboid or
/// convex hull) that cross, where the collider is now: the exact triangle test, so a
/// cloth edge cutting across the body's edge counts even with every cloth vertex outside.
pub fn body_crossings(simulation: &mut Simulation, name: &str) -> usize {
    use selvedge::collision::intersection::triangles_intersect;
    use selvedge::components::{Collider, Particles, Triangles};
    use selvedge::resources::SimClock;

    let time = simulation.world().resource::<SimClock>().time_s as f32;
    let world = simulation.world_mut();
    let collider = world
        .query::<&Collider>()
        .iter(world)
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no collider {name}"))
        .clone();
    let (points, faces) = if let Some(cuboid) = collider.shape.as_cuboid() {
        cuboid.to_trimesh()
    } else {
        collider.shape.as_convex_polyhedron().expect("a cuboid or a convex hull").to_trimesh()
    };
    let pose = collider.motion.state_at(time).pose;
    let points: Vec<_> = points.iter().map(|&p| pose.transform_point(p).as_dvec3()).collect();
    let mut crossings = 0;
    for (particles, triangles) in world.query::<(&Particles, &Triangles)>().iter(world) {
        for t in &triangles.indices {
            let cloth = t.map(|k| particles.position[k as usize].as_dvec3());
            crossings += faces.iter().filter(|f| triangles_intersect(cloth, f.map(|k| points[k as usize]))).count();
        }
    }
    crossings
}
