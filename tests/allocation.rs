//! The step allocates nothing once its buffers have grown to their working size (issue 5):
//! a counting allocator watches whole frames after a few warm-up frames, with every
//! integrator, body contact with friction, self-contact, strain limiting and the frame's
//! probes. (Rigid props are left out: rapier3d's own step allocates a little.) The windows
//! are long, since contact starting or spreading in a warm frame is what grows buffers:
//! three frames of the draped sheet were clean by chance, where its frames 31 to 60
//! reallocated 34 times over the 20 solvers before the contact lists started with room
//! (`selvedge::solver::gather::FLOOR`). A list that outgrows all it has held before still
//! grows, by doubling, as where a twist winds ever tighter.

mod common;

use std::alloc::System;

use glam::Vec3;
use selvedge::Simulation;
use selvedge::solver::integrate::Integrator;
use stats_alloc::{INSTRUMENTED_SYSTEM, Region, StatsAlloc};

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

/// The count is global, so the cases run one after another in a single test: no other
/// test's set-up is counted in their frames, and neither is libtest's own work between
/// tests, which allocates as one ends and the next begins (its result printed, the next
/// test's thread spawned). As four tests taking turns, the case with the shortest warm-up
/// (`frames_whose_steps_follow_the_motion_allocate_nothing_once_warm`, counting within
/// milliseconds of its turn) once counted 12 allocations in a clean CI run while benches
/// loaded the machine, and never alone.
#[test]
fn warm_frames_allocate_nothing() {
    a_released_list_is_shrunk_in_place_then_freed_as_one_element();
    a_warm_step_allocates_nothing_with_any_integrator();
    the_bench_scenes_allocate_nothing_once_warm();
    frames_whose_steps_follow_the_motion_allocate_nothing_once_warm();
}

/// Allocations and reallocations over `frames` frames after `warm_up` frames.
fn allocations_after(sim: &mut Simulation, warm_up: u32, frames: u32) -> usize {
    common::run_frames(sim, warm_up);
    allocations_in(|| common::run_frames(sim, frames))
}

/// Allocations and reallocations while `work` runs, counted from inside the pool. A frame
/// started from outside it is injected into rayon's global queue, which allocates a block
/// every 63 injections, at a point that depends on how many frames the cases before have
/// run: one in three runs failed.
fn allocations_in(work: impl FnOnce() + Send) -> usize {
    rayon::scope(|_| {
        let region = Region::new(GLOBAL);
        work();
        let change = region.change();
        change.allocations + change.reallocations
    })
}

