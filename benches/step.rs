//! Criterion benchmarks: one whole step of a hanging grid cloth through the engine, and
//! the force and integration kernels alone, at 64×64 and 256×256 particles.

use std::hint::black_box;
use std::path::Path;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use glam::{Affine3A, Vec3};
use selvedge::Simulation;
use selvedge::builders::grid::build_grid;
use selvedge::components::{ClothMaterial, ClothTopology, SpringCoefficients};
use selvedge::scene::parse_scene;
use selvedge::solver::forces::{Air, ClothDynamics, ForceModel, ForceScratch};
use selvedge::solver::integrate::{Integrator, IntegratorWorkspace, MethodSettings, step};

const SIZES: [u32; 2] = [64, 256];

/// A hanging cloth whose frame is a single step, so a frame measures one step. The step
/// shrinks with the spacing, as explicit integration of stiff springs requires.
fn hanging(n: u32) -> Simulation {
    let fps = 100 * n;
    let text = format!(
        "Scene(name: \"bench\", air: (drag: 1.0), solver: (integrator: SymplecticEuler, substeps: 1),
          time: (fps: {fps}, frames: 1000),
          cloths: [(name: \"c\", shape: Grid(size: (1.0, 1.0), resolution: ({n}, {n})),
                    material: (density: 0.2, stretch: (stiffness: 100.0, damping: 0.01),
                               shear: (stiffness: 10.0), bend: (stiffness: 1.0)),
                    pins: [Corners([TopLeft, TopRight])])])"
    );
    let scene = parse_scene(&text, Path::new("bench.ron")).expect("valid bench scene");
    Simulation::new(&scene, Path::new(".")).expect("bench scene builds")
}

fn whole_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("step");
    group.sample_size(20);
    for n in SIZES {
        let mut sim = hanging(n);
        group.bench_function(BenchmarkId::new("hang", format!("{n}x{n}")), |b| {
            b.iter(|| sim.step_frame().expect("stable"));
        });
    }
    group.finish();
}

fn kernels(c: &mut Criterion) {
    let coefficients = SpringCoefficients { stiffness: 100.0, damping: 0.01 };
    let springs = Some(coefficients);
    let material =
        ClothMaterial { density: 0.2, stretch: springs, shear: springs, bend: springs, membrane: None, bending: None };
    let mut group = c.benchmark_group("kernels");
    group.sample_size(20);
    for n in SIZES {
        let cloth = build_grid((1.0, 1.0), (n, n), Affine3A::IDENTITY, &material);
        let count = cloth.particles.len();
        let topology = ClothTopology::build(
            &cloth.particles.inv_mass,
            &cloth.springs,
            &cloth.triangles,
            &cloth.hinges,
            &cloth.membranes,
            &[],
            1,
        );
        let model = ForceModel {
            inv_mass: &cloth.particles.inv_mass,
            density: material.density,
            springs: &cloth.springs,
            triangles: &cloth.triangles.indices,
            hinges: &cloth.hinges,
            membranes: &cloth.membranes,
            topology: &topology,
            gravity: Vec3::new(0.0, -9.81, 0.0),
            air: Air { drag: 1.0, wind: Vec3::X, wind_drag: 0.6, gust: None, area_damping: 0.0 },
            user_forces: &[],
        };
        let mut scratch = ForceScratch::default();
        let mut force = vec![Vec3::ZERO; count];
        let (x, v) = (cloth.particles.position.clone(), vec![Vec3::ZERO; count]);
        group.bench_function(BenchmarkId::new("forces", format!("{n}x{n}")), |b| {
            b.iter(|| model.eval(black_box(&x), &v, 0.0, &mut scratch, &mut force));
        });
        let settings = MethodSettings::default();
        for method in [Integrator::SymplecticEuler, Integrator::Rk4, Integrator::ImplicitEuler] {
            let mut dynamics = ClothDynamics { model, free_inv_mass: &topology.free_inv_mass, scratch: &mut scratch };
            let mut ws = IntegratorWorkspace::default();
            ws.resize(count);
            let (mut x, mut v) = (x.clone(), v.clone());
            group.bench_function(BenchmarkId::new(format!("integrate/{}", method.name()), format!("{n}x{n}")), |b| {
                b.iter(|| {
                    step(method, &mut dynamics, &[], &mut x, &mut v, 0.0, 1e-5, &settings, &mut ws).expect("fixed step")
                });
            });
        }
    }
    group.finish();
}

criterion_group!(benches, whole_step, kernels);
criterion_main!(benches);
