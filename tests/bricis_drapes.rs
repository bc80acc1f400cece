//! Bricis's drapes over solids (B6), checked by their end state: on a table corner the
//! cloth rests on the top and hangs over both edges that meet at the corner; over a
//! cylinder a disk rests on the top and hangs down around it. Nothing ends inside a body
//! or through itself.

mod common;

use glam::Vec3;
use selvedge::Simulation;
use selvedge::components::Particles;

const TABLE_TOP: f32 = 0.75;

fn settle(name: &str) -> (Simulation, Vec<Vec3>) {
    let mut sim = common::bundled(name);
    for _ in 0..sim.counts().time.frames {
        sim.step_frame().unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    let positions = sim.world_mut().query::<&Particles>().single(sim.world()).expect("one cloth").position.clone();
    (sim, positions)
}

/// Where the hanging cloth folds, it has not passed through itself.
fn untangled(name: &str, sim: &Simulation) {
    let crossed = sim.probes().get("self_intersections").expect("probe");
    assert_eq!(crossed, 0.0, "{name}: {crossed} pairs of triangles cross");
}

#[test]
fn table_corner_drapes_rest_on_the_top_and_hang_over_both_edges() {
    for name in ["bricis_table_cotton.ron", "bricis_table_polyester.ron", "bricis_table_mat.ron"] {
        let (mut sim, x) = settle(name);
        // Where it hangs over the edges, no cloth triangle cuts across the table's rim.
        let crossed = common::body_crossings(&mut sim, "table");
        assert_eq!(crossed, 0, "{name}: {crossed} cloth triangles cross the table");
        let kinetic = sim.probes().get("kinetic_energy_j").expect("probe");
        assert!(kinetic < 1e-3, "{name}: still moving, {kinetic} J");
        untangled(name, &sim);
        // Over the table (away from its edges) the cloth lies on the top, never in it.
        let over: Vec<&Vec3> = x.iter().filter(|p| p.x < -0.03 && p.z < -0.03).collect();
        assert!(over.len() > x.len() / 3, "{name}: only {} particles over the table", over.len());
        assert!(over.iter().all(|p| p.y >= TABLE_TOP), "{name}: cloth inside the table");
        // Most of it lies flat on the top (the stiff mat lifts near the corner, where it
        // bends over both edges at once).
        let resting = over.iter().filter(|p| p.y < TABLE_TOP + 0.003).count();
        assert!(resting * 4 >= over.len() * 3, "{name}: {resting} of {} rest on the top", over.len());
        // Over each edge the 0.1 m overhang hangs down by more than half its length.
        // (Friction keeps the cloth where it landed, so the overhang is what the scene
        // placed; the stiff mat, bending length 5.4 cm, droops 8.7 cm of its 10.)
        let lowest =
            |beyond: &dyn Fn(&Vec3) -> bool| x.iter().filter(|p| beyond(p)).map(|p| p.y).fold(f32::INFINITY, f32::min);
        assert!(lowest(&|p| p.x > 0.02) < TABLE_TOP - 0.05, "{name}: nothing hangs over the x edge");
        assert!(lowest(&|p| p.z > 0.02) < TABLE_TOP - 0.05, "{name}: nothing hangs over the z edge");
    }
}

#[test]
fn a_disk_rests_on_a_cylinder_and_hangs_around_it() {
    let (sim, x) = settle("bricis_cylinder.ron");
    untangled("bricis_cylinder.ron", &sim);
    let radial = |p: &Vec3| Vec3::new(p.x, 0.0, p.z).length();
    let top: Vec<&Vec3> = x.iter().filter(|p| radial(p) < 0.1).collect();
    assert!(top.iter().all(|p| (p.y - 0.5).abs() < 0.003), "the centre rests on the top at 0.5 m");
    assert!(x.iter().all(|p| radial(p) > 0.119 || p.y >= 0.5), "nothing inside the cylinder");
    assert!(x.iter().map(|p| p.y).fold(f32::INFINITY, f32::min) < 0.42, "the rim hangs down");
    // The cylinder carries the whole weight: π 0.25² m² × 0.2578 kg/m² × 9.81 m/s².
    let weight = std::f64::consts::PI * 0.0625 * 0.2578 * 9.81;
    let force = sim.probes().get("contact_force_n").expect("probe");
    assert!((force - weight).abs() < 0.02 * weight, "contact force {force} N, weight {weight} N");
}
