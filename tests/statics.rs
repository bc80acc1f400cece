//! Statics: a damped hanging cloth comes to rest with its pins carrying its weight.

mod common;

use selvedge::Simulation;

const DENSITY: f64 = 0.2;
const G: f64 = 9.81;

#[test]
fn a_hanging_cloth_comes_to_rest_and_the_pins_carry_its_weight() {
    let mut sim = common::simulation(&format!(
        "Scene(name: \"hang\", gravity: (0.0, -9.81, 0.0), air: (drag: 4.0),
          solver: (integrator: SymplecticEuler, substeps: 20), time: (fps: 60, duration_s: 10.0),
          cloths: [(name: \"c\", shape: Grid(size: (1.0, 1.0), resolution: (16, 16)),
                    placement: (translation: (0.0, 2.0, 0.0)),
                    material: {}, pins: [Corners([TopLeft, TopRight])])])",
        common::material(100.0, 0.05)
    ));
    common::run_frames(&mut sim, 600);
    assert_at_rest_on_its_pins(&sim);
}

/// The 1 m² cloth of `sim` has come to rest (kinetic energy below 1 µJ) with its pins
/// carrying its weight within 0.5 %.
fn assert_at_rest_on_its_pins(sim: &Simulation) {
    let weight = DENSITY * 1.0 * G;
    let kinetic = common::probe(sim, "kinetic_energy_j");
    let pin_force = common::probe(sim, "pin_force_n");
    assert!(kinetic < 1e-6, "still moving: kinetic energy {kinetic} J");
    assert!((pin_force - weight).abs() < 0.005 * weight, "pins carry {pin_force} N, the cloth weighs {weight} N");
    eprintln!("pin force {pin_force} N, weight {weight} N, kinetic energy {kinetic:e} J");
}

/// A scene that names no integrator gets the default, implicit Euler at 10 steps a frame.
/// A stiff membrane (10⁴ N/m), which an explicit method cannot take at that step (the
/// same scene with `SymplecticEuler` diverges), hangs and comes to rest with its pins
/// carrying its weight.
#[test]
fn a_stiff_membrane_hangs_at_rest_with_the_default_solver() {
    let scene = |solver: &str| {
        format!(
            "Scene(name: \"hang\", gravity: (0.0, -9.81, 0.0), air: (drag: 4.0), {solver}
              time: (fps: 60, duration_s: 10.0),
              cloths: [(name: \"c\", shape: Grid(size: (1.0, 1.0), resolution: (16, 16)),
                        placement: (translation: (0.0, 2.0, 0.0)),
                        material: (density: 0.2, membrane: Isotropic(young: 10000.0, poisson: 0.3),
                                   bending: (warp: 1.0e-5, weft: 1.0e-5)),
                        pins: [Corners([TopLeft, TopRight])])])"
        )
    };
    let mut explicit = common::simulation(&scene("solver: (integrator: SymplecticEuler),"));
    let diverged = (0..60).try_for_each(|_| explicit.step_frame());
    assert!(diverged.is_err(), "symplectic Euler at 10 steps a frame should diverge on a 10⁴ N/m membrane");

    let mut sim = common::simulation(&scene(""));
    common::run_frames(&mut sim, 600);
    assert_at_rest_on_its_pins(&sim);
}
