//! Finite-difference helpers for the element tests.

use glam::{Mat3, Vec3};

use super::block::upper_pair;

/// Central difference gradient of `f` at `x` with a step relative to the scale of `x`.
pub fn central_difference(f: impl Fn(Vec3) -> f32, x: Vec3) -> Vec3 {
    let h = 1e-3 * x.length().max(0.1);
    let mut gradient = Vec3::ZERO;
    for axis in 0..3 {
        let mut step = Vec3::ZERO;
        step[axis] = h;
        gradient[axis] = (f(x + step) - f(x - step)) / (2.0 * h);
    }
    gradient
}

/// Asserts `|actual − expected| ≤ tolerance · max(|expected|, floor)` with a floor that
/// keeps near-zero comparisons meaningful in f32.
pub fn assert_close(actual: Vec3, expected: Vec3, tolerance: f32, what: &str) {
    let scale = expected.length().max(actual.length()).max(1e-2);
    assert!(
        (actual - expected).length() <= tolerance * scale + 1e-4,
        "{what}: analytic {actual} against finite difference {expected}"
    );
}

/// An element's full `N × N` blocks from those on and above its diagonal (in
/// `upper_pairs` order), each one below its mirror transposed.
pub fn full_blocks<const N: usize, const M: usize>(upper: &[Mat3; M]) -> [[Mat3; N]; N] {
    std::array::from_fn(|a| {
        std::array::from_fn(|b| {
            let block = upper[upper_pair::<N>(a, b)];
            if a <= b { block } else { block.transpose() }
        })
    })
}
