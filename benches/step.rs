//! Criterion benchmarks: one whole step of a hanging grid cloth through the engine (64×64
//! and 256×256 particles), and the kernels alone at 1 k, 16 k and 65 k particles.

use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

use criterion::{Bencher, BenchmarkId, Criterion, criterion_group, criterion_main};
use glam::{Affine3A, Vec3};
use selvedge::Simulation;
use selvedge::builders::ClothData;
use selvedge::builders::grid::build_grid;
use selvedge::collision::intersection::IntersectionCounter;
use selvedge::components::{BendingDesc, BendingLawDesc, ClothMaterial, ClothTopology, MembraneDesc, SolverParts};
use selvedge::pool::run_awake;
use selvedge::scene::parse_scene;
use selvedge::solver::contact_springs::{ContactSpring, Outside, Stencil, Weights, add_diagonal};
use selvedge::solver::descent::{DescentSettings, DescentWorkspace, descend};
use selvedge::solver::elements::{SymmetricBlockMatrix, VelocityJacobian};
use selvedge::solver::filter::Filters;
use selvedge::solver::forces::{Air, ClothDynamics, ForceModel, ForceScratch};
use selvedge::solver::implicit::StepSystem;
use selvedge::solver::integrate::{Integrator, IntegratorWorkspace, MethodSettings, step};
use selvedge::solver::multigrid::Multigrid;
use selvedge::solver::probes::most_stretched_edge;
use selvedge::solver::spring_couplings::SpringCouplings;

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

/// Particles per side of the kernel benches: about 1 k, 16 k and 65 k particles.
const KERNEL_SIZES: [u32; 3] = [32, 128, 256];

/// A flat n × n sheet of the `selvedge bench` material bending by `law`, and its topology.
struct Sheet {
    cloth: ClothData,
    topology: ClothTopology,
}

impl Sheet {
    fn new(n: u32, law: BendingLawDesc) -> Self {
        let material = ClothMaterial {
            density: 0.2,
            stretch: None,
            shear: None,
            bend: None,
            membrane: Some(MembraneDesc::Isotropic { young: 2666.667, poisson: 1.0 / 3.0 }),
            bending: Some(BendingDesc { warp: 1e-5, weft: 1e-5, twist: None, law }),
        };
        let mut cloth = build_grid((1.0, 1.0), (n, n), Affine3A::IDENTITY, &material);
        cloth.add_surface_elements(&material, Vec3::X).expect("a flat sheet");
        let topology =
            ClothTopology::build(&cloth.particles.inv_mass, cloth.elements(), &[], 1, SolverParts::default());
        Self { cloth, topology }
    }

    fn model(&self) -> ForceModel<'_> {
        let cloth = &self.cloth;
        ForceModel {
            inv_mass: &cloth.particles.inv_mass,
            density: 0.2,
            springs: &cloth.springs,
            triangles: &cloth.triangles.indices,
            hinges: &cloth.hinges,
            membranes: &cloth.membranes,
            topology: &self.topology,
            gravity: Vec3::new(0.0, -9.81, 0.0),
            air: Air::default(),
            user_forces: &[],
        }
    }
}

