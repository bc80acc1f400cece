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
