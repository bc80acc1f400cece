//! The engine as a library: a world built from a scene, stepped a frame at a time.

use std::path::Path;
use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;

use crate::components::{Cloth, Particles, RenderMesh, Triangles};
use crate::pool::run_awake;
use crate::resources::{HealthReport, IntegratorStats, Probes, SimClock};
use crate::scene::load::SceneFile;
use crate::scene::{Scene, SceneCounts, SceneError, spawn_scene};
use crate::schedule::{FrameSchedule, ProbeSchedule, RenderSchedule, add_schedules};

/// A run that went bad: where and when.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("diverged in frame {frame} (t = {time_s:.4} s): cloth `{cloth}`: {problem}")]
pub struct Divergence {
    /// The frame being computed when it happened (1-based).
    pub frame: u64,
    /// Simulated time when it was detected [s].
    pub time_s: f64,
    /// Name of the cloth.
    pub cloth: String,
    /// What went wrong and where in the cloth.
    pub problem: String,
}

/// One cloth's surface as a renderer or exporter sees it.
#[derive(Debug, Clone, Copy)]
pub struct ClothSurface<'a> {
    /// Name of the cloth.
    pub name: &'a str,
    /// Vertex positions [m].
    pub positions: &'a [glam::Vec3],
    /// Unit vertex normals.
    pub normals: &'a [glam::Vec3],
    /// Triangles.
    pub triangles: &'a [[u32; 3]],
}

/// Where a frame's wall-clock time went.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameTiming {
    /// The simulation: the frame's steps, health check and render data.
    pub simulation: Duration,
    /// The probes ([`ProbeSchedule`]), which measure the frame.
    pub probes: Duration,
}

/// A simulation: the ECS world holding the scene's cloths and resources, with the
/// schedules that step it.
pub struct Simulation {
    world: World,
    counts: SceneCounts,
    timing: FrameTiming,
}

impl Simulation {
    /// Builds the world of `scene`; mesh paths are relative to `base_dir`.
    pub fn new(scene: &Scene, base_dir: &Path) -> Result<Self, SceneError> {
        let mut world = World::new();
        // Built on a worker of rayon's pool, where the frames run: glibc's allocator keeps
        // an arena a thread, and the memory the build frees then serves the first frame
        // instead of staying with the calling thread (`bench --quick`, peak resident:
        // hang_256 1 523 to 1 575 bytes a particle against 1 607, hang_64 1 886 to 1 906
        // against 1 945 to 1 968, alternating, same times).
        let counts = rayon::scope(|_| spawn_scene(&mut world, scene, base_dir))?;
        add_schedules(&mut world);
        world.run_schedule(RenderSchedule);
        Ok(Self { world, counts, timing: FrameTiming::default() })
    }

    /// Builds the world of a scene read from a file; errors point into the file.
    pub fn from_file(file: &SceneFile) -> Result<Self, SceneError> {
        Self::new(&file.scene, file.base_dir()).map_err(|e| e.located(&file.path, &file.text))
    }

    /// Computes one frame. On divergence the world keeps the bad state for inspection
    /// and the render meshes keep the last good frame.
    pub fn step_frame(&mut self) -> Result<(), Divergence> {
        // The frame runs on a worker of rayon's pool: a parallel loop started from any
        // other thread has to wake a worker and sleep until it is done, which cost more
        // than the loops themselves (block descent starts a few hundred per step). The
        // other workers stay awake through it ([`run_awake`]).
        let world = &mut self.world;
        let start = Instant::now();
        let probes = run_awake(|| {
            world.run_schedule(FrameSchedule);
            let measuring = Instant::now();
            world.run_schedule(ProbeSchedule);
            measuring.elapsed()
        });
        let problem = self.world.resource::<HealthReport>().problem.clone();
        if problem.is_none() {
            self.world.run_schedule(RenderSchedule);
        }
        self.timing = FrameTiming { simulation: start.elapsed() - probes, probes };
        match problem {
            Some(problem) => {
                let clock = self.clock();
                Err(Divergence {
                    frame: clock.frame.max(1),
                    time_s: clock.time_s,
                    cloth: problem.cloth,
                    problem: problem.problem,
                })
            }
            None => Ok(()),
        }
    }

    /// Where the last frame's time went, a diverged one's too.
    pub fn frame_timing(&self) -> FrameTiming {
        self.timing
    }

    /// What the scene built.
    pub fn counts(&self) -> SceneCounts {
        self.counts
    }

    /// The clock.
    pub fn clock(&self) -> SimClock {
        *self.world.resource::<SimClock>()
    }

    /// The probes of the last frame.
    pub fn probes(&self) -> &Probes {
        self.world.resource::<Probes>()
    }

    /// Work done by the integrators so far.
    pub fn integrator_stats(&self) -> IntegratorStats {
        *self.world.resource::<IntegratorStats>()
    }

    /// The world, to query components.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The world, to edit components: changes to springs, triangles and pins take effect
    /// from the next frame.
    pub fn world_mut(&mut self) -> &mut World {
        &mut self.world
    }

    /// The entity of the cloth named `name`.
    pub fn cloth_entity(&mut self, name: &str) -> Option<Entity> {
        self.world.query::<(Entity, &Cloth)>().iter(&self.world).find(|(_, c)| c.name == name).map(|(e, _)| e)
    }

    /// The surfaces of all cloths as of the last completed frame, in spawn order.
    pub fn surfaces(&mut self) -> Vec<ClothSurface<'_>> {
        let mut query = self.world.query::<(&Cloth, &Particles, &RenderMesh, &Triangles)>();
        query
            .iter(&self.world)
            .map(|(cloth, particles, mesh, triangles)| ClothSurface {
                name: &cloth.name,
                positions: &particles.position,
                normals: &mesh.normals,
                triangles: &triangles.indices,
            })
            .collect()
    }
}
