//! Free fall: y(t) = y0 − g t²/2, for a lone particle through each integrator kernel and
//! for a whole unpinned cloth through the engine.

mod common;

use common::oscillator::{ParticleSystem, with_tolerance};
use glam::Vec3;
use selvedge::components::{Particles, Springs};
use selvedge::solver::integrate::Integrator;

const G: f32 = 9.81;

/// Drops one particle from rest at 100 m for 1 s in steps of `h`; returns (y, v).
fn drop_particle(method: Integrator, h: f32) -> (f32, f32) {
    let system =
        ParticleSystem::new(vec![Vec3::new(0.0, 100.0, 0.0)], &[1.0], Springs::default(), &[], Vec3::new(0.0, -G, 0.0));
    let (x, v, _) = system.run(method, f64::from(h), 1.0, &with_tolerance(1e-5));
    (x[0].y, v[0].y)
}

#[test]
fn a_free_particle_falls_as_each_method_predicts() {
    let h = 0.01;
    let exact_y = 100.0 - 0.5 * G;
    // f32 rounding over 100 steps at 100 m.
    let rounding = 2e-4;
    for method in Integrator::ALL {
        let (y, v) = drop_particle(method, h);
        assert!((v + G).abs() < 1e-4, "{method:?}: v = {v}, expected {}", -G);
        // Symplectic and implicit Euler (block descent solves the same step) move with the
        // updated velocity, explicit Euler with the old one: each is off by exactly
        // g h t / 2, in opposite directions. Every other method (Newmark's trapezoidal rule
        // included) integrates constant acceleration exactly.
        let offset = match method {
            Integrator::SymplecticEuler | Integrator::ImplicitEuler | Integrator::BlockDescent => -0.5 * G * h,
            Integrator::ExplicitEuler => 0.5 * G * h,
            _ => 0.0,
        };
        assert!(
            (y - (exact_y + offset)).abs() < rounding,
            "{method:?}: y = {y}, expected {} (analytic {exact_y} with its first-order offset {offset})",
            exact_y + offset
        );
    }
}

fn cloth_free_fall(integrator: &str) -> (Vec<Vec3>, Vec<Vec3>, f64) {
    let mut sim = common::simulation(&format!(
        "Scene(name: \"fall\", solver: (integrator: {integrator}, substeps: 10), time: (fps: 60, frames: 60),
          cloths: [(name: \"c\", shape: Grid(size: (1.0, 1.0), resolution: (12, 12)),
                    placement: (translation: (0.0, 20.0, 0.0), rotation_deg: (90.0, 0.0, 0.0)),
                    material: {})])",
        common::material(200.0, 0.1)
    ));
    let start = sim.world_mut().query::<&Particles>().single(sim.world()).expect("one cloth").position.clone();
    common::run_frames(&mut sim, 60);
    let end = sim.world_mut().query::<&Particles>().single(sim.world()).expect("one cloth").position.clone();
    (start, end, sim.clock().time_s)
}

#[test]
fn an_unpinned_cloth_falls_as_one_body_under_velocity_verlet() {
    let (start, end, t) = cloth_free_fall("VelocityVerlet");
    assert!((t - 1.0).abs() < 1e-6);
    let drop = 0.5 * G * (t as f32).powi(2);
    for (a, b) in start.iter().zip(&end) {
        assert!((b.y - (a.y - drop)).abs() < 2e-4, "y {} → {}, expected drop {drop}", a.y, b.y);
        assert!((b.x - a.x).abs() < 1e-5 && (b.z - a.z).abs() < 1e-5, "no sideways motion");
    }
}

#[test]
fn an_unpinned_cloth_under_symplectic_euler_has_only_its_first_order_offset() {
    let (start, end, t) = cloth_free_fall("SymplecticEuler");
    let h = 1.0 / 600.0;
    let drop = 0.5 * G * (t as f32).powi(2) + 0.5 * G * h * t as f32;
    for (a, b) in start.iter().zip(&end) {
        assert!((b.y - (a.y - drop)).abs() < 2e-4, "y {} → {}, expected drop {drop}", a.y, b.y);
    }
}
