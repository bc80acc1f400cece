//! Structure that changes while the engine runs: tearing by removing springs, pins added
//! and removed, and derived caches rebuilt only when the structure changed.

mod common;

use glam::Vec3;
use selvedge::Simulation;
use selvedge::components::{BendingHinges, ClothTopology, Particles, Pins, Springs};

const G: f32 = 9.81;

fn sheet(drag: f32, integrator: &str, edits: &str) -> Simulation {
    common::simulation(&format!(
        "Scene(name: \"edit\", air: (drag: {drag}), solver: (integrator: {integrator}, substeps: 20),
          time: (fps: 60, duration_s: 5.0),
          cloths: [(name: \"sheet\", shape: Grid(size: (1.0, 1.0), resolution: (16, 16)),
                    placement: (translation: (0.0, 2.0, 0.0)),
                    material: {}, pins: [Corners([TopLeft, TopRight])])],
          edits: [{edits}])",
        common::material(100.0, 0.05)
    ))
}

fn particles(sim: &mut Simulation) -> Particles {
    sim.world_mut().query::<&Particles>().single(sim.world()).expect("one cloth").clone()
}

/// Mass-weighted centre and velocity of the particles whose rest position satisfies `side`.
fn centre_of_mass(p: &Particles, side: impl Fn(Vec3) -> bool) -> (Vec3, Vec3) {
    let (mut mass, mut x, mut v) = (0.0, Vec3::ZERO, Vec3::ZERO);
    for i in (0..p.len()).filter(|&i| side(p.rest_position[i])) {
        let m = p.mass(i);
        mass += m;
        x += m * p.position[i];
        v += m * p.velocity[i];
    }
    (x / mass, v / mass)
}

fn topology_builds(sim: &mut Simulation) -> u32 {
    sim.world_mut().query::<&ClothTopology>().single(sim.world()).expect("one cloth").builds
}

#[test]
fn a_torn_sheet_hangs_as_two_halves_under_their_own_pins() {
    let mut sim = sheet(
        3.0,
        "SymplecticEuler",
        "(at_s: 1.0, cloth: \"sheet\", action: Tear(point: (0.0, 2.0, 0.0), normal: (1.0, 0.0, 0.0)))",
    );
    common::run_frames(&mut sim, 59);
    assert_eq!(topology_builds(&mut sim), 1, "the cache is built once and not rebuilt every frame");
    let before = particles(&mut sim);
    let (left_before, _) = centre_of_mass(&before, |r| r.x < 0.0);
    common::run_frames(&mut sim, 1 + 240);
    assert_eq!(topology_builds(&mut sim), 2, "the tear rebuilt the cache once");
    let after = particles(&mut sim);
    let springs = sim.world_mut().query::<&Springs>().single(sim.world()).expect("one cloth").clone();
    let crossing = springs
        .pairs
        .iter()
        .filter(|[i, j]| (after.rest_position[*i as usize].x < 0.0) != (after.rest_position[*j as usize].x < 0.0))
        .count();
    assert_eq!(crossing, 0, "no spring joins the two halves after the tear");
    let (left, _) = centre_of_mass(&after, |r| r.x < 0.0);
    let (right, _) = centre_of_mass(&after, |r| r.x >= 0.0);
    // A body hanging from one point rests with its centre of mass below that point.
    assert!(left_before.x > -0.3, "before the tear the left half is spread: {left_before}");
    assert!((left.x + 0.5).abs() < 0.02, "left half hangs below its pin at x = -0.5: {left}");
    assert!((right.x - 0.5).abs() < 0.02, "right half hangs below its pin at x = 0.5: {right}");
}

