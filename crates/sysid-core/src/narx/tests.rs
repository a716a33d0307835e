use faer::Mat;
use rand::{rngs::StdRng, Rng, SeedableRng};

use super::basis::{Basis, Candidates, Term};
use super::frols::{fit, frols, solve_prefix, FrolsOptions};
use super::regressors::{LagSpec, Record};
use super::simulate::{Equation, NarxModel};

/// y = -0.605 y(t-1) - 0.163 y(t-2)^2 + 0.588 u(t-1) - 0.24 u(t-2) (Billings' example).
fn billings(n: usize, seed: u64) -> (Mat<f64>, Mat<f64>) {
    let mut rng = StdRng::seed_from_u64(seed);
    let u = Mat::from_fn(n, 1, |_, _| rng.random_range(-1.0..1.0));
    let mut y = Mat::<f64>::zeros(n, 1);
    for t in 2..n {
        y[(t, 0)] = -0.605 * y[(t - 1, 0)] - 0.163 * y[(t - 2, 0)].powi(2) + 0.588 * u[(t - 1, 0)]
            - 0.24 * u[(t - 2, 0)];
    }
    (u, y)
}

#[test]
fn enumeration_counts_and_parents() {
    let c = Candidates::new(&Basis::Polynomial { degree: 3 }, 4).unwrap();
    assert_eq!(c.len(), 35); // binomial(7, 3)
                             // the generated columns equal the directly evaluated terms
    let len = 5;
    let x: Vec<f64> = (0..len * 4).map(|i| (i as f64 * 0.37).sin()).collect();
    let mut sc = vec![0.0; c.scratch_len(len)];
    c.for_each_column(&x, len, &mut sc, |k, col| {
        for r in 0..len {
            let row: Vec<f64> = (0..4).map(|v| x[v * len + r]).collect();
            let want = c.basis.eval(&c.terms[k], &row);
            assert!((col[r] - want).abs() < 1e-15);
        }
    });
}

#[test]
fn frols_selects_true_terms_and_exact_coefficients() {
    let (u, y) = billings(500, 1);
    let spec = LagSpec::new(1, 1, &[2], &[2], &[1], &[0]).unwrap();
    let cands = Candidates::new(&Basis::Polynomial { degree: 2 }, spec.n_vars()).unwrap();
    let rec = [Record::new(u.as_ref(), y.as_ref())];
    for block_rows in [0, 7, 64] {
        let mut opts = FrolsOptions::with_max_terms(8);
        opts.block_rows = block_rows;
        let sel = frols(&spec, &cands, &rec, &[vec![]], &opts).unwrap();
        let mut got: Vec<Term> = sel[0]
            .terms
            .iter()
            .map(|&k| cands.terms[k].clone())
            .collect();
        assert_eq!(got.len(), 4, "{got:?}");
        let r = fit(&spec, &cands, &rec, &[sel[0].terms.clone()]).unwrap();
        let th = solve_prefix(&r[0], 4).unwrap();
        let mut pairs: Vec<(Term, f64)> = got.drain(..).zip(th).collect();
        pairs.sort_by_key(|p| format!("{:?}", p.0));
        let want = [
            (Term::Monomial(vec![0]), -0.605),
            (Term::Monomial(vec![1, 1]), -0.163),
            (Term::Monomial(vec![2]), 0.588),
            (Term::Monomial(vec![3]), -0.24),
        ];
        let mut want = want.to_vec();
        want.sort_by_key(|p| format!("{:?}", p.0));
        for (g, w) in pairs.iter().zip(&want) {
            assert_eq!(g.0, w.0);
            assert!((g.1 - w.1).abs() < 1e-10, "{g:?} vs {w:?}");
        }
    }
}

#[test]
fn simulate_and_predict_reproduce_the_system() {
    let (u, y) = billings(200, 2);
    let spec = LagSpec::new(1, 1, &[2], &[2], &[1], &[0]).unwrap();
    let eq = Equation {
        terms: vec![
            Term::Monomial(vec![0]),
            Term::Monomial(vec![1, 1]),
            Term::Monomial(vec![2]),
            Term::Monomial(vec![3]),
        ],
        coefs: vec![-0.605, -0.163, 0.588, -0.24],
    };
    let m = NarxModel::new(spec, Basis::Polynomial { degree: 2 }, vec![eq]).unwrap();
    let y0 = Mat::<f64>::zeros(2, 1);
    let ys = m.simulate(u.as_ref(), y0.as_ref()).unwrap();
    for h in [1, 3] {
        let yp = m.predict(u.as_ref(), y.as_ref(), h).unwrap();
        for t in 0..200 {
            assert!((yp[(t, 0)] - y[(t, 0)]).abs() < 1e-12);
        }
    }
    for t in 0..200 {
        assert!((ys[(t, 0)] - y[(t, 0)]).abs() < 1e-12);
    }
}

