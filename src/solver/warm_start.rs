//! Where conjugate gradients start a step's solve: the combination of the last steps'
//! solutions nearest this step's in the system's energy norm (Fischer's projection of
//! successive right-hand sides, 1998, with the Galerkin system formed anew each step,
//! since the system changes from one step to the next).
//!
//! A step's velocity change is close to a combination of the last few: the motion is
//! smooth in time at a frame-sized step, and the combinations include the linear and
//! quadratic extrapolations. The last solution on its own is not: started from it, the
//! hang_64 bench scene took 1 107 iterations against 987 from rest, the stiff modes of
//! the difference weighing more than the whole solution. The projection cannot be worse
//! than rest in the energy norm (zero is one of the combinations), and it is the best of
//! them there. It costs a product with the system for each kept solution. The implicit
//! step uses it for multigrid's solves (ARCHITECTURE.md, "A multigrid solve starts from
//! the best combination of the last three solutions").

use glam::Vec3;
use rayon::prelude::*;

use super::PARALLEL_MIN_LEN;
use super::filter::Filters;
use super::reduce::reduce;

/// Solutions kept. Over the first 60 frames of the 256² hang scene, starting from rest
/// took 734 iterations, from the last one, two, three and four solutions 728 (the last
/// solution scaled), 674, 645 and 642. Each costs a product a step and 12 bytes a
/// particle.
pub const KEPT: usize = 3;

/// A direction whose energy is below this fraction of the largest of them is one the
/// others already span, left out of the combination.
const DEPENDENT: f64 = 1e-9;

/// The last solutions of a system and the sums that combine them.
#[derive(Debug, Clone, Default)]
pub struct WarmStart {
    /// Up to [`KEPT`] solutions, the next to be replaced at `oldest`.
    solutions: Vec<Vec<Vec3>>,
    oldest: usize,
}

impl WarmStart {
    /// Forgets the solutions, as for another system.
    pub fn forget(&mut self) {
        self.solutions.clear();
        self.oldest = 0;
    }

    /// Keeps `solution` in place of the oldest one kept.
    pub fn keep(&mut self, solution: &[Vec3]) {
        if self.solutions.first().is_some_and(|kept| kept.len() != solution.len()) {
            self.forget();
        }
        if self.solutions.len() < KEPT {
            self.solutions.push(solution.to_vec());
        } else {
            self.solutions[self.oldest].copy_from_slice(solution);
        }
        self.oldest = (self.oldest + 1) % KEPT;
    }