#[test]
fn a_released_half_falls_with_its_centre_of_mass_accelerating_at_g() {
    let mut sim = sheet(
        0.0,
        "VelocityVerlet",
        "(at_s: 0.5, cloth: \"sheet\", action: Tear(point: (0.0, 2.0, 0.0), normal: (1.0, 0.0, 0.0))),
         (at_s: 1.0, cloth: \"sheet\", action: Unpin([Corners([TopRight])]))",
    );
    common::run_frames(&mut sim, 60);
    let pins = sim.world_mut().query::<&Pins>().single(sim.world()).expect("one cloth").clone();
    assert_eq!(pins.len(), 2, "the release is not due before its time");
    common::run_frames(&mut sim, 1);
    let (start_time, start) = (sim.clock().time_s, particles(&mut sim));
    // The release applies at the start of the frame just computed, so the half has fallen
    // freely since the frame began.
    let frame = 1.0 / 60.0;
    let (x0, v0) = centre_of_mass(&start, |r| r.x >= 0.0);
    common::run_frames(&mut sim, 30);
    let t = (sim.clock().time_s - start_time) as f32;
    let (x1, _) = centre_of_mass(&particles(&mut sim), |r| r.x >= 0.0);
    // Internal forces cancel in pairs: only gravity moves the centre of mass.
    let expected = x0 + v0 * t + 0.5 * Vec3::new(0.0, -G, 0.0) * t * t;
    assert!((x1 - expected).length() < 1e-3, "centre of mass at {x1}, free fall predicts {expected}");
    let pinned_particle = sim.world_mut().query::<&Pins>().single(sim.world()).expect("one cloth").particles.clone();
    assert_eq!(pinned_particle.len(), 1, "one pin was released");
    assert!(start_time > 1.0 && start_time <= 1.0 + frame + 1e-6);
}

#[test]
fn a_pin_added_through_the_world_holds_its_particle_from_the_next_frame() {
    let mut sim = common::simulation(&format!(
        "Scene(name: \"fall\", solver: (substeps: 10), time: (fps: 60, frames: 100),
          cloths: [(name: \"sheet\", shape: Grid(size: (1.0, 1.0), resolution: (8, 8)), material: {})])",
        common::material(100.0, 0.05)
    ));
    common::run_frames(&mut sim, 10);
    let entity = sim.cloth_entity("sheet").expect("the cloth exists");
    let held = sim.world().get::<Particles>(entity).expect("particles").position[63];
    sim.world_mut().get_mut::<Pins>(entity).expect("pins").insert(63, held);
    common::run_frames(&mut sim, 20);
    let p = particles(&mut sim);
    assert_eq!(p.position[63], held, "the pinned particle stays where it was pinned");
    assert!(p.position[0].y < held.y - 0.1, "the rest of the cloth falls below it");
    assert_eq!(topology_builds(&mut sim), 2);

    sim.world_mut().get_mut::<Pins>(entity).expect("pins").remove(63);
    common::run_frames(&mut sim, 10);
    assert!(particles(&mut sim).position[63].y < held.y - 0.05, "released, it falls again");
}

/// A tear through a sheet that bends quadratically builds its bending again over the
/// triangles left, with no coupling across the cut: both halves hang under their own pins,
/// each still bending.
#[test]
fn a_torn_sheet_bending_quadratically_hangs_as_two_halves() {
    let mut sim = common::simulation(
        "Scene(name: \"edit\", air: (drag: 3.0), solver: (integrator: ImplicitEuler, substeps: 2),
          time: (fps: 60, duration_s: 5.0),
          cloths: [(name: \"sheet\", shape: Grid(size: (1.0, 1.0), resolution: (16, 16)),
                    placement: (translation: (0.0, 2.0, 0.0)),
                    material: (density: 0.2, membrane: Isotropic(young: 500.0, poisson: 0.3),
                               bending: (warp: 1e-4, weft: 1e-4, law: Quadratic)),
                    pins: [Corners([TopLeft, TopRight])])],
          edits: [(at_s: 1.0, cloth: \"sheet\", action: Tear(point: (0.0, 2.0, 0.0), normal: (1.0, 0.0, 0.0)))])",
    );
    let hinges = |sim: &mut selvedge::Simulation| {
        sim.world_mut().query::<&BendingHinges>().single(sim.world()).expect("one cloth").clone()
    };
    // 15 × 15 cells of two triangles: 15 · 16 edges each way and 15² diagonals inside.
    assert_eq!(hinges(&mut sim).hinge_count(), 2 * 15 * 14 + 15 * 15);
    common::run_frames(&mut sim, 60 + 240);
    let after = particles(&mut sim);
    let bending = hinges(&mut sim);
    assert!(bending.is_quadratic());
    let crossing = bending
        .quadratic
        .pairs()
        .filter(|&(i, j, _)| (after.rest_position[i as usize].x < 0.0) != (after.rest_position[j as usize].x < 0.0))
        .count();
    assert_eq!(crossing, 0, "no coupling joins the two halves after the tear");
    // The column of cells the cut crosses loses its 15 diagonals and 14 edges across, and
    // its 2 · 15 edges along it, left on the boundary, bend no more.
    assert_eq!(bending.hinge_count(), 2 * 15 * 14 + 15 * 15 - 15 - 14 - 30, "the halves still bend");
    let (left, _) = centre_of_mass(&after, |r| r.x < 0.0);
    let (right, _) = centre_of_mass(&after, |r| r.x >= 0.0);
    assert!((left.x + 0.5).abs() < 0.02, "left half hangs below its pin at x = -0.5: {left}");
    assert!((right.x - 0.5).abs() < 0.02, "right half hangs below its pin at x = 0.5: {right}");
}

/// A tear that severs nothing builds a turned, warp-aligned sheet's quadratic bending again
/// exactly as the scene built it: the rest positions and the warp it keeps are the ones
/// its faces were made from.
#[test]
fn a_tear_that_severs_nothing_leaves_quadratic_bending_as_it_was() {
    let mut sim = common::simulation(
        "Scene(name: \"edit\", solver: (integrator: ImplicitEuler, substeps: 2),
          time: (fps: 60, duration_s: 1.0),
          cloths: [(name: \"sheet\", shape: Grid(size: (1.0, 0.6), resolution: (12, 9)),
                    placement: (translation: (0.0, 2.0, 0.0), rotation_deg: (-60.0, 25.0, 10.0)),
                    material: (density: 0.2, membrane: Isotropic(young: 500.0, poisson: 0.3),
                               bending: (warp: 2e-4, weft: 1e-4, law: Quadratic)),
                    pins: [Corners([TopLeft, TopRight])])],
          edits: [(at_s: 0.5, cloth: \"sheet\", action: Tear(point: (9.0, 9.0, 9.0), normal: (1.0, 0.0, 0.0),
                                                                 radius: 0.1))])",
    );
    let bending = |sim: &mut Simulation| {
        sim.world_mut().query::<&BendingHinges>().single(sim.world()).expect("one cloth").clone()
    };
    let spawned = bending(&mut sim);
    assert!(spawned.is_quadratic());
    common::run_frames(&mut sim, 40);
    assert_eq!(bending(&mut sim), spawned);
}
