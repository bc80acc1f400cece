//! `selvedge bench`: the fixed benchmark scenes of `scenes/bench/`, timed frame by frame,
//! with the quality measures that make a time worth comparing (strain, penetration,
//! self-intersections) and the peak memory.

use std::path::{Path, PathBuf};
use std::time::Duration;

use serde::{Deserialize, Serialize};

use super::{EXIT_IO, Failure};
use crate::Simulation;
use crate::io::report::write_json;
use crate::scene::{Scene, load_scene};
use crate::solver::integrate::StageTimes;

/// The benchmark scenes, in the order they run; each is `scenes/bench/<name>.ron`.
pub const BENCH_SCENES: [&str; 8] =
    ["hang_32", "hang_64", "hang_128", "hang_256", "sphere_64", "sphere_64_adaptive", "fold_64", "fold_64_adaptive"];

/// Frames run before timing starts (caches, workspaces and the first contacts settle):
/// full runs and `--quick` ones.
const WARM_UP: (u32, u32) = (10, 3);
/// Frames timed by `--quick` (a full run times the rest of the scene).
const QUICK_FRAMES: u32 = 10;

/// One scene's line of the report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BenchResult {
    /// Scene name.
    pub scene: String,
    /// `"completed"`, or the divergence report.
    pub status: String,
    /// Particles over all cloths.
    pub particles: usize,
    /// Triangles over all cloths.
    pub triangles: usize,
    /// Integrator name.
    pub solver: String,
    /// The cloths' bending laws (`Linear`, `Quadratic`, `Zheng`), `none` for a cloth
    /// without bending, `+`-separated where the cloths differ: the same rigidity makes
    /// different work under different laws.
    #[serde(default)]
    pub bending: String,
    /// Steps per frame, the mean over the timed frames: the scene's `substeps`, or with
    /// `step_motion` the steps its frames took, up to `substeps`.
    pub steps_per_frame: f64,
    /// Solver iterations per frame (conjugate-gradient iterations for the implicit
    /// methods, force evaluations for the explicit ones), over the timed frames.
    pub iterations_per_frame: f64,
    /// Frames timed (after the warm-up).
    pub timed_frames: u32,
    /// Median wall-clock time of the timed frames' simulation [ms]: the steps, the health
    /// check and the render data, not the probes that measure the frame.
    pub ms_per_frame: f64,
    /// Median wall-clock time of the timed frames' probes [ms]: the exact
    /// self-intersection count, the energies, the strain and the pin force.
    pub probe_ms_per_frame: f64,
    /// Where the implicit steps' time went, means over the timed frames [ms]: forces,
    /// derivatives and the system built from them ...
    pub assembly_ms_per_frame: f64,
    /// ... the preconditioner made ready for each system (the multigrid's levels) ...
    pub preconditioner_ms_per_frame: f64,
    /// ... and the linear solves' iterations ...
    pub solve_ms_per_frame: f64,
    /// ... and the rest of the mean frame: contact, the health check, the render data.
    pub other_ms_per_frame: f64,
    /// Simulated time over wall-clock time: 1 is real time.
    pub realtime_factor: f64,
    /// Particles × iterations per second of wall-clock time.
    pub particle_iterations_per_s: f64,
    /// Largest edge strain over all frames.
    pub max_strain: f64,
    /// Deepest particle inside a body over all frames [m].
    pub max_penetration_m: f64,
    /// Most intersecting non-adjacent triangle pairs in any frame.
    pub max_self_intersections: f64,
    /// Intersecting triangle pairs at the last frame.
    pub final_self_intersections: f64,
    /// Peak resident memory the scene added to what the process held before it was
    /// built [bytes], where the system tells it.
    pub peak_memory_bytes: Option<u64>,
    /// That peak per particle [bytes].
    pub bytes_per_particle: Option<f64>,
}