    /// Sets `delta` to `prescribed + Σ y_k S u_k`, `u_k` the kept solutions and `S` the
    /// `filter`, with the `y` that minimise the error's energy `‖δ − A⁻¹ b‖_A` among such
    /// combinations, the system `A` given by `multiply` (`out = A x`) and `b` by `rhs`,
    /// and `products[0]` to `A δ`, formed from the kept solutions' products rather than
    /// by another product, so that the solve's first residual needs none; the other
    /// `products` are scratch. Returns false, leaving `delta` alone, with nothing kept.
    /// The kept solutions are filtered in place: what the constraints rule out of this
    /// step is no use to the next one's start either.
    pub fn start(
        &mut self,
        filter: &Filters,
        rhs: &[Vec3],
        prescribed: &[Vec3],
        mut multiply: impl FnMut(&[Vec3], &mut [Vec3]),
        mut products: [&mut [Vec3]; KEPT],
        delta: &mut [Vec3],
    ) -> bool {
        let count = self.solutions.len();
        if count == 0 || self.solutions[0].len() != delta.len() {
            return false;
        }
        for (solution, product) in self.solutions.iter_mut().zip(products.iter_mut()) {
            solution
                .par_iter_mut()
                .enumerate()
                .with_min_len(PARALLEL_MIN_LEN)
                .for_each(|(i, u)| *u = filter.apply(i, *u));
            multiply(solution, product);
        }
        // Gram matrix G_kl = u_kᵀ A u_l (its lower triangle, row by row) and
        // c_k = u_kᵀ (b − A p), p the prescribed part: with u_k filtered, u_kᵀ S w = u_kᵀ w,
        // and u_kᵀ A p = (A u_k)ᵀ p. All in one pass, summed the same way on any number of
        // threads.
        let (solutions, kept) = (&self.solutions[..count], &products[..count]);
        let terms = |range: std::ops::Range<usize>| {
            let mut sums = [0.0f64; PAIRS + KEPT];
            for i in range {
                let p = prescribed.get(i).copied().unwrap_or(Vec3::ZERO);
                for (k, (solution, product)) in solutions.iter().zip(kept).enumerate() {
                    let w = product[i];
                    for (l, other) in solutions[..=k].iter().enumerate() {
                        sums[pair(k, l)] += f64::from(other[i].dot(w));
                    }
                    sums[PAIRS + k] += f64::from(solution[i].dot(rhs[i]) - w.dot(p));
                }
            }
            sums
        };
        let add = |mut left: [f64; PAIRS + KEPT], right: [f64; PAIRS + KEPT]| {
            left.iter_mut().zip(right).for_each(|(l, r)| *l += r);
            left
        };
        let sums = reduce(0..delta.len(), &terms, &add);
        let (mut gram, mut load) = ([[0.0f64; KEPT]; KEPT], [0.0f64; KEPT]);
        for k in 0..count {
            for l in 0..=k {
                (gram[k][l], gram[l][k]) = (sums[pair(k, l)], sums[pair(k, l)]);
            }
            load[k] = sums[PAIRS + k];
        }
        let weights = solve_dropping_dependent(gram, load, count).map(|y| y as f32);
        // A p into `delta`, which the pass below reads before it writes.
        if !prescribed.is_empty() {
            multiply(prescribed, delta);
        }
        let [combined, others @ ..] = products;
        let others: [&[Vec3]; KEPT - 1] = others.map(|other| &*other);
        combined.par_iter_mut().zip(delta.par_iter_mut()).enumerate().with_min_len(PARALLEL_MIN_LEN).for_each(
            |(i, (product, d))| {
                let (p, pushed) = match prescribed.get(i) {
                    Some(&p) => (p, *d),
                    None => (Vec3::ZERO, Vec3::ZERO),
                };
                let kept = std::iter::once(*product).chain(others.iter().map(|other| other[i]));
                *product = kept.zip(&weights).take(count).fold(pushed, |sum, (w, &y)| sum + y * w);
                *d = solutions.iter().zip(&weights).fold(p, |d, (u, &y)| d + y * u[i]);
            },
        );
        true
    }
}

/// Entries of the Gram matrix's lower triangle.
const PAIRS: usize = KEPT * (KEPT + 1) / 2;

/// Where `G_kl`, `l ≤ k`, lies among the [`PAIRS`] sums.
const fn pair(k: usize, l: usize) -> usize {
    k * (k + 1) / 2 + l
}