/// The kernels alone on the material of the `selvedge bench` scenes (membrane μ = λ =
/// 1000 N/m, bending 1e-5 N·m, 0.2 kg/m²): force evaluation, the per-frame probes
/// (potential energy, largest strain, self-intersection count), derivative assembly, one
/// symmetric block-descent sweep and one multigrid V-cycle over the implicit-Euler system
/// at 1/60 s, the contact springs' product, the multigrid's prepare and V-cycle with
/// them as in a heap, and whole steps of three integrators, each timed on a worker of
/// rayon's pool ([`on_pool`]); and the forces and derivatives again with `law: Quadratic`.
fn kernels(c: &mut Criterion) {
    let mut group = c.benchmark_group("kernels");
    group.sample_size(20);
    for n in KERNEL_SIZES {
        let sheet = Sheet::new(n, BendingLawDesc::Linear);
        let (cloth, topology, model) = (&sheet.cloth, &sheet.topology, sheet.model());
        let count = cloth.particles.len();
        let size = format!("{count}");
        let mut scratch = ForceScratch::default();
        let mut force = vec![Vec3::ZERO; count];
        // A sagging, slightly stretched state, so that every element is loaded.
        let x: Vec<Vec3> = cloth.particles.position.iter().map(|p| *p * 1.01 + Vec3::Z * 0.1 * p.x * p.x).collect();
        let v = vec![Vec3::ZERO; count];
        group.bench_function(BenchmarkId::new("forces", &size), |b| {
            on_pool(b, || model.eval(black_box(&x), &v, 0.0, &mut scratch, &mut force));
        });
        group.bench_function(BenchmarkId::new("probes/potential_energy", &size), |b| {
            on_pool(b, || model.potential_energy(black_box(&x), &mut scratch));
        });
        group.bench_function(BenchmarkId::new("probes/max_strain", &size), |b| {
            on_pool(b, || {
                most_stretched_edge(black_box(&x), &cloth.particles.rest_position, &cloth.springs, &cloth.membranes)
            });
        });
        let mut counter = IntersectionCounter::default();
        group.bench_function(BenchmarkId::new("probes/self_intersections", &size), |b| {
            on_pool(b, || counter.count(black_box(&x), &cloth.triangles.indices));
        });
        let (mut dfdx, mut dfdv) = (SymmetricBlockMatrix::default(), VelocityJacobian::default());
        group.bench_function(BenchmarkId::new("derivatives", &size), |b| {
            on_pool(b, || model.assemble(black_box(&x), &v, 0.0, true, &mut scratch, &mut force, &mut dfdx, &mut dfdv));
        });
        {
            let quadratic = Sheet::new(n, BendingLawDesc::Quadratic);
            let model = quadratic.model();
            let mut scratch = ForceScratch::default();
            group.bench_function(BenchmarkId::new("forces/quadratic", &size), |b| {
                on_pool(b, || model.eval(black_box(&x), &v, 0.0, &mut scratch, &mut force));
            });
            group.bench_function(BenchmarkId::new("derivatives/quadratic", &size), |b| {
                on_pool(b, || {
                    model.assemble(black_box(&x), &v, 0.0, true, &mut scratch, &mut force, &mut dfdx, &mut dfdv);
                });
            });
        }
        // Assembled here too, so that a filter that skips the bench above leaves a system.
        model.assemble(&x, &v, 0.0, true, &mut scratch, &mut force, &mut dfdx, &mut dfdv);
        let h = 1.0 / 60.0f32;
        let pattern = &topology.pattern;
        let mut system = SymmetricBlockMatrix { blocks: dfdx.blocks.iter().map(|k| -h * h * *k).collect() };
        system.add_diagonal(pattern, |i| 1.0 / cloth.particles.inv_mass[i]);
        let rhs: Vec<Vec3> = force.iter().map(|f| h * *f).collect();
        let filter = Filters::free(count);
        let one_sweep = DescentSettings { sweeps: 1, spectral_radius: 0.0, contact_bounds: false };
        let mut descent = DescentWorkspace::default();
        let mut delta = vec![Vec3::ZERO; count];
        group.bench_function(BenchmarkId::new("matrix_product", &size), |b| {
            on_pool(b, || system.multiply(pattern, black_box(&rhs), &mut delta));
        });
        // One V-cycle of the multigrid preconditioner on the same system (its levels
        // built once, outside the timing): with the product above, what an iteration of
        // the hang scenes' conjugate gradients costs.
        let elements = cloth.elements();
        let hierarchy = topology.hierarchy(elements);
        let system_at = StepSystem::new(pattern, &system);
        let mut multigrid = Multigrid::default();
        multigrid.prepare(hierarchy, system_at, &filter, &x, None, false);
        group.bench_function(BenchmarkId::new("v_cycle", &size), |b| {
            on_pool(b, || multigrid.apply(hierarchy, system_at, &filter, black_box(&rhs), &mut delta, None));
        });
        // The same sheet as a heap, folded in thought: a contact spring holds each vertex
        // of its lower half off the triangle mirrored across the fold, half as many springs
        // as particles (untangle_layers holds three a particle). What a step's lagged
        // solve prepares again (the springs' coarse sums, smoothers and coarsest factor,
        // the levels kept), and a V-cycle with them.
        let springs = folded_springs(n);
        let weights = Weights { stiffness: h * h, drag: h };
        let mut heap = system.clone();
        add_diagonal(&springs, weights, pattern, &mut heap);
        let heap_at = StepSystem::new(pattern, &heap);
        let mut couplings = SpringCouplings::default();
        couplings.prepare(Some(&springs), weights, count);
        // Their off-diagonal blocks' product, which each product of the heap's system adds.
        let mut pushes = Vec::new();
        group.bench_function(BenchmarkId::new("springs_product", &size), |b| {
            on_pool(b, || couplings.set_product(black_box(&rhs), &mut pushes, &mut delta));
        });
        let mut multigrid = Multigrid::default();
        multigrid.prepare(hierarchy, heap_at, &filter, &x, Some(&couplings), false);
        group.bench_function(BenchmarkId::new("multigrid/springs_changed", &size), |b| {
            on_pool(b, || {
                couplings.prepare(Some(black_box(&springs)), weights, count);
                multigrid.prepare(hierarchy, heap_at, &filter, black_box(&x), Some(&couplings), true);
            });
        });
        group.bench_function(BenchmarkId::new("v_cycle/heap", &size), |b| {
            on_pool(b, || multigrid.apply(hierarchy, heap_at, &filter, black_box(&rhs), &mut delta, Some(&couplings)));
        });
        group.bench_function(BenchmarkId::new("descent_sweep", &size), |b| {
            on_pool(b, || {
                descend(
                    StepSystem::new(pattern, &system),
                    topology.colouring(elements),
                    &rhs,
                    &filter,
                    &one_sweep,
                    0.0,
                    None,
                    &mut delta,
                    &mut descent,
                )
            });
        });
        let settings = MethodSettings::default();
        for method in [Integrator::SymplecticEuler, Integrator::ImplicitEuler, Integrator::BlockDescent] {
            let mut dynamics = ClothDynamics {
                model,
                free_inv_mass: &topology.free_inv_mass,
                scratch: &mut scratch,
                self_collision: None,
                others: None,
                contact_springs: &mut [],
                bodies: &[],
                start_force: None,
            };
            let mut ws = IntegratorWorkspace::default();
            ws.resize(count, method);
            let (mut x, mut v) = (x.clone(), v.clone());
            group.bench_function(BenchmarkId::new(format!("integrate/{}", method.name()), &size), |b| {
                on_pool(b, || {
                    step(method, &mut dynamics, &mut [], None, &mut x, &mut v, 0.0, 1e-5, &settings, &mut ws)
                        .expect("fixed step")
                });
            });
        }
    }
    group.finish();
}

