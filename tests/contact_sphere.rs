//! Zheng's sphere drape (§3.7.2): a cloth settled on a sphere is held by a frame-averaged
//! contact force equal to its weight (0.144 × 0.16 × 9.8 = 0.2258 N) within 2 %, and no
//! particle goes deeper into the sphere than the contact thickness.

mod common;

#[test]
fn the_contact_force_converges_to_the_weight_without_penetration() {
    let mut sim = common::bundled("zheng_sphere.ron");
    let weight = 0.144 * 0.4 * 0.4 * 9.8;
    let thickness = 0.001177;
    let frames = sim.counts().time.frames;
    for frame in 1..=frames {
        sim.step_frame().unwrap_or_else(|e| panic!("{e}"));
        let probe = |name: &str| sim.probes().get(name).unwrap_or_else(|| panic!("no probe {name}"));
        assert!(probe("max_penetration_m") <= thickness, "frame {frame}: {} m deep", probe("max_penetration_m"));
        if frame + 15 > frames {
            let force = probe("contact_force_n");
            assert!(
                (force - weight).abs() < 0.02 * weight,
                "frame {frame}: contact force {force} N, weight {weight} N"
            );
        }
    }
}
