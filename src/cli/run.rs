//! `selvedge run SCENE`.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use indicatif::{ProgressBar, ProgressStyle};

use super::{EXIT_DIVERGED, Failure};
use crate::Simulation;
use crate::io::frames::write_frame;
use crate::io::report::{ProbeTable, Summary, write_json};
use crate::scene::load_scene;

/// Runs the scene at `path`, writing frames, the summary and the probe table.
pub(super) fn run(path: &Path, out: Option<PathBuf>, frames: Option<u32>, quiet: bool) -> Result<(), Failure> {
    let file = load_scene(path).map_err(Failure::bad_input)?;
    let scene = &file.scene;
    let mut simulation = Simulation::from_file(&file).map_err(Failure::bad_input)?;
    let counts = simulation.counts();
    let frame_count = u64::from(frames.unwrap_or(counts.time.frames));
    if frame_count == 0 {
        return Err(Failure::bad_input("--frames must be at least 1"));
    }

    let dir = out
        .or_else(|| scene.output.directory.as_ref().map(PathBuf::from))
        .unwrap_or_else(|| Path::new("out").join(&scene.name));
    let frames_dir = dir.join("frames");
    prepare_frames_dir(&frames_dir).map_err(|e| Failure::io(format!("cannot prepare {}", frames_dir.display()), e))?;
    let formats = &scene.output.formats;
    let write = |simulation: &mut Simulation, frame: u64| {
        write_frame(&frames_dir, frame, formats, &simulation.surfaces())
            .map_err(|e| Failure::io(format!("cannot write frame {frame} into {}", frames_dir.display()), e))
    };
    write(&mut simulation, 0)?;

    let progress = Progress::new(frame_count, quiet);
    let mut table = ProbeTable::default();
    let mut divergence = None;
    let (mut wall, mut probing) = (0.0, 0.0);
    for frame in 1..=frame_count {
        let stepped = simulation.step_frame();
        let timing = simulation.frame_timing();
        wall += (timing.simulation + timing.probes).as_secs_f64();
        probing += timing.probes.as_secs_f64();
        if let Err(diverged) = stepped {
            divergence = Some(diverged);
            break;
        }
        let clock = simulation.clock();
        table.push(frame, clock.time_s, simulation.probes().values.iter().map(|(k, v)| (*k, *v)));
        if frame.is_multiple_of(u64::from(scene.output.every)) || frame == frame_count {
            write(&mut simulation, frame)?;
        }
        progress.advance(frame);
    }
    progress.finish();

    let clock = simulation.clock();
    let computed = table.rows.len() as u64;
    let stats = simulation.integrator_stats();
    let per_frame =
        |stage: std::time::Duration| if computed > 0 { 1e3 * stage.as_secs_f64() / computed as f64 } else { 0.0 };
    let summary = Summary {
        scene: scene.name.clone(),
        status: if divergence.is_some() { "diverged" } else { "completed" }.into(),
        divergence: divergence.as_ref().map(ToString::to_string),
        integrator: scene.solver.integrator.name().into(),
        frames: computed,
        steps: clock.step,
        dt: counts.time.dt,
        substeps: counts.time.substeps,
        sim_time_s: clock.time_s,
        wall_time_s: wall,
        ms_per_frame: if computed > 0 { 1e3 * wall / computed as f64 } else { 0.0 },
        probe_ms_per_frame: if computed > 0 { 1e3 * probing / computed as f64 } else { 0.0 },
        particles: counts.particles,
        springs: counts.springs,
        triangles: counts.triangles,
        force_evaluations: stats.evaluations,
        rejected_steps: stats.rejected,
        cg_iterations: stats.iterations,
        assembly_ms_per_frame: per_frame(stats.stages.assembly),
        preconditioner_ms_per_frame: per_frame(stats.stages.preconditioner),
        solve_ms_per_frame: per_frame(stats.stages.solve),
        probes: simulation.probes().values.iter().map(|(k, v)| ((*k).to_owned(), *v)).collect(),
    };
    let summary_path = dir.join("summary.json");
    write_json(&summary_path, &summary)
        .map_err(|e| Failure::io(format!("cannot write {}", summary_path.display()), e))?;
    let probes_path = dir.join("probes.csv");
    table.write_csv(&probes_path).map_err(|e| Failure::io(format!("cannot write {}", probes_path.display()), e))?;

    if !quiet {
        print_summary(&summary, &dir);
    }
    match divergence {
        Some(diverged) => Err(Failure {
            message: format!("{diverged}; the frames before it are in {}", frames_dir.display()),
            status: EXIT_DIVERGED,
        }),
        None => Ok(()),
    }
}

/// Creates the frames folder and removes frames of an earlier run, so that the folder
/// holds exactly this run's frames.
fn prepare_frames_dir(dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        if name.starts_with("frame_") && (name.ends_with(".obj") || name.ends_with(".ply")) {
            std::fs::remove_file(&path)?;
        }
    }
    Ok(())
}

#[expect(clippy::print_stdout, reason = "the summary is the command's output")]
fn print_summary(summary: &Summary, dir: &Path) {
    println!(
        "{}: {} frames ({:.3} s simulated) in {:.2} s, {:.2} ms/frame ({:.2} of it probes), {} with {} steps/frame",
        summary.scene,
        summary.frames,
        summary.sim_time_s,
        summary.wall_time_s,
        summary.ms_per_frame,
        summary.probe_ms_per_frame,
        summary.integrator,
        summary.substeps
    );
    println!("  {} particles, {} springs, {} triangles", summary.particles, summary.springs, summary.triangles);
    if summary.cg_iterations > 0 {
        println!(
            "  implicit steps: {:.2} ms/frame assembling, {:.2} preparing the preconditioner, {:.2} solving ({} iterations)",
            summary.assembly_ms_per_frame,
            summary.preconditioner_ms_per_frame,
            summary.solve_ms_per_frame,
            summary.cg_iterations
        );
    }
    for (name, value) in &summary.probes {
        println!("  {name:<20} {value:.6}");
    }
    println!("  output in {}", dir.display());
}

/// Progress on stderr: a bar on a terminal, a line every tenth of the run otherwise,
/// nothing when quiet.
enum Progress {
    Bar(ProgressBar),
    Lines { total: u64 },
    Silent,
}

impl Progress {
    fn new(total: u64, quiet: bool) -> Self {
        if quiet {
            Progress::Silent
        } else if std::io::stderr().is_terminal() {
            let bar = ProgressBar::new(total);
            if let Ok(style) =
                ProgressStyle::with_template("{bar:40} {pos}/{len} frames  {elapsed_precise} (eta {eta})")
            {
                bar.set_style(style);
            }
            Progress::Bar(bar)
        } else {
            Progress::Lines { total }
        }
    }

    fn advance(&self, frame: u64) {
        match self {
            Progress::Bar(bar) => bar.set_position(frame),
            Progress::Lines { total } => {
                let step = (total / 10).max(1);
                if frame.is_multiple_of(step) || frame == *total {
                    eprintln!("frame {frame}/{total}");
                }
            }
            Progress::Silent => {}
        }
    }

    fn finish(&self) {
        if let Progress::Bar(bar) = self {
            bar.finish_and_clear();
        }
    }
}
