//! Cusick's drape test: a 30 cm disk of each Bricis fabric clamped on an 18 cm pedestal.
//! The drape coefficients are distinct and ordered like the fabrics' bending lengths
//! (geometric mean of warp and weft): stiffer, heavier-to-bend fabrics drape less.

mod common;

use selvedge::fabrics::FabricName;

fn drape_coefficient(fabric: FabricName) -> f64 {
    let name = format!("cusick_{}.ron", format!("{fabric:?}").to_lowercase());
    let mut sim = common::bundled(&name);
    for _ in 0..sim.counts().time.frames {
        sim.step_frame().unwrap_or_else(|e| panic!("{e}"));
    }
    assert!(sim.probes().get("kinetic_energy_j").expect("probe") < 1e-8, "{fabric:?} has not settled");
    sim.probes().get("drape_coefficient").expect("the scene asks for it")
}

#[test]
fn drape_coefficients_are_distinct_and_follow_the_bending_length() {
    let mut results: Vec<(f32, f64, FabricName)> = FabricName::ALL
        .into_iter()
        .map(|fabric| {
            let (warp, weft) = fabric.measurements().bending_length();
            ((warp * weft).sqrt(), drape_coefficient(fabric), fabric)
        })
        .collect();
    results.sort_by(|a, b| a.0.total_cmp(&b.0));
    eprintln!("(bending length [m], drape coefficient, fabric): {results:?}");
    for (_, dc, fabric) in &results {
        assert!((0.0..1.0).contains(dc), "{fabric:?}: drape coefficient {dc}");
    }
    for pair in results.windows(2) {
        assert!(
            pair[1].1 > pair[0].1 + 1e-3,
            "{:?} (c = {:.4} m) drapes to {:.4}, not above {:?} (c = {:.4} m) at {:.4}",
            pair[1].2,
            pair[1].0,
            pair[1].1,
            pair[0].2,
            pair[0].0,
            pair[0].1
        );
    }
}