/// A contact spring from each vertex of the lower half of an `n × n` grid to the
/// triangle mirrored across its middle row, as layers of a heap are joined: far apart in
/// the sheet's pattern.
fn folded_springs(n: u32) -> Vec<ContactSpring> {
    (0..n / 2 - 1)
        .flat_map(|row| (0..n - 1).map(move |column| (row, column)))
        .map(|(row, column)| {
            let (p, q) = (row * n + column, (n - 1 - row) * n + column);
            ContactSpring {
                stencil: Stencil::point_triangle(p, [q, q + 1, q - n], [0.2, 0.5, 0.3]),
                normal: Vec3::Z,
                gap: 0.002,
                stiffness: 500.0,
                friction: 0.3,
                drag: 20.0,
                armed: 0.0,
                outside: Outside::default(),
            }
        })
        .collect()
}

/// Times `work` on a worker of rayon's pool with the other workers kept awake, as the
/// engine's frames run ([`Simulation::step_frame`], [`run_awake`]): a parallel loop
/// started from any other thread pays for waking a worker and sleeping until it is done,
/// which the engine does not (timed that way, the derivative assembly of a 128² sheet
/// took 32 ms on two threads, not 22).
fn on_pool<R>(b: &mut Bencher, mut work: impl FnMut() -> R + Send) {
    b.iter_custom(|iterations| {
        run_awake(|| {
            let start = Instant::now();
            for _ in 0..iterations {
                black_box(work());
            }
            start.elapsed()
        })
    });
}

criterion_group!(benches, whole_step, kernels);
criterion_main!(benches);
