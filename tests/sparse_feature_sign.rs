//! Feature-sign search is exact: on random problems its solution satisfies the L1
//! optimality conditions to 1e-8 and its objective matches an independent solver
//! (cyclic coordinate descent run to convergence) to 1e-6 relative.

use tactile_workbench::rng::Rng;
use tactile_workbench::sparse::{FeatureSign, FsStats, l1_objective, l1_optimality_violation};

/// A random problem: dictionary K × n with unit-norm rows, a patch, its G and c.
fn problem(rng: &mut Rng, k: usize, n: usize, correlated: bool) -> (Vec<f64>, Vec<f64>) {
    let mut d = vec![0.0; k * n];
    let base: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
    for j in 0..k {
        let row = &mut d[j * n..(j + 1) * n];
        for (i, v) in row.iter_mut().enumerate() {
            *v = rng.normal() + if correlated { 2.0 * base[i] } else { 0.0 };
        }
        let nrm = row.iter().map(|v| v * v).sum::<f64>().sqrt();
        row.iter_mut().for_each(|v| *v /= nrm);
    }
    // Patch: a sparse combination of atoms plus noise, at a z-score-like scale.
    let mut x: Vec<f64> = (0..n).map(|_| 0.3 * rng.normal()).collect();
    for _ in 0..3 {
        let j = rng.below(k);
        let w = 3.0 * rng.normal();
        for i in 0..n {
            x[i] += w * d[j * n + i];
        }
    }
    let mut g = vec![0.0; k * k];
    let mut c = vec![0.0; k];
    for a in 0..k {
        for b in 0..k {
            g[a * k + b] = (0..n).map(|i| d[a * n + i] * d[b * n + i]).sum();
        }
        c[a] = (0..n).map(|i| d[a * n + i] * x[i]).sum();
    }
    (g, c)
}

/// Cyclic coordinate descent on the same objective, to a 1e-15 change.
fn coordinate_descent(g: &[f64], c: &[f64], gamma: f64) -> Vec<f64> {
    let k = c.len();
    let mut a = vec![0.0; k];
    for _ in 0..200_000 {
        let mut change = 0.0f64;
        for j in 0..k {
            let mut r = c[j];
            for i in 0..k {
                if i != j {
                    r -= g[j * k + i] * a[i];
                }
            }
            let new = if r > gamma {
                (r - gamma) / g[j * k + j]
            } else if r < -gamma {
                (r + gamma) / g[j * k + j]
            } else {
                0.0
            };
            change = change.max((new - a[j]).abs());
            a[j] = new;
        }
        if change < 1e-15 {
            break;
        }
    }
    a
}

fn check(k: usize, n: usize, gamma: f64, correlated: bool, seeds: std::ops::Range<u64>) {
    let mut fs = FeatureSign::new(k);
    for seed in seeds {
        let mut rng = Rng::new(seed);
        let (g, c) = problem(&mut rng, k, n, correlated);
        let mut a = vec![0.0; k];
        let st = fs.solve(&g, &c, gamma, &mut a);
        assert!(
            st.converged,
            "k={k} n={n} γ={gamma} seed={seed}: not converged {st:?}"
        );
        let viol = l1_optimality_violation(&g, &c, gamma, &a);
        assert!(
            viol <= 1e-8,
            "k={k} n={n} γ={gamma} seed={seed}: violation {viol:e}"
        );
        let cd = coordinate_descent(&g, &c, gamma);
        // Compare 0.5||x − aD||² + γ|a| up to the shared constant: use the objective
        // relative to the zero code, which is ≤ 0, and compare in relative terms.
        let f_fs = l1_objective(&g, &c, gamma, &a);
        let f_cd = l1_objective(&g, &c, gamma, &cd);
        let scale = f_fs.abs().max(f_cd.abs()).max(1e-12);
        assert!(
            (f_fs - f_cd) / scale <= 1e-6,
            "k={k} n={n} γ={gamma} seed={seed}: feature-sign {f_fs} vs coordinate descent {f_cd}"
        );
        // And feature-sign is never worse than coordinate descent beyond rounding.
        assert!((f_cd - f_fs) / scale >= -1e-6);
        // Warm start from the coordinate-descent solution reaches the same optimum.
        let mut warm = cd.clone();
        assert!(fs.solve(&g, &c, gamma, &mut warm).converged);
        assert!(l1_optimality_violation(&g, &c, gamma, &warm) <= 1e-8);
    }
}

#[test]
fn undercomplete_problems_are_solved_exactly() {
    for gamma in [0.05, 0.3, 1.0, 3.0] {
        check(12, 24, gamma, false, 0..40);
    }
}

#[test]
fn overcomplete_problems_are_solved_exactly() {
    // More bases than taxels: the active Gram matrix can become singular.
    for gamma in [0.01, 0.1, 0.5, 1.0, 2.0] {
        check(29, 24, gamma, false, 100..140);
        check(60, 24, gamma, false, 200..220);
    }
}