#[test]
fn accumulate_equals_explicit_columns() {
    let nv = 5;
    for basis in [
        Basis::Polynomial { degree: 1 },
        Basis::Polynomial { degree: 3 },
        Basis::Rbf(super::basis::RbfBasis {
            centres: Mat::from_fn(3, nv, |i, j| (i as f64 - j as f64) * 0.3),
            widths: vec![1.0, 0.7, 2.0],
            shift: vec![0.1; nv],
            scale: vec![1.5; nv],
        }),
    ] {
        let c = Candidates::new(&basis, nv).unwrap();
        for len in [1, 7, 33] {
            let x: Vec<f64> = (0..len * nv).map(|i| (i as f64 * 0.71).cos()).collect();
            let np = 2;
            let p: Vec<f64> = (0..len * np).map(|i| (i as f64 * 0.13).sin()).collect();
            let mut cross = vec![0.0; c.len() * np];
            let mut sq = vec![0.0; c.len()];
            let mut sc = vec![0.0; c.accumulate_scratch_len(len, np)];
            c.accumulate(&x, len, &p, np, &mut cross, Some(&mut sq), &mut sc);
            let mut sc2 = vec![0.0; c.scratch_len(len)];
            c.for_each_column(&x, len, &mut sc2, |k, col| {
                let want: f64 = col.iter().map(|v| v * v).sum();
                assert!((sq[k] - want).abs() < 1e-12 * (1.0 + want));
                for j in 0..np {
                    let want: f64 = (0..len).map(|i| col[i] * p[j * len + i]).sum();
                    assert!((cross[k * np + j] - want).abs() < 1e-12 * (1.0 + want.abs()));
                }
            });
        }
    }
}

/// y = 0.5 y(t-1) + 0.8 u(t-1) - 0.4 y(t-1) |u(t-1)|: the last term a custom regressor.
#[test]
fn custom_regressor_is_selected_fitted_and_simulated_exactly() {
    use super::regressors::{LagVar, Signal};
    let n = 400;
    let mut rng = StdRng::seed_from_u64(7);
    let u = Mat::from_fn(n, 1, |_, _| rng.random_range(-1.5..1.5));
    let mut y = Mat::<f64>::zeros(n, 1);
    let f = |a: &[f64]| a[0] * a[1].abs();
    for t in 1..n {
        y[(t, 0)] =
            0.5 * y[(t - 1, 0)] + 0.8 * u[(t - 1, 0)] - 0.4 * f(&[y[(t - 1, 0)], u[(t - 1, 0)]]);
    }
    let args = vec![
        LagVar {
            signal: Signal::Output,
            channel: 0,
            lag: 1,
        },
        LagVar {
            signal: Signal::Input,
            channel: 0,
            lag: 1,
        },
    ];
    let spec = LagSpec::new(1, 1, &[1], &[1], &[1], &[0])
        .unwrap()
        .with_custom(vec![args])
        .unwrap();
    let c = Mat::from_fn(n, 1, |t, _| {
        if t == 0 {
            0.0
        } else {
            f(&[y[(t - 1, 0)], u[(t - 1, 0)]])
        }
    });
    let cands =
        Candidates::with_custom(&Basis::Polynomial { degree: 2 }, spec.n_lagged(), 1).unwrap();
    let rec = [Record {
        u: u.as_ref(),
        y: y.as_ref(),
        e: None,
        c: Some(c.as_ref()),
    }];
    let sel = frols(
        &spec,
        &cands,
        &rec,
        &[vec![]],
        &FrolsOptions::with_max_terms(3),
    )
    .unwrap();
    let mut got: Vec<Term> = sel[0]
        .terms
        .iter()
        .map(|&k| cands.terms[k].clone())
        .collect();
    let r = fit(&spec, &cands, &rec, &[sel[0].terms.clone()]).unwrap();
    let th = solve_prefix(&r[0], 3).unwrap();
    let mut pairs: Vec<(Term, f64)> = got.drain(..).zip(th).collect();
    pairs.sort_by_key(|p| format!("{:?}", p.0));
    let want = [
        (Term::Custom(2), -0.4),
        (Term::Monomial(vec![0]), 0.5),
        (Term::Monomial(vec![1]), 0.8),
    ];
    for (g, w) in pairs.iter().zip(&want) {
        assert_eq!(g.0, w.0);
        assert!((g.1 - w.1).abs() < 1e-10, "{g:?} vs {w:?}");
    }
    let eq = Equation {
        terms: want.iter().map(|p| p.0.clone()).collect(),
        coefs: want.iter().map(|p| p.1).collect(),
    };
    let m = NarxModel::new(spec, Basis::Polynomial { degree: 2 }, vec![eq]).unwrap();
    let y0 = Mat::<f64>::zeros(1, 1);
    assert!(m.simulate(u.as_ref(), y0.as_ref()).is_err()); // needs the function
    let ys = m
        .simulate_with(u.as_ref(), y0.as_ref(), &mut |_, a| Ok(f(a)))
        .unwrap();
    let p3 = m
        .predict_with(u.as_ref(), y.as_ref(), 3, &mut |_, a| Ok(f(a)))
        .unwrap();
    for t in 0..n {
        assert!((ys[(t, 0)] - y[(t, 0)]).abs() < 1e-12);
        assert!((p3[(t, 0)] - y[(t, 0)]).abs() < 1e-12);
    }
    let bad = m.simulate_with(u.as_ref(), y0.as_ref(), &mut |_, _| Ok(f64::NAN));
    assert!(format!("{:?}", bad.unwrap_err()).contains("custom regressor"));
}