/// What `--out` holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct BenchReport {
    /// Whether the short `--quick` run made it.
    quick: bool,
    /// Threads of the parallel loops.
    threads: usize,
    /// One line per scene.
    scenes: Vec<BenchResult>,
}

/// Runs the benchmark scenes (those named in `only`, else all), prints the table and
/// writes the JSON report to `out`.
pub(super) fn bench(quick: bool, out: Option<PathBuf>, threads: Option<usize>, only: &[String]) -> Result<(), Failure> {
    if let Some(threads) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global()
            .map_err(|e| Failure::bad_input(format!("cannot use {threads} threads: {e}")))?;
    }
    if let Some(unknown) = only.iter().find(|name| !BENCH_SCENES.contains(&name.as_str())) {
        return Err(Failure::bad_input(format!(
            "there is no bench scene {unknown}; the bench scenes are {}",
            BENCH_SCENES.join(", ")
        )));
    }
    let dir = scenes_dir();
    let names: Vec<&str> =
        BENCH_SCENES.into_iter().filter(|name| only.is_empty() || only.iter().any(|o| o == name)).collect();
    let mut results = Vec::new();
    print_header();
    for name in &names {
        let result = match names.len() {
            1 => bench_scene(&dir.join(format!("{name}.ron")), quick)?,
            _ => bench_apart(name, quick, threads)?,
        };
        print_row(&result);
        results.push(result);
    }
    print_stages(&results);
    if let Some(out) = out {
        let report = BenchReport { quick, threads: rayon::current_num_threads(), scenes: results };
        write_json(&out, &report).map_err(|e| Failure::io(format!("cannot write {}", out.display()), e))?;
    }
    Ok(())
}

/// Runs one scene in a process of its own (this command with `--only`), so that its peak
/// memory is its own: memory an earlier scene freed stays with the process, and a later
/// scene that reused it showed as needing less (fold_64 after sphere_64 1 674 bytes a
/// particle, alone 4 030).
fn bench_apart(name: &str, quick: bool, threads: Option<usize>) -> Result<BenchResult, Failure> {
    let exe = std::env::current_exe().map_err(|e| Failure::io("cannot find this program to run a scene", e))?;
    let report = std::env::temp_dir().join(format!("selvedge-bench-{}-{name}.json", std::process::id()));
    let mut command = std::process::Command::new(exe);
    command.args(["bench", "--only", name, "--out"]).arg(&report).stdout(std::process::Stdio::null());
    if quick {
        command.arg("--quick");
    }
    if let Some(threads) = threads {
        command.args(["--threads", &threads.to_string()]);
    }
    let status = command.status().map_err(|e| Failure::io(format!("cannot run bench scene {name}"), e))?;
    let text = std::fs::read_to_string(&report);
    // Best effort: a report that cannot be removed is a stray file in the temporary folder.
    let _ = std::fs::remove_file(&report);
    if !status.success() {
        let message = format!("bench scene {name} failed ({status}); its error is above");
        return Err(Failure { message, status: status.code().and_then(|c| u8::try_from(c).ok()).unwrap_or(EXIT_IO) });
    }
    let text = text.map_err(|e| Failure::io(format!("cannot read the report of bench scene {name}"), e))?;
    let parsed: BenchReport = serde_json::from_str(&text)
        .map_err(|e| Failure::bad_input(format!("the report of bench scene {name} is not readable: {e}")))?;
    parsed.scenes.into_iter().next().ok_or_else(|| Failure::bad_input(format!("bench scene {name} reported nothing")))
}

/// `scenes/bench` under the working folder, else the one of the source tree this binary
/// was built from.
fn scenes_dir() -> PathBuf {
    let local = Path::new("scenes").join("bench");
    if local.is_dir() { local } else { Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join("bench") }
}