#[test]
fn correlated_dictionaries_are_solved_exactly() {
    for gamma in [0.01, 0.2, 1.0] {
        check(40, 12, gamma, true, 300..330);
    }
}

#[test]
fn tiny_penalty_with_many_more_bases_than_dimensions() {
    // γ → 0 drives the active set to the patch dimension: the singular branch must work.
    let mut fs = FeatureSign::new(30);
    for seed in 400..430 {
        let mut rng = Rng::new(seed);
        let (g, c) = problem(&mut rng, 30, 6, false);
        let mut a = vec![0.0; 30];
        let st = fs.solve(&g, &c, 1e-4, &mut a);
        assert!(st.converged, "seed {seed}: {st:?}");
        assert!(l1_optimality_violation(&g, &c, 1e-4, &a) <= 1e-8);
        let active = a.iter().filter(|v| **v != 0.0).count();
        assert!(
            active <= 6,
            "seed {seed}: {active} active bases for 6 taxels"
        );
    }
}

#[test]
fn warm_start_from_wrong_signs_and_large_penalty() {
    let k = 20;
    let mut fs = FeatureSign::new(k);
    let mut rng = Rng::new(9);
    let (g, c) = problem(&mut rng, k, 24, false);
    // A warm start with arbitrary signs.
    let mut a: Vec<f64> = (0..k)
        .map(|i| if i % 3 == 0 { rng.normal() } else { 0.0 })
        .collect();
    assert!(fs.solve(&g, &c, 0.7, &mut a).converged);
    assert!(l1_optimality_violation(&g, &c, 0.7, &a) <= 1e-8);
    // A penalty above max |c| gives the zero code.
    let cmax = c.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut z = vec![0.5; k];
    assert!(fs.solve(&g, &c, cmax * 1.01, &mut z).converged);
    assert!(z.iter().all(|v| *v == 0.0), "{z:?}");
}

/// A random dictionary (K × n, rows not normalised), a patch, their G = D Dᵀ and c = D x.
fn raw_problem(rng: &mut Rng, k: usize, n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
    let d: Vec<f64> = (0..k * n).map(|_| rng.normal()).collect();
    let x: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
    let mut g = vec![0.0; k * k];
    let mut c = vec![0.0; k];
    for a in 0..k {
        for b in 0..k {
            g[a * k + b] = (0..n).map(|i| d[a * n + i] * d[b * n + i]).sum();
        }
        c[a] = (0..n).map(|i| d[a * n + i] * x[i]).sum();
    }
    (d, x, g, c)
}

#[test]
fn objective_and_optimality_violation_follow_their_definitions_from_d_and_x() {
    // Both are the tests' yardsticks, so they are checked against the definitions written
    // with the dictionary and the patch themselves: F(a) = 0.5 ||x − a D||² − 0.5 ||x||² +
    // γ ||a||₁, and with the residual r = a D − x the gradient ∇_j = d_j · r.
    let (k, n) = (7, 5);
    for seed in 0..20 {
        let mut rng = Rng::new(600 + seed);
        let (d, x, g, c) = raw_problem(&mut rng, k, n);
        let gamma = 0.1 + rng.uniform();
        // Codes with zeros, positive and negative entries.
        let a: Vec<f64> = (0..k)
            .map(|_| {
                if rng.bernoulli(0.4) {
                    0.0
                } else {
                    2.0 * rng.normal()
                }
            })
            .collect();
        let r: Vec<f64> = (0..n)
            .map(|i| (0..k).map(|j| a[j] * d[j * n + i]).sum::<f64>() - x[i])
            .collect();
        let sq = |v: &[f64]| v.iter().map(|e| e * e).sum::<f64>();
        let l1: f64 = a.iter().map(|v| v.abs()).sum();
        let want = 0.5 * sq(&r) - 0.5 * sq(&x) + gamma * l1;
        let got = l1_objective(&g, &c, gamma, &a);
        assert!(
            (got - want).abs() <= 1e-10 * (1.0 + want.abs()),
            "seed {seed}: {got} vs {want}"
        );
        let mut worst = 0.0f64;
        for j in 0..k {
            let grad: f64 = (0..n).map(|i| d[j * n + i] * r[i]).sum();
            let v = if a[j] > 0.0 {
                (grad + gamma).abs()
            } else if a[j] < 0.0 {
                (grad - gamma).abs()
            } else {
                (grad.abs() - gamma).max(0.0)
            };
            worst = worst.max(v);
        }
        let got = l1_optimality_violation(&g, &c, gamma, &a);
        assert!(
            (got - worst).abs() <= 1e-10 * (1.0 + worst),
            "seed {seed}: {got} vs {worst}"
        );
    }
    // By hand: G = [[2, 1, 0], [1, 3, 1], [0, 1, 3]], c = (3, 0.5, 1), γ = 0.5, a = (2, −1, 0):
    // G a = (3, −1, −1), so F = 0.5 · 7 − 5.5 + 0.5 · 3 = −0.5; ∇ = G a − c = (0, −1.5, −2),
    // whose violations are |0 + 0.5| = 0.5, |−1.5 − 0.5| = 2 and max(0, 2 − 0.5) = 1.5.
    let g = [2.0, 1.0, 0.0, 1.0, 3.0, 1.0, 0.0, 1.0, 3.0];
    let c = [3.0, 0.5, 1.0];
    assert_eq!(l1_objective(&g, &c, 0.5, &[2.0, -1.0, 0.0]), -0.5);
    assert_eq!(l1_optimality_violation(&g, &c, 0.5, &[2.0, -1.0, 0.0]), 2.0);
    // With a = (2, 0, 0): ∇ = (1, 1.5, −1), violations 1.5, 1 and 0.5.
    assert_eq!(l1_optimality_violation(&g, &c, 0.5, &[2.0, 0.0, 0.0]), 1.5);
    // With a = (0, 0, 0): ∇ = −c, violations of the zero coefficients 2.5, 0 and 0.5.
    assert_eq!(l1_optimality_violation(&g, &c, 0.5, &[0.0; 3]), 2.5);
}