/// A 9 × 9 sheet pinned at two corners, draped over a sphere with friction, colliding
/// with itself, its strain limited, stepped by `integrator` (with `preconditioner` if it
/// solves by conjugate gradients).
fn draped_sheet(integrator: Integrator, preconditioner: &str) -> Simulation {
    common::simulation(&format!(
        "Scene(
            name: \"draped\",
            solver: (integrator: {integrator:?}, substeps: 60, preconditioner: {preconditioner}),
            time: (fps: 60, duration_s: 1.0),
            cloths: [(
                name: \"sheet\",
                shape: Grid(size: (0.4, 0.4), resolution: (9, 9)),
                placement: (translation: (0.0, 0.12, 0.0), rotation_deg: (-90.0, 0.0, 0.0)),
                material: (density: 0.2, membrane: Isotropic(young: 20.0, poisson: 0.3),
                           bending: (warp: 1.0e-5, weft: 1.0e-5)),
                strain_limit: (max_strain: 0.1),
                pins: [Corners([TopLeft, TopRight])],
                self_collision: (friction: 0.3),
            )],
            colliders: [(name: \"sphere\", shape: Sphere(radius: 0.1), friction: 0.3)],
            ground: (enabled: true, height: -0.1, friction: 0.3),
        )"
    ))
}

fn a_warm_step_allocates_nothing_with_any_integrator() {
    for integrator in Integrator::ALL {
        for preconditioner in ["BlockJacobi", "Multigrid"] {
            let mut sim = draped_sheet(integrator, preconditioner);
            let count = allocations_after(&mut sim, 30, 30);
            let case = format!("{integrator:?} ({preconditioner})");
            assert!(common::probe(&sim, "contact_force_n") > 0.0, "{case}: the sheet rests on the sphere");
            assert_eq!(count, 0, "{case} allocated {count} times in frames 31 to 60");
        }
    }
}

fn the_bench_scenes_allocate_nothing_once_warm() {
    // sphere_64 counted once its sheet has landed (its contact lists grow over frames 14
    // to 28, and its self contact's candidates once, in frame 31 or 32, where its sweeps
    // have become short enough for a listing to cover them whole; since the armed
    // contact springs of the tenth session, a chunk of the contact stage's proximity
    // contacts last in frame 36, and none from there to frame 119), the others from
    // their start.
    for (name, warm_up) in [("bench/hang_32.ron", 3), ("bench/sphere_64.ron", 36), ("twist.ron", 3)] {
        let mut sim = common::bundled(name);
        let count = allocations_after(&mut sim, warm_up, 20);
        assert_eq!(count, 0, "{name} allocated {count} times in frames {} to {}", warm_up + 1, warm_up + 20);
    }
    // Two cloths resting on each other, their close pairs springs of each cloth's step,
    // placed against the other before each step. Gravity straight down: on the scene's
    // slope the upper cloth slides on, and the contact lists grow as it goes.
    let mut sim = common::bundled_with("layer_slope_cloths.ron", |scene| scene.gravity = Vec3::new(0.0, -9.8, 0.0));
    let count = allocations_after(&mut sim, 30, 20);
    assert_eq!(count, 0, "two cloths resting on each other allocated {count} times in frames 31 to 50");
}

fn frames_whose_steps_follow_the_motion_allocate_nothing_once_warm() {
    // The square of tests/step_motion.rs (`common::square_scene`), colliding with itself,
    // falling flat towards the ground 0.3 m below: one step a frame while the ground is
    // beyond its reach, and in frame 13 (from 0) the several its speed needs, the last
    // frame before it touches. Counted before it touches, since contact beginning grows the
    // contact lists (on sphere_64 with `step_motion` its self contact spread until frame 75
    // or later, as rounding fell, while the frames' steps changed).
    let mut sim = common::simulation(&common::square_scene(9.81, "", Some(19.7), true));
    common::run_frames(&mut sim, 5);
    // Made before counting, so that its own growth is not counted.
    let mut taken = Vec::with_capacity(9);
    let count = allocations_in(|| {
        for _ in 5..=13 {
            let before = sim.clock().step;
            common::run_frames(&mut sim, 1);
            taken.push(sim.clock().step - before);
        }
    });
    assert!(taken[0] == 1 && taken[8] > 1, "frames 5 to 13 took {taken:?} steps: one, then more near the ground");
    assert_eq!(common::probe(&sim, "contact_force_n"), 0.0, "the square has not touched the ground yet");
    assert_eq!(count, 0, "frames whose steps follow the motion allocated {count} times ({taken:?} steps)");
    // Landing, all its 144 particles touch the ground at once: each of the five lists
    // that contact makes (the touches, the coupling's links, the implicit constraints,
    // their filter blocks and impulses) grows once, not by doubling (29 allocations).
    let landing = allocations_after(&mut sim, 0, 1);
    assert!(common::probe(&sim, "contact_force_n") > 0.0, "the square lands in frame 14");
    assert!(landing <= 5, "contact beginning allocated {landing} times");
}

/// A large temporary list is given back shrunk in place to one element, then freed: the
/// block freed is that element's, so glibc's mmap threshold, which a mapped block freed
/// whole raises to its size, stays where it was (`selvedge::memory::release`).
fn a_released_list_is_shrunk_in_place_then_freed_as_one_element() {
    for length in [1 << 20, 1] {
        let list = vec![7u64; length];
        let region = Region::new(GLOBAL);
        selvedge::memory::release(list);
        let change = region.change();
        let shrunk = usize::from(length > 1);
        assert_eq!(change.reallocations, shrunk, "{length} elements: shrunk in place once if there was room");
        assert_eq!(change.bytes_reallocated, -(8 * (length as isize - 1)), "{length} elements");
        // The shrink counts its bytes as deallocated too: the free is the one block left.
        assert_eq!((change.deallocations, change.bytes_deallocated), (1, 8 * length), "{length} elements: one free");
    }
}
