//! Self-collision scenes (Zheng §3.7.3, §4.5.2; the fold and twist cases): the exact
//! triangle–triangle count `self_intersections`, computed independently of the contact
//! code, stays 0 at every frame, while the same scenes without self-collision pass
//! through themselves (hundreds of pairs; see each scene's comment). Each test also
//! checks that contact really happened, so it cannot pass on a cloth that never folds. A
//! heap in contact gives the same bits on one thread and two.

mod common;

use selvedge::components::{MembraneDesc, Particles};
use selvedge::scene::format::Preconditioner;
use selvedge::solver::integrate::Integrator;

/// Runs a bundled scene to its end, checking after every frame that no triangle pair
/// intersects and that no particle is below `floor` [m]; returns the frame-summed
/// continuous impacts and the largest number of proximity pairs in a step.
fn run_untangled(name: &str, floor: Option<f32>) -> (f64, f64) {
    let mut sim = common::bundled(name);
    let (mut impacts, mut pairs) = (0.0, 0.0f64);
    for frame in 1..=sim.counts().time.frames {
        sim.step_frame().unwrap_or_else(|e| panic!("{name}: {e}"));
        let probe = |p: &str| sim.probes().get(p).unwrap_or_else(|| panic!("no probe {p}"));
        assert_eq!(probe("self_intersections"), 0.0, "{name}, frame {frame}: the cloth passed through itself");
        impacts += probe("self_impacts");
        pairs = pairs.max(probe("self_contact_pairs"));
        if let Some(floor) = floor {
            let world = sim.world_mut();
            let mut cloths = world.query::<&Particles>();
            let lowest = cloths.iter(world).flat_map(|p| p.position.iter().map(|x| x.y)).fold(f32::INFINITY, f32::min);
            assert!(lowest >= floor, "{name}, frame {frame}: a particle is {} m into the ground", floor - lowest);
        }
    }
    (impacts, pairs)
}

#[test]
fn zheng_flag_folds_onto_itself_without_passing_through() {
    let (impacts, pairs) = run_untangled("zheng_flag.ron", None);
    assert!(impacts > 10.0 && pairs > 10.0, "the flag touched itself: {impacts} impacts, {pairs} pairs");
}

#[test]
fn zheng_vertical_drape_piles_up_without_passing_through_itself_or_the_ground() {
    // The contact springs hold resting layers at their separation, where the impulses
    // alone left them pressed a millimetre into it: some 700 pairs a step closer than it
    // at the most, against 9 000 before.
    let (impacts, pairs) = run_untangled("zheng_vertical_drape.ron", Some(0.0));
    assert!(pairs > 300.0, "the cloth piled onto itself: {impacts} impacts, {pairs} pairs");
}

#[test]
fn a_strip_falling_in_folds_heaps_up_untangled() {
    let (impacts, pairs) = run_untangled("fold_heap.ron", Some(0.0));
    assert!(pairs > 1000.0, "the strip folded onto itself: {impacts} impacts, {pairs} pairs");
}

#[test]
fn a_stiff_strip_falling_in_folds_never_holds_more_energy_than_it_started_with() {
    // Nothing works on the strip but gravity and the fixed ground, so its kinetic plus
    // potential energy (gravity and elastic) can only fall. With the membrane of the bench
    // scenes (μ = λ = 1000 N/m), a contact stage alone, after the step, undid motions the
    // membrane drove and stored that work as strain: the heap rose to twice its starting
    // energy by frame 37, with 2 000 continuous impacts. The contact springs in the
    // implicit solve stop those pairs while the membrane is solved for.
    let mut sim = common::bundled_with("fold_heap.ron", |scene| {
        let material = scene.cloths[0].material.as_mut().expect("fold_heap gives a material");
        material.membrane = Some(MembraneDesc::Isotropic { young: 2666.667, poisson: 1.0 / 3.0 });
    });
    let energy =
        |sim: &selvedge::Simulation| common::probe(sim, "kinetic_energy_j") + common::probe(sim, "potential_energy_j");
    sim.step_frame().expect("frame 1");
    let start = energy(&sim);
    let (mut pairs, mut highest) = (0.0f64, start);
    for frame in 2..=60 {
        sim.step_frame().unwrap_or_else(|e| panic!("frame {frame}: {e}"));
        highest = highest.max(energy(&sim));
        pairs = pairs.max(common::probe(&sim, "self_contact_pairs"));
    }
    assert!(pairs > 100.0, "the strip folded onto itself: {pairs} pairs");
    assert!(highest <= start * 1.01, "the heap gained energy: {highest} J against {start} J at frame 1");
}

#[test]
fn a_twisted_strip_coils_untangled() {
    // Until the armed contact springs of the tenth session the contact stage met over a
    // hundred continuous impacts here; now the solve stops the coils' layers before they
    // meet, and none is left to it (196 pairs in contact at the most): the pairs show
    // that the strip wrung onto itself.
    let (_, pairs) = run_untangled("twist.ron", None);
    assert!(pairs > 100.0, "the strip wrung onto itself: {pairs} pairs");
}

