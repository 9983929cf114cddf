//! Feature-sign search is exact: on random problems its solution satisfies the L1
//! optimality conditions to 1e-8 and its objective matches an independent solver
//! (cyclic coordinate descent run to convergence) to 1e-6 relative.

use tactile_workbench::rng::Rng;
use tactile_workbench::sparse::{FeatureSign, l1_objective, l1_optimality_violation};

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