/// `y` with `G y = c` over the first `count` unknowns, by Cholesky's factors of the
/// symmetric positive semi-definite `G`, an unknown whose pivot falls to [`DEPENDENT`] of
/// the largest diagonal set to zero (its solution is a combination of the others).
fn solve_dropping_dependent(mut g: [[f64; KEPT]; KEPT], mut c: [f64; KEPT], count: usize) -> [f64; KEPT] {
    let largest = (0..count).map(|k| g[k][k]).fold(0.0, f64::max);
    let mut kept = [false; KEPT];
    for k in 0..count {
        for j in 0..k {
            if kept[j] {
                let factor = g[k][j];
                for l in k..count {
                    g[l][k] -= factor * g[l][j];
                }
                c[k] -= factor * c[j];
            }
        }
        kept[k] = g[k][k] > DEPENDENT * largest && largest > 0.0;
        if kept[k] {
            let pivot = g[k][k].sqrt();
            for l in k..count {
                g[l][k] /= pivot;
            }
            c[k] /= pivot;
        }
    }
    let mut y = [0.0; KEPT];
    for k in (0..count).rev() {
        if kept[k] {
            let sum = c[k] - (k + 1..count).filter(|&l| kept[l]).map(|l| g[l][k] * y[l]).sum::<f64>();
            y[k] = sum / g[k][k];
        }
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_combination_solves_a_system_its_solutions_span() {
        // A diagonal system whose solution is 2 u₀ − u₁ plus a part no solution has.
        let n = 5000;
        let a = |i: usize| 1.0 + (i % 7) as f32;
        let u0: Vec<Vec3> = (0..n).map(|i| Vec3::new(i as f32 * 1e-3, 1.0, 0.0)).collect();
        let u1: Vec<Vec3> = (0..n).map(|i| Vec3::new(0.0, (i % 3) as f32, 1.0)).collect();
        let exact: Vec<Vec3> = (0..n).map(|i| 2.0 * u0[i] - u1[i]).collect();
        let b: Vec<Vec3> = (0..n).map(|i| a(i) * exact[i]).collect();
        let mut start = WarmStart::default();
        start.keep(&u0);
        start.keep(&u1);
        // A third, dependent solution changes nothing.
        start.keep(&u0.iter().zip(&u1).map(|(p, q)| *p + *q).collect::<Vec<_>>());
        let (mut products, mut delta) = (buffers(n), vec![Vec3::ZERO; n]);
        let multiply = |x: &[Vec3], out: &mut [Vec3]| out.iter_mut().enumerate().for_each(|(i, o)| *o = a(i) * x[i]);
        assert!(start.start(
            &Filters::free(n),
            &b,
            &[],
            multiply,
            products.each_mut().map(|p| p.as_mut_slice()),
            &mut delta
        ));
        let error = delta.iter().zip(&exact).map(|(d, e)| (*d - *e).length()).fold(0.0, f32::max);
        assert!(error < 1e-4, "largest error {error}");
        assert_forms_the_product(multiply, &delta, &products[0]);
    }

    #[test]
    fn the_combination_adds_to_the_prescribed_part() {
        // A diagonal system whose solution is the prescribed part plus 2 u₀.
        let n = 4000;
        let a = |i: usize| 2.0 + (i % 5) as f32;
        let u0: Vec<Vec3> = (0..n).map(|i| Vec3::new(1.0, (i % 9) as f32 * 0.1, -0.5)).collect();
        let prescribed: Vec<Vec3> = (0..n).map(|i| if i % 50 == 0 { Vec3::splat(0.3) } else { Vec3::ZERO }).collect();
        let exact: Vec<Vec3> = (0..n).map(|i| prescribed[i] + 2.0 * u0[i]).collect();
        let b: Vec<Vec3> = (0..n).map(|i| a(i) * exact[i]).collect();
        let mut start = WarmStart::default();
        start.keep(&u0);
        let (mut products, mut delta) = (buffers(n), vec![Vec3::ZERO; n]);
        let multiply = |x: &[Vec3], out: &mut [Vec3]| out.iter_mut().enumerate().for_each(|(i, o)| *o = a(i) * x[i]);
        let slices = products.each_mut().map(|p| p.as_mut_slice());
        assert!(start.start(&Filters::free(n), &b, &prescribed, multiply, slices, &mut delta));
        let error = delta.iter().zip(&exact).map(|(d, e)| (*d - *e).length()).fold(0.0, f32::max);
        assert!(error < 1e-5, "largest error {error}");
        assert_forms_the_product(multiply, &delta, &products[0]);
    }

    /// Scratch for [`WarmStart::start`]'s products.
    fn buffers(n: usize) -> [Vec<Vec3>; KEPT] {
        std::array::from_fn(|_| vec![Vec3::ZERO; n])
    }

    /// `formed` is `A delta` within rounding.
    fn assert_forms_the_product(multiply: impl Fn(&[Vec3], &mut [Vec3]), delta: &[Vec3], formed: &[Vec3]) {
        let mut exact = vec![Vec3::ZERO; delta.len()];
        multiply(delta, &mut exact);
        let scale = exact.iter().map(|e| e.length()).fold(0.0, f32::max);
        let error = exact.iter().zip(formed).map(|(e, f)| (*e - *f).length()).fold(0.0, f32::max);
        assert!(error <= 1e-5 * scale, "A δ formed off by {error} of {scale}");
    }

    /// `E(δ) = δᵀ A δ − 2 δᵀ b`, the error's energy `‖δ − A⁻¹ b‖²_A` less a constant.
    fn energy(multiply: impl Fn(&[Vec3], &mut [Vec3]), b: &[Vec3], delta: &[Vec3]) -> f64 {
        let mut product = vec![Vec3::ZERO; delta.len()];
        multiply(delta, &mut product);
        delta.iter().zip(&product).zip(b).map(|((d, p), b)| f64::from(d.dot(*p)) - 2.0 * f64::from(d.dot(*b))).sum()
    }

    #[test]
    fn the_start_is_the_best_of_its_solutions_in_the_energy_norm() {
        // A chain of springs with masses (symmetric positive definite), a load, and kept
        // solutions that have little to do with it.
        let n = 3000;
        let multiply = |x: &[Vec3], out: &mut [Vec3]| {
            for (i, o) in out.iter_mut().enumerate() {
                let (left, right) =
                    (if i > 0 { x[i - 1] } else { Vec3::ZERO }, x.get(i + 1).copied().unwrap_or(Vec3::ZERO));
                *o = 2.01 * x[i] - left - right;
            }
        };
        let wave = |k: f32, phase: f32| -> Vec<Vec3> {
            (0..n).map(|i| Vec3::new((k * i as f32 + phase).sin(), (0.5 * k * i as f32).cos(), 0.1)).collect()
        };
        let b = wave(0.01, 0.3);
        let kept = [wave(0.013, 0.0), wave(0.2, 1.0), wave(0.011, 2.0)];
        let mut start = WarmStart::default();
        kept.iter().for_each(|u| start.keep(u));
        let (mut products, mut delta) = (buffers(n), vec![Vec3::ZERO; n]);
        let slices = products.each_mut().map(|p| p.as_mut_slice());
        assert!(start.start(&Filters::free(n), &b, &[], multiply, slices, &mut delta));
        assert_forms_the_product(multiply, &delta, &products[0]);
        let best = energy(multiply, &b, &delta);
        assert!(best < 0.0, "worse than rest: {best}");
        for u in &kept {
            // The best multiple of each solution alone: E = −(uᵀb)² / uᵀAu.
            let (mut au, ub) = (vec![Vec3::ZERO; n], u.iter().zip(&b).map(|(u, b)| f64::from(u.dot(*b))).sum::<f64>());
            multiply(u, &mut au);
            let uau: f64 = u.iter().zip(&au).map(|(u, a)| f64::from(u.dot(*a))).sum();
            assert!(best <= -ub * ub / uau * (1.0 - 1e-4), "{best} against {}", -ub * ub / uau);
        }
    }

    #[test]
    fn nothing_kept_gives_no_start_and_another_size_forgets() {
        let mut start = WarmStart::default();
        let (mut products, mut delta) = (buffers(4), vec![Vec3::ONE; 4]);
        let multiply = |x: &[Vec3], out: &mut [Vec3]| out.copy_from_slice(x);
        let slices = products.each_mut().map(|p| p.as_mut_slice());
        assert!(!start.start(&Filters::free(4), &[Vec3::X; 4], &[], multiply, slices, &mut delta));
        start.keep(&[Vec3::X; 3]);
        start.keep(&[Vec3::X; 4]);
        assert_eq!(start.solutions.len(), 1);
        let slices = products.each_mut().map(|p| p.as_mut_slice());
        assert!(start.start(&Filters::free(4), &[Vec3::X * 2.0; 4], &[], multiply, slices, &mut delta));
        assert_eq!(delta, vec![Vec3::X * 2.0; 4]);
        assert_eq!(products[0], vec![Vec3::X * 2.0; 4]);
    }
}
