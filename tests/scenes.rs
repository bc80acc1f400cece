//! Every bundled scene parses, builds (what `selvedge check` does) and survives a RON
//! round trip unchanged.

use std::path::{Path, PathBuf};

use selvedge::Simulation;
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
    for required in ["hang.ron", "flag.ron", "free_fall.ron"] {
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
