use tactile_workbench::gp::{KernelParams, LagMajor, RecursiveArd, Window};
use tactile_workbench::rng::Rng;

fn params(dim: usize, rng: &mut Rng) -> KernelParams {
    KernelParams {
        lengthscales: (0..dim).map(|_| rng.range(0.5, 2.0)).collect(),
        sigma_rho: 1.01,
        sigma_f: 1.3,
        sigma_n: 0.1,
    }
}

#[test]
fn recursion_matches_hand_unrolled_definition() {
    let mut rng = Rng::new(1);
    let (dim, tau) = (3, 4);
    let p = params(dim, &mut rng);
    let k = RecursiveArd::new(dim, tau, p.clone()).unwrap();
    let a: Vec<f64> = (0..dim * tau).map(|_| rng.normal()).collect();
    let b: Vec<f64> = (0..dim * tau).map(|_| rng.normal()).collect();
    let mut kk = 1.0;
    for lag in 0..tau {
        let d: f64 = (0..dim)
            .map(|j| ((a[lag * dim + j] - b[lag * dim + j]) / p.lengthscales[j]).powi(2))
            .sum();
        kk = (-0.5 * d).exp() * ((kk - 1.0) / p.sigma_rho).exp();
    }
    assert!((k.eval(&a, &b) - 1.69 * kk).abs() < 1e-12);
    assert!((k.eval(&a, &a) - 1.69).abs() < 1e-12, "k(x, x) = sigma_f²");
    assert!((k.eval(&a, &b) - k.eval(&b, &a)).abs() < 1e-15);
}

#[test]
fn newest_lag_weighs_most_and_padding_is_neutral() {
    let (dim, tau) = (1, 3);
    let k = RecursiveArd::new(
        dim,
        tau,
        KernelParams {
            lengthscales: vec![1.0],
            sigma_rho: 1.01,
            sigma_f: 1.0,
            sigma_n: 0.1,
        },
    )
    .unwrap();
    let base = [0.0, 0.0, 0.0];
    let old = k.eval(&base, &[1.0, 0.0, 0.0]);
    let new = k.eval(&base, &[0.0, 0.0, 1.0]);
    assert!(
        new < old,
        "a difference at the newest lag lowers k more: {new} vs {old}"
    );
    // A window at the start of a sequence is zero padded: one push equals [0, 0, x].
    let mut w = Window::new(dim, tau);
    w.push(&[0.7]);
    assert_eq!(w.as_slice(), &[0.0, 0.0, 0.7]);
    w.push(&[0.2]);
    assert_eq!(w.as_slice(), &[0.0, 0.7, 0.2]);
    w.reset();
    assert_eq!(w.as_slice(), &[0.0, 0.0, 0.0]);
}

#[test]
fn recursive_derivatives_match_finite_differences() {
    let mut rng = Rng::new(7);
    let (dim, tau) = (4, 5);
    for trial in 0..5 {
        let p = params(dim, &mut rng);
        let a: Vec<f64> = (0..dim * tau).map(|_| rng.normal() * 0.7).collect();
        let b: Vec<f64> = (0..dim * tau).map(|_| rng.normal() * 0.7).collect();
        let unit = |p: &KernelParams| {
            let k = RecursiveArd::new(dim, tau, p.clone()).unwrap();
            let (mut sa, mut sb) = (vec![0.0; a.len()], vec![0.0; b.len()]);
            k.scale_into(&a, &mut sa);
            k.scale_into(&b, &mut sb);
            k.unit_scaled(&sa, &sb)
        };
        let k = RecursiveArd::new(dim, tau, p.clone()).unwrap();
        let (mut sa, mut sb) = (vec![0.0; a.len()], vec![0.0; b.len()]);
        k.scale_into(&a, &mut sa);
        k.scale_into(&b, &mut sb);
        let mut g = vec![0.0; dim + 1];
        let value = k.unit_scaled_grad(&sa, &sb, &mut g);
        assert!((value - unit(&p)).abs() < 1e-14);
        let h: f64 = 1e-6;
        for (j, &gj) in g.iter().enumerate() {
            let (mut hi, mut lo) = (p.clone(), p.clone());
            if j < dim {
                hi.lengthscales[j] *= h.exp();
                lo.lengthscales[j] *= (-h).exp();
            } else {
                hi.sigma_rho += h;
                lo.sigma_rho -= h;
            }
            let fd = (unit(&hi) - unit(&lo)) / (2.0 * h);
            assert!(
                (fd - gj).abs() < 1e-7 * (1.0 + fd.abs()),
                "trial {trial}, parameter {j}: analytic {gj} vs finite difference {fd}"
            );
        }
    }
}

