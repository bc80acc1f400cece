//! Untangling (Z6): two cloths placed through each other (`scenes/untangle_layers.ron`)
//! end apart, in the order their layers give, after falling onto the ground. The layer
//! number decides the order: swapping the layers swaps which cloth ends on top. The exact
//! triangle–triangle test over both cloths together, independent of the contact code,
//! counts the crossings.

mod common;

use glam::Vec3;
use selvedge::Simulation;
use selvedge::collision::intersection::count_self_intersections;
use selvedge::components::{Cloth, Particles, Triangles};

/// Both cloths as one mesh, and the positions of the cloth named `name`.
fn state(sim: &mut Simulation, name: &str) -> (Vec<Vec3>, Vec<[u32; 3]>, Vec<Vec3>) {
    let world = sim.world_mut();
    let mut query = world.query::<(&Cloth, &Particles, &Triangles)>();
    let (mut x, mut triangles, mut named) = (Vec::new(), Vec::new(), Vec::new());
    for (cloth, particles, tris) in query.iter(world) {
        let offset = x.len() as u32;
        triangles.extend(tris.indices.iter().map(|t| t.map(|k| k + offset)));
        x.extend_from_slice(&particles.position);
        if cloth.name == name {
            named = particles.position.clone();
        }
    }
    (x, triangles, named)
}

/// Runs the scene with `over`'s and `under`'s layers as given; returns the crossings at
/// the start and at the end, after checking that `top` lies above the other cloth
/// wherever one is over the other.
fn run(over_layer: u32, under_layer: u32, top: &str) -> (usize, usize) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/untangle_layers.ron");
    let text = std::fs::read_to_string(path)
        .expect("bundled scene")
        .replace("layer: 0)", "layer: UNDER)")
        .replace("layer: 1)", &format!("layer: {over_layer})"))
        .replace("layer: UNDER)", &format!("layer: {under_layer})"));
    let mut sim = common::simulation(&text);
    let (x, triangles, _) = state(&mut sim, top);
    let start = count_self_intersections(&x, &triangles);
    let frames = sim.counts().time.frames;
    common::run_frames(&mut sim, frames);
    let (x, triangles, upper) = state(&mut sim, top);
    let bottom = if top == "over" { "under" } else { "over" };
    let (_, _, lower) = state(&mut sim, bottom);
    for p in &upper {
        let horizontal = |q: &Vec3| Vec3::new(q.x - p.x, 0.0, q.z - p.z).length();
        let below = lower.iter().min_by(|a, b| horizontal(a).total_cmp(&horizontal(b))).expect("vertices");
        if horizontal(below) < 0.01 {
            assert!(p.y > below.y, "`{top}` ends on top: {p} is not above {below}");
        }
    }
    (start, count_self_intersections(&x, &triangles))
}

#[test]
fn layers_placed_through_each_other_end_apart_in_layer_order() {
    let (start, end) = run(1, 0, "over");
    assert!(start > 0, "the scene starts tangled");
    assert_eq!(end, 0, "{start} crossing triangle pairs at the start, {end} at the end");
}

#[test]
fn swapping_the_layers_swaps_the_order() {
    let (start, end) = run(0, 1, "under");
    assert!(start > 0);
    assert_eq!(end, 0, "{start} crossing triangle pairs at the start, {end} at the end");
}