#[test]
fn iterations_follow_algorithm_1_and_bad_warm_start_entries_are_dropped() {
    // Orthonormal bases 0–2 and a zero basis 3 (G = diag(1, 1, 1, 0)), c = (3, 0.5, −2, 0),
    // γ = 1: the solution is the soft threshold of c, a = (2, 0, −1, 0).
    let mut fs = FeatureSign::new(4);
    assert_eq!(fs.num_bases(), 4);
    let mut g = vec![0.0; 16];
    for j in 0..3 {
        g[j * 4 + j] = 1.0;
    }
    let c = [3.0, 0.5, -2.0, 0.0];
    let solution = [2.0, 0.0, -1.0, 0.0];
    // From zero: check (activates 0), step, check (activates 2), step, check (optimal).
    let mut a = [0.0; 4];
    let st = fs.solve(&g, &c, 1.0, &mut a);
    assert_eq!(a, solution);
    assert_eq!(
        st,
        FsStats {
            iterations: 5,
            converged: true
        }
    );
    // Warm starts with the solution's signs need one feature-sign step and one check.
    // Non-finite entries and an entry on the zero basis are not part of such a start:
    // they are set to zero, not stepped over.
    let nan = f64::NAN;
    let inf = f64::INFINITY;
    for start in [
        solution,
        [2.0, nan, -1.0, 0.0],
        [2.0, inf, -1.0, -inf],
        [2.0, 0.0, -1.0, 5.0],
        [0.5, 0.0, -4.0, 0.0],
    ] {
        let mut a = start;
        let st = fs.solve(&g, &c, 1.0, &mut a);
        assert_eq!(a, solution, "warm start {start:?}");
        assert_eq!(st.iterations, 2, "warm start {start:?}");
        assert!(st.converged);
    }
}

#[test]
fn a_zero_coefficient_is_activated_only_beyond_the_documented_tolerance() {
    // G = I: the exact solution is the soft threshold of c. A gradient that exceeds γ by
    // less than γ · 1e-12 (the stopping rule |∇_j| ≤ γ (1 + 1e-12)), or one below the floor
    // 1e-300 when γ = 0, leaves its coefficient at zero.
    let g = [1.0, 0.0, 0.0, 1.0];
    let mut fs = FeatureSign::new(2);
    for (gamma, c, want) in [
        (4.0, [8.0, 4.0 + 1e-12], [4.0, 0.0]),
        (1.0, [2.0, 1.0 + 1e-14], [1.0, 0.0]),
        (0.0, [2.0, 1e-301], [2.0, 0.0]),
        // Exactly at the tolerance (the rule is ≤).
        (4.0, [8.0, 4.0 + (1e-12 * 4.0 + 1e-300)], [4.0, 0.0]),
    ] {
        let mut a = [0.0; 2];
        assert!(fs.solve(&g, &c, gamma, &mut a).converged);
        assert_eq!(a, want, "γ = {gamma}, c = {c:?}");
    }
    // Beyond the tolerance it is activated: c₂ = γ (1 + 1e-9) gives a₂ = c₂ − γ.
    let mut a = [0.0; 2];
    assert!(
        fs.solve(&g, &[8.0, 4.0 * (1.0 + 1e-9)], 4.0, &mut a)
            .converged
    );
    assert_eq!(a[0], 4.0);
    assert!(a[1] > 0.0 && (a[1] - 4e-9).abs() < 1e-15, "{a:?}");
}

#[test]
fn a_duplicated_atom_gives_its_code_to_the_first_copy() {
    // Two copies of one unit atom and x = 3 times it: every split of the weight 2 between
    // them is optimal; the most violating zero coefficient is the first of equal ones.
    let g = [1.0, 1.0, 1.0, 1.0];
    let mut a = [0.0; 2];
    assert!(
        FeatureSign::new(2)
            .solve(&g, &[3.0, 3.0], 1.0, &mut a)
            .converged
    );
    assert_eq!(a, [2.0, 0.0]);
}
