//! Fabric constants are per unit area and width, so a fabric behaves the same whatever the
//! particle spacing: a 0.5 m cotton sheet hanging from two corners settles to the same
//! shape at 2 cm and at 1 cm spacing.

mod common;

use glam::Vec3;
use selvedge::components::Particles;

/// Settles the sheet at `n × n` particles; returns (bottom-edge midpoint, potential energy).
fn settled(n: u32) -> (Vec3, f64) {
    let mut sim = common::simulation(&format!(
        "Scene(name: \"res\", air: (drag: 5.0), solver: (integrator: ImplicitEuler, substeps: 1, cg_tolerance: 1e-5),
          time: (fps: 30, duration_s: 5.0),
          cloths: [(name: \"sheet\", shape: Grid(size: (0.5, 0.5), resolution: ({n}, {n})),
                    placement: (translation: (0.0, 1.0, 0.0)), fabric: Named(Cotton),
                    pins: [Corners([TopLeft, TopRight])])])"
    ));
    common::run_frames(&mut sim, 150);
    assert!(common::probe(&sim, "kinetic_energy_j") < 1e-10, "settled");
    let particles = sim.world_mut().query::<&Particles>().single(sim.world()).expect("one cloth").clone();
    // Bottom row, middle: the two middle particles when the count is even.
    let middle = ((n - 1) / 2, n / 2);
    let bottom_mid = 0.5 * (particles.position[middle.0 as usize] + particles.position[middle.1 as usize]);
    (bottom_mid, common::probe(&sim, "potential_energy_j"))
}

#[test]
fn a_cotton_sheet_hangs_the_same_at_two_and_one_centimetre_spacing() {
    let (coarse, coarse_energy) = settled(26);
    let (fine, fine_energy) = settled(51);
    assert!((coarse.y - fine.y).abs() < 1e-3, "bottom midpoint at {} m and {} m", coarse.y, fine.y);
    assert!(
        (coarse_energy - fine_energy).abs() < 1e-3 * fine_energy.abs(),
        "potential energy {coarse_energy} J and {fine_energy} J"
    );
}