/// Runs one scene: the warm-up, then the timed frames, keeping the worst quality measures.
fn bench_scene(path: &Path, quick: bool) -> Result<BenchResult, Failure> {
    let file = load_scene(path).map_err(Failure::bad_input)?;
    let baseline = reset_peak_memory();
    let mut simulation = Simulation::from_file(&file).map_err(Failure::bad_input)?;
    let counts = simulation.counts();
    let (warm_up, timed) = if quick {
        (WARM_UP.1, QUICK_FRAMES)
    } else {
        (WARM_UP.0, counts.time.frames.saturating_sub(WARM_UP.0).max(1))
    };
    let mut worst = [0.0f64; 3];
    let mut keep_worst = |simulation: &Simulation| {
        for (worst, probe) in worst.iter_mut().zip(["max_strain", "max_penetration_m", "self_intersections"]) {
            *worst = worst.max(simulation.probes().get(probe).unwrap_or(0.0));
        }
    };
    let mut status = "completed".to_owned();
    let (mut times, mut probe_times) = (Vec::with_capacity(timed as usize), Vec::with_capacity(timed as usize));
    let (mut iterations_before, mut stages_before, mut steps_before) = (0, StageTimes::default(), 0);
    for frame in 0..warm_up + timed {
        if frame == warm_up {
            steps_before = simulation.clock().step;
            iterations_before = iterations(&simulation);
            stages_before = simulation.integrator_stats().stages;
        }
        if let Err(diverged) = simulation.step_frame() {
            status = diverged.to_string();
            break;
        }
        if frame >= warm_up {
            let timing = simulation.frame_timing();
            times.push(timing.simulation.as_secs_f64());
            probe_times.push(timing.probes.as_secs_f64());
        }
        keep_worst(&simulation);
    }
    let timed_frames = times.len() as u32;
    let mean_ms = 1e3 * times.iter().sum::<f64>() / f64::from(timed_frames.max(1));
    let seconds = median(&mut times);
    let iterations_per_frame = (iterations(&simulation) - iterations_before) as f64 / f64::from(timed_frames.max(1));
    let stages = simulation.integrator_stats().stages;
    let per_frame = |after: Duration, before: Duration| {
        1e3 * after.saturating_sub(before).as_secs_f64() / f64::from(timed_frames.max(1))
    };
    let peak_memory_bytes = baseline.zip(memory("VmHWM:")).map(|(before, peak)| peak.saturating_sub(before));
    Ok(BenchResult {
        scene: file.scene.name.clone(),
        status,
        particles: counts.particles,
        triangles: counts.triangles,
        solver: file.scene.solver.integrator.name().to_owned(),
        bending: bending_laws(&file.scene),
        steps_per_frame: (simulation.clock().step - steps_before) as f64 / f64::from(timed_frames.max(1)),
        iterations_per_frame,
        timed_frames,
        ms_per_frame: 1e3 * seconds,
        probe_ms_per_frame: 1e3 * median(&mut probe_times),
        assembly_ms_per_frame: per_frame(stages.assembly, stages_before.assembly),
        preconditioner_ms_per_frame: per_frame(stages.preconditioner, stages_before.preconditioner),
        solve_ms_per_frame: per_frame(stages.solve, stages_before.solve),
        other_ms_per_frame: mean_ms - per_frame(stages.total(), stages_before.total()),
        realtime_factor: if seconds > 0.0 { 1.0 / (f64::from(file.scene.time.fps) * seconds) } else { 0.0 },
        particle_iterations_per_s: if seconds > 0.0 {
            counts.particles as f64 * iterations_per_frame / seconds
        } else {
            0.0
        },
        max_strain: worst[0],
        max_penetration_m: worst[1],
        max_self_intersections: worst[2],
        final_self_intersections: simulation.probes().get("self_intersections").unwrap_or(0.0),
        peak_memory_bytes,
        bytes_per_particle: peak_memory_bytes.map(|bytes| bytes as f64 / counts.particles.max(1) as f64),
    })
}

/// The solver's iterations so far: conjugate-gradient iterations where it has them, else
/// force evaluations.
fn iterations(simulation: &Simulation) -> u64 {
    let stats = simulation.integrator_stats();
    if stats.iterations > 0 { stats.iterations } else { stats.evaluations }
}

