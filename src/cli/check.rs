//! `selvedge check SCENE`.

use std::path::Path;

use super::Failure;
use crate::Simulation;
use crate::scene::load_scene;

/// Loads and builds the scene without stepping it, and prints what it builds.
pub(super) fn check(path: &Path) -> Result<(), Failure> {
    let file = load_scene(path).map_err(Failure::bad_input)?;
    let simulation = Simulation::from_file(&file).map_err(Failure::bad_input)?;
    let counts = simulation.counts();
    let time = counts.time;
    println!("{}: scene `{}` is valid", path.display(), file.scene.name);
    println!("  cloths     {}", counts.cloths);
    println!("  particles  {}", counts.particles);
    println!("  springs    {}", counts.springs);
    println!("  triangles  {}", counts.triangles);
    println!("  pins       {}", counts.pins);
    println!(
        "  time       {} frames at {} fps, {} steps of {:.6} s per frame, {}",
        time.frames,
        time.fps,
        time.substeps,
        time.dt,
        file.scene.solver.integrator.name()
    );
    Ok(())
}
