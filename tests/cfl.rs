//! Zheng's adaptive step (Z4): velocity Verlet splits each step so that no sub-step
//! exceeds `α Δx √(ρ/E)`, which keeps a stiff membrane stable at a frame-sized scene step
//! where the plain method diverges.

mod common;

use selvedge::Simulation;

fn cotton_sheet(cfl: &str) -> Simulation {
    common::simulation(&format!(
        "Scene(name: \"cfl\", solver: (integrator: VelocityVerlet, substeps: 1{cfl}), time: (fps: 60, frames: 30),
          cloths: [(name: \"sheet\", shape: Grid(size: (0.5, 0.5), resolution: (16, 16)),
                    placement: (translation: (0.0, 1.0, 0.0)), fabric: Named(Cotton),
                    pins: [Corners([TopLeft, TopRight])])])"
    ))
}

#[test]
fn the_adaptive_step_keeps_a_stiff_membrane_stable_at_sixty_frames_per_second() {
    let mut plain = cotton_sheet("");
    let diverged = (0..30).try_for_each(|_| plain.step_frame());
    assert!(diverged.is_err(), "plain Verlet at 1/60 s should diverge on a 2000 N/m membrane");

    let mut adaptive = cotton_sheet(", cfl: 0.5");
    common::run_frames(&mut adaptive, 30);
    // Δx = 0.5/15 m at rest, ρ = 0.2578 kg/m², E = 2000 N/m: the limit is
    // 0.5 · 0.0333 · 0.01135 = 1.89e-4 s, so about 88 sub-steps a frame (more as the
    // cloth compresses).
    let per_frame = adaptive.integrator_stats().accepted as f64 / 30.0;
    let rest_limit = 0.5 * (0.5 / 15.0) * (0.2578f64 / 2000.0).sqrt();
    let expected = ((1.0 / 60.0) / rest_limit).ceil();
    assert!(per_frame >= expected && per_frame < 1.5 * expected, "{per_frame} sub-steps a frame, at rest {expected}");
    assert!(common::probe(&adaptive, "max_strain") < 0.2, "bounded");
}
