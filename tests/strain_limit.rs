//! Strain limiting on Zheng's corner-kidnapped cloth (§5.6.1): with soft stretch springs
//! (k/ρ = 100 m²/s²) a 1 % limit keeps the largest strain within 1.5 % through the swing,
//! while without it the cloth stretches tens of percent (Zheng's table 5.1: 220 %).

mod common;

/// Runs a bundled scene and returns the largest `max_strain` over all its frames.
fn peak_strain(name: &str) -> f64 {
    let mut sim = common::bundled(name);
    let mut peak = 0.0f64;
    for _ in 0..sim.counts().time.frames {
        sim.step_frame().unwrap_or_else(|e| panic!("{e}"));
        peak = peak.max(sim.probes().get("max_strain").expect("built-in probe"));
    }
    peak
}

#[test]
fn a_one_percent_limit_holds_the_swinging_cloth_within_one_and_a_half_percent() {
    let limited = peak_strain("corner_limited.ron");
    let unlimited = peak_strain("corner_unlimited.ron");
    assert!(limited <= 0.015, "limited cloth reached {:.2} % strain", 100.0 * limited);
    assert!(unlimited > 10.0 * limited && unlimited > 0.2, "unlimited cloth reached only {:.1} %", 100.0 * unlimited);
    eprintln!("peak strain: {:.2} % limited, {:.1} % unlimited", 100.0 * limited, 100.0 * unlimited);
}
