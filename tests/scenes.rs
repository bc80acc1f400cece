//! Every bundled scene parses, builds (what `selvedge check` does) and survives a RON
//! round trip unchanged.

use std::path::{Path, PathBuf};

use glam::Vec3;
use selvedge::Simulation;
use selvedge::components::{Particles, Pins};
use selvedge::scene::load::scene_to_ron;
use selvedge::scene::{load_scene, parse_scene};

fn bundled_scenes() -> Vec<PathBuf> {
    let mut scenes = Vec::new();
    let mut folders = vec![PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes")];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).expect("scenes folder is readable") {
            let path = entry.expect("readable entry").path();
            if path.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|e| e == "ron") {
                scenes.push(path);
            }
        }
    }
    scenes.sort();
    scenes
}

#[test]
fn the_required_scenes_are_bundled() {
    let names: Vec<String> =
        bundled_scenes().iter().map(|p| p.file_name().expect("a file").to_string_lossy().into_owned()).collect();
    let bench = ["hang_32.ron", "hang_64.ron", "hang_128.ron", "hang_256.ron", "sphere_64.ron", "fold_64.ron"];
    for required in ["hang.ron", "flag.ron", "free_fall.ron"].into_iter().chain(bench) {
        assert!(names.iter().any(|n| n == required), "scenes/{required} is missing; found {names:?}");
    }
}

#[test]
fn every_bundled_scene_parses_builds_and_round_trips() {
    for path in bundled_scenes() {
        let file = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
        let simulation = Simulation::from_file(&file).unwrap_or_else(|e| panic!("{e}"));
        assert!(simulation.counts().particles > 0, "{} builds no particles", path.display());
        let text = scene_to_ron(&file.scene);
        let again = parse_scene(&text, Path::new("round-trip.ron"))
            .unwrap_or_else(|e| panic!("{}: {e}\n{text}", path.display()));
        assert_eq!(again, file.scene, "{} changes in a RON round trip", path.display());
    }
}

#[test]
fn every_bundled_scene_runs_its_first_frames_without_diverging() {
    for path in bundled_scenes() {
        let file = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
        let mut simulation = Simulation::from_file(&file).unwrap_or_else(|e| panic!("{e}"));
        for _ in 0..5 {
            simulation.step_frame().unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        }
    }
}

#[test]
fn the_hang_bench_scenes_are_built_as_issue_5_defines_them() {
    // A 1 m square of N × N particles flat at y = 1 m, x ∈ [−0.5, 0.5], z ∈ [0, 1], held
    // by the two corners on the edge z = 0, with 0.2 kg/m² of mass.
    for n in [32, 64, 128, 256] {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/bench/hang_{n}.ron"));
        let file = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
        let mut simulation = Simulation::from_file(&file).unwrap_or_else(|e| panic!("{e}"));
        let world = simulation.world_mut();
        let (particles, pins) =
            world.query::<(&Particles, &Pins)>().single(world).unwrap_or_else(|e| panic!("one cloth: {e}"));
        assert_eq!(particles.len(), n * n);
        let (min, max) = particles.position.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        assert!(min.abs_diff_eq(Vec3::new(-0.5, 1.0, 0.0), 1e-5) && max.abs_diff_eq(Vec3::new(0.5, 1.0, 1.0), 1e-5));
        let mass: f64 = particles.inv_mass.iter().map(|w| 1.0 / f64::from(*w)).sum();
        assert!((mass - 0.2).abs() < 1e-6, "hang_{n} weighs {mass} kg");
        let mut held = pins.targets.clone();
        held.sort_by(|a, b| a.x.total_cmp(&b.x));
        assert_eq!(held.len(), 2);
        assert!(
            held[0].abs_diff_eq(Vec3::new(-0.5, 1.0, 0.0), 1e-5) && held[1].abs_diff_eq(Vec3::new(0.5, 1.0, 0.0), 1e-5)
        );
    }
}