/// The median of `values` [s], zero if there are none.
fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let middle = values.len() / 2;
    if values.len() % 2 == 1 { values[middle] } else { 0.5 * (values[middle - 1] + values[middle]) }
}

/// Starts the process's peak resident memory over from what it holds now (Linux: writing
/// 5 to `/proc/self/clear_refs`), so that each scene's peak is its own, and returns what it
/// holds now [bytes]. `None` where the system does not tell.
fn reset_peak_memory() -> Option<u64> {
    std::fs::write("/proc/self/clear_refs", "5").ok()?;
    memory("VmRSS:")
}

/// A memory figure of the process [bytes]: `VmRSS:` (resident now) or `VmHWM:` (peak
/// resident) of Linux's `/proc/self/status`.
fn memory(field: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|line| line.starts_with(field))?;
    let kilobytes: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kilobytes * 1024)
}

/// The cloths' bending laws, each once, in the cloths' order ([`BenchResult::bending`]).
fn bending_laws(scene: &Scene) -> String {
    let mut laws: Vec<&str> = Vec::new();
    for cloth in &scene.cloths {
        let law = cloth.resolved_material().and_then(|m| m.bending).map_or("none", |b| b.law.name());
        if !laws.contains(&law) {
            laws.push(law);
        }
    }
    laws.join("+")
}

/// The scene column's width: the longest scene name.
fn name_width() -> usize {
    BENCH_SCENES.iter().map(|name| name.len()).max().unwrap_or(0)
}

#[expect(clippy::print_stdout, reason = "the table is the command's output")]
fn print_header() {
    println!(
        "{:<w$} {:>7} {:>7} {:<14} {:<9} {:>5} {:>8} {:>10} {:>8} {:>8} {:>10} {:>9} {:>9} {:>6} {:>8}",
        "scene",
        "parts",
        "tris",
        "solver",
        "bending",
        "steps",
        "iter/fr",
        "ms/frame",
        "probe ms",
        "realtime",
        "p·it/s",
        "strain",
        "pen [mm]",
        "selfX",
        "B/part",
        w = name_width()
    );
}

#[expect(clippy::print_stdout, reason = "the table is the command's output")]
fn print_row(r: &BenchResult) {
    println!(
        "{:<w$} {:>7} {:>7} {:<14} {:<9} {:>5.1} {:>8.1} {:>10.2} {:>8.2} {:>8.3} {:>10.3e} {:>9.4} {:>9.3} {:>6} {:>8}{}",
        r.scene,
        r.particles,
        r.triangles,
        r.solver,
        r.bending,
        r.steps_per_frame,
        r.iterations_per_frame,
        r.ms_per_frame,
        r.probe_ms_per_frame,
        r.realtime_factor,
        r.particle_iterations_per_s,
        r.max_strain,
        1e3 * r.max_penetration_m,
        r.max_self_intersections,
        r.bytes_per_particle.map_or("-".to_owned(), |b| format!("{b:.0}")),
        if r.status == "completed" { String::new() } else { format!("  ({})", r.status) },
        w = name_width()
    );
}

/// Where each scene's frame time goes: the implicit steps' stages, and the rest.
#[expect(clippy::print_stdout, reason = "the table is the command's output")]
fn print_stages(results: &[BenchResult]) {
    println!("\nwhere a frame's time goes [ms, means over the timed frames]");
    let w = name_width();
    println!("{:<w$} {:>10} {:>15} {:>10} {:>10}", "scene", "assembly", "preconditioner", "solve", "other");
    for r in results {
        println!(
            "{:<w$} {:>10.2} {:>15.2} {:>10.2} {:>10.2}",
            r.scene, r.assembly_ms_per_frame, r.preconditioner_ms_per_frame, r.solve_ms_per_frame, r.other_ms_per_frame
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_median_of_an_even_count_is_the_mean_of_the_middle_two() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(&mut []), 0.0);
    }
}
