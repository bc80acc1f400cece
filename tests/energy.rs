//! Energy: an undamped spring network under velocity Verlet conserves its total energy.

mod common;

#[test]
fn an_undamped_swinging_cloth_keeps_its_energy_within_one_percent_over_ten_seconds() {
    // Released horizontal from two corners: it swings down and back, trading about 1 J of
    // potential energy for kinetic energy and back, with no damping anywhere.
    let mut sim = common::simulation(&format!(
        "Scene(name: \"swing\", solver: (integrator: VelocityVerlet, substeps: 20), time: (fps: 60, duration_s: 10.0),
          cloths: [(name: \"c\", shape: Grid(size: (1.0, 1.0), resolution: (8, 8)),
                    placement: (translation: (0.0, 2.0, 0.0), rotation_deg: (90.0, 0.0, 0.0)),
                    material: {}, pins: [Corners([BottomLeft, BottomRight])])])",
        common::material(100.0, 0.0)
    ));
    let total =
        |sim: &selvedge::Simulation| common::probe(sim, "kinetic_energy_j") + common::probe(sim, "potential_energy_j");
    common::run_frames(&mut sim, 1);
    let initial = total(&sim);
    let (mut worst, mut largest_kinetic) = (0.0f64, 0.0f64);
    for _ in 1..600 {
        common::run_frames(&mut sim, 1);
        worst = worst.max((total(&sim) - initial).abs());
        largest_kinetic = largest_kinetic.max(common::probe(&sim, "kinetic_energy_j"));
    }
    assert!(largest_kinetic > 0.5, "the cloth should swing: peak kinetic energy {largest_kinetic} J");
    // Measured against the energy that moves (the peak kinetic energy), which is stricter
    // than against the total, whose gravitational part depends on where y = 0 is.
    assert!(
        worst < 0.01 * largest_kinetic,
        "energy drifted by {worst} J against a peak kinetic energy of {largest_kinetic} J"
    );
    eprintln!("energy drift {worst:e} J of peak kinetic {largest_kinetic} J");
}