#[test]
fn bad_parameters_are_errors_naming_the_parameter() {
    let bad = KernelParams {
        lengthscales: vec![1.0, -1.0],
        sigma_rho: 1.01,
        sigma_f: 1.0,
        sigma_n: 0.1,
    };
    let e = RecursiveArd::new(2, 3, bad).unwrap_err().to_string();
    assert!(e.contains("lengthscales"), "{e}");
    let e = RecursiveArd::new(
        1,
        0,
        KernelParams {
            lengthscales: vec![1.0],
            sigma_rho: 1.01,
            sigma_f: 1.0,
            sigma_n: 0.1,
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("tau"), "{e}");
}

#[test]
fn fast_exp_matches_the_library_exp() {
    use tactile_workbench::gp::kernel::exp_nonpos;
    let mut x = 0.0;
    while x > -745.0 {
        let (a, b) = (exp_nonpos(x), x.exp());
        if x >= -700.0 {
            assert!((a - b).abs() <= 4e-16 * b, "exp({x}): {a} vs {b}");
        } else {
            assert!(a < 1e-303);
        }
        x -= 0.0137;
    }
    assert_eq!(exp_nonpos(0.0), 1.0);
}

#[test]
fn many_bvs_at_once_equal_one_at_a_time() {
    let mut rng = Rng::new(3);
    // dim 5 has a tail beyond the 4-wide chunks; 11 BVs fill one block and part of the next.
    let (dim, tau, n) = (5, 4, 11);
    let k = RecursiveArd::new(dim, tau, params(dim, &mut rng)).unwrap();
    // Padding lags (exact zeros) in the window and in some BVs take the stored-norm path.
    let window = |rng: &mut Rng, pad: usize| -> Vec<f64> {
        (0..dim * tau)
            .map(|t| if t < pad * dim { 0.0 } else { rng.normal() })
            .collect()
    };
    let bvs: Vec<Vec<f64>> = (0..n).map(|i| window(&mut rng, i % 3)).collect();
    let mut basis = LagMajor::new(dim, tau, 16);
    for (i, b) in bvs.iter().enumerate() {
        basis.set(i, b);
    }
    // A copy out of block 1 into a slot of block 0 and back, over other data, exercises
    // the block layout.
    basis.copy(9, 2);
    basis.set(9, &window(&mut rng, 0));
    basis.copy(2, 9);
    basis.set(2, &bvs[2]);
    let s = basis.stride();
    for pad in [0, 1, 3] {
        let x = window(&mut rng, pad);
        let (mut lag_k, mut out) = (vec![0.0; tau * s], vec![0.0; s]);
        k.unit_many(&x, &basis, n, &mut lag_k, &mut out);
        let mut grad = vec![0.0; (dim + 1) * s];
        k.unit_grad_many(&x, &basis, n, &lag_k, &mut grad);
        for (i, b) in bvs.iter().enumerate() {
            assert_eq!(out[i], k.unit_scaled(&x, b), "pad {pad}, BV {i}");
            let mut g = vec![0.0; dim + 1];
            assert_eq!(k.unit_scaled_grad(&x, b, &mut g), out[i]);
            for (p, gp) in g.iter().enumerate() {
                assert_eq!(grad[p * s + i], *gp, "pad {pad}, BV {i}, parameter {p}");
            }
        }
    }
}

/// `dot_rows` sums each row as `dot` does, to the bit, for every row count and length
/// (whole blocks of four rows and the rows after them, whole chunks of four values and the
/// tail), over a strided matrix; values of mixed magnitudes make any other order of
/// summation show in the last bits.
#[test]
fn dot_rows_sums_each_row_as_dot_does() {
    use tactile_workbench::gp::kernel::{dot, dot_rows};
    let mut rng = Rng::new(7);
    for rows in 0..11 {
        for n in 0..23 {
            let stride = n + 3;
            let m: Vec<f64> = (0..rows * stride)
                .map(|_| rng.normal() * 10f64.powi(rng.below(9) as i32 - 4))
                .collect();
            let x: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
            let mut out = vec![0.0; rows];
            dot_rows(&m, stride, n, &x, &mut out);
            for (i, o) in out.iter().enumerate() {
                let d = dot(&m[i * stride..i * stride + n], &x);
                assert_eq!(o.to_bits(), d.to_bits(), "rows {rows}, n {n}, row {i}");
            }
        }
    }
}