#[test]
fn a_heap_in_contact_gives_the_same_bits_on_one_thread_and_two() {
    // The strip lands at about frame 20 and heaps up from there: ground contact, self
    // proximity, continuous impacts and impact zones all run in these frames; with
    // multigrid, the contact springs on its levels too.
    for preconditioner in [Preconditioner::BlockJacobi, Preconditioner::Multigrid] {
        let run = |threads| {
            common::on_threads(threads, || {
                let mut sim =
                    common::bundled_with("fold_heap.ron", |scene| scene.solver.preconditioner = preconditioner);
                common::run_frames(&mut sim, 40);
                let pairs = sim.probes().get("self_contact_pairs").expect("self-contact probes");
                let world = sim.world_mut();
                let positions = world.query::<&Particles>().single(world).expect("one cloth").position.clone();
                (positions, pairs)
            })
        };
        let (one, pairs) = run(1);
        assert!(pairs > 0.0, "no self-contact by frame 40 ({preconditioner:?})");
        assert_eq!(one, run(2).0, "two threads changed the result ({preconditioner:?})");
    }
}

/// Runs `fold_heap.ron` with block descent at one step per frame, its contact bounds on
/// or off, for `frames` frames ([`descended`]).
fn descent_heap(bounded: bool, frames: u32) -> (f64, Vec<Vec<glam::Vec3>>) {
    let mut sim = common::bundled_with("fold_heap.ron", |scene| {
        scene.solver.integrator = Integrator::BlockDescent;
        scene.solver.substeps = Some(1);
        scene.solver.descent.get_or_insert_default().contact_bounds = bounded;
    });
    descended(&mut sim, frames)
}

/// Steps `sim` `frames` frames, checking that no triangle pair intersects after any;
/// returns the frame-summed continuous impacts the contact stage met after the steps, and
/// each cloth's positions.
fn descended(sim: &mut selvedge::Simulation, frames: u32) -> (f64, Vec<Vec<glam::Vec3>>) {
    let mut impacts = 0.0;
    for frame in 1..=frames {
        sim.step_frame().unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(common::probe(sim, "self_intersections"), 0.0, "frame {frame}: the cloth passed through itself");
        impacts += common::probe(sim, "self_impacts");
    }
    let world = sim.world_mut();
    let positions = world.query::<&Particles>().iter(world).map(|p| p.position.clone()).collect();
    (impacts, positions)
}

#[test]
fn block_descent_bounded_by_contact_leaves_the_contact_stage_almost_nothing_to_catch() {
    // At one step per 1/60 s frame the strip lands and folds within the first second.
    // Unbounded, the sweeps carry folds through one another and the contact stage after
    // the step must stop them (about 1 500 continuous impacts by frame 60); bounded, no
    // sweep passes a vertex through a triangle, and what the contact stage still meets
    // comes only from the straight path it checks between the step's ends.
    let (free, _) = descent_heap(false, 60);
    let (bounded, positions) = descent_heap(true, 60);
    assert!(free > 300.0, "the unbounded sweeps met {free} impacts: the strip did not fold");
    assert!(bounded < 0.05 * free, "bounded: {bounded} impacts against {free}");
    let one = common::on_threads(1, || descent_heap(true, 60).1);
    assert_eq!(one, positions, "one thread changed the result");
}

/// Two strips of `fold_heap.ron`, two cloths, the second 6 cm behind the first and 10 cm
/// higher, leaning the same way, so that each folds onto itself and onto the other, at one
/// block-descent step a frame, its contact bounds on or off.
fn two_strips(bounded: bool) -> String {
    let strip = |name: &str, translation: &str| {
        format!(
            "(name: \"{name}\", shape: Grid(size: (0.3, 1.5), resolution: (16, 76)), \
             placement: (translation: {translation}, rotation_deg: (4.0, 0.0, 0.0)), \
             material: (density: 0.15, membrane: Isotropic(young: 200.0, poisson: 0.3), \
             bending: (warp: 2.0e-5, weft: 2.0e-5)), thickness: 0.002, self_collision: (friction: 0.3))"
        )
    };
    format!(
        "Scene(name: \"two_strips\", gravity: (0.0, -9.8, 0.0), air: (drag: 0.2), \
         solver: (integrator: BlockDescent, substeps: 1, descent: (contact_bounds: {bounded})), \
         time: (fps: 60, duration_s: 1.5), cloths: [{}, {}], ground: (enabled: true, height: 0.0, friction: 0.3))",
        strip("first", "(0.0, 0.85, 0.0)"),
        strip("second", "(0.0, 0.95, 0.06)"),
    )
}

/// Runs [`two_strips`] to its end ([`descended`]).
fn descent_two_strips(bounded: bool) -> (f64, Vec<Vec<glam::Vec3>>) {
    let mut sim = common::simulation(&two_strips(bounded));
    let frames = sim.counts().time.frames;
    descended(&mut sim, frames)
}

#[test]
fn block_descent_bounds_each_cloth_by_the_other_cloths_too() {
    // The strips fold onto themselves and onto each other. Unbounded, the sweeps carry
    // folds through folds and the contact stage after the step must stop them (some
    // 19 000 continuous impacts in 90 frames); each cloth bounded by its own contact
    // alone still left it 1 000, nearly all between the two strips (29 November 2026);
    // bounded by the other strip too, a handful.
    let (free, _) = descent_two_strips(false);
    let (bounded, positions) = descent_two_strips(true);
    assert!(free > 3000.0, "the unbounded sweeps met {free} impacts: the strips did not fold");
    assert!(bounded < 0.01 * free, "bounded: {bounded} impacts against {free}");
    let one = common::on_threads(1, || descent_two_strips(true).1);
    assert_eq!(one, positions, "one thread changed the result");
}
