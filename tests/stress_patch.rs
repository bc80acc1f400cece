//! Zheng's stress patch test (§5.6.4): a 1 m square membrane held along its top edge and
//! pulled by 1 N/m along its bottom edge settles with a mean normal stress resultant of
//! 1 N/m along the load (equilibrium of every horizontal cut), within 2 %.

mod common;

#[test]
fn the_stress_patch_carries_one_newton_per_metre() {
    let mut sim = common::bundled("stress_patch.ron");
    for _ in 0..sim.counts().time.frames {
        sim.step_frame().unwrap_or_else(|e| panic!("{e}"));
    }
    let probe = |name: &str| sim.probes().get(name).unwrap_or_else(|| panic!("no probe {name}"));
    let stress = probe("mean_stress_n_per_m");
    assert!((stress - 1.0).abs() < 0.02, "mean stress {stress} N/m");
    // The held edge carries the whole 1 N load.
    let pin_force = probe("pin_force_n");
    assert!((pin_force - 1.0).abs() < 0.005, "pins carry {pin_force} N");
    assert!(probe("kinetic_energy_j") < 1e-9, "at rest");
}
