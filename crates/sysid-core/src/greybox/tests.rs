use super::expm::expm_frechet;
use crate::optim::{Evaluation, ParameterMap, Problem, Reparameterized};
use faer::{mat, Mat};

#[test]
fn expm_matches_closed_form_and_frechet_matches_differences() {
    // rotation generator: exp([[0, w], [-w, 0]] t) = [[cos, sin], [-sin, cos]]
    let w = 2.3;
    let x = mat![[0.0, w], [-w, 0.0]];
    let (f, _) = expm_frechet(x.as_ref(), &[]);
    assert!((f[(0, 0)] - w.cos()).abs() < 1e-14 && (f[(0, 1)] - w.sin()).abs() < 1e-14);
    // a non-normal 3x3 with a large norm (several squarings)
    let x = mat![[-1.0, 4.0, 0.5], [0.0, -2.0, 3.0], [1.0, 0.0, -0.5]];
    let e = mat![[0.3, -0.2, 0.0], [0.1, 0.0, 0.7], [0.0, 0.5, -0.4]];
    let (f, l) = expm_frechet(x.as_ref(), std::slice::from_ref(&e));
    let h = 1e-6;
    let (fp, _) = expm_frechet((&x + &e * h).as_ref(), &[]);
    let (fm, _) = expm_frechet((&x - &e * h).as_ref(), &[]);
    for i in 0..3 {
        for j in 0..3 {
            let fd = (fp[(i, j)] - fm[(i, j)]) / (2.0 * h);
            assert!(
                (l[0][(i, j)] - fd).abs() < 1e-7 * (1.0 + fd.abs()),
                "{i} {j}"
            );
        }
    }
    // exp(X) exp(-X) = I
    let (g, _) = expm_frechet((&x * -1.0).as_ref(), &[]);
    let id = &f * &g;
    for i in 0..3 {
        for j in 0..3 {
            let t = if i == j { 1.0 } else { 0.0 };
            assert!((id[(i, j)] - t).abs() < 1e-12);
        }
    }
}

/// r(theta) = (theta0 - 1, 2 theta1 - theta0, theta2)
struct Quad;
impl Problem for Quad {
    fn n_params(&self) -> usize {
        3
    }
    fn evaluate(&mut self, t: &[f64], jac: bool) -> crate::Result<Evaluation> {
        let r = [t[0] - 1.0, 2.0 * t[1] - t[0], t[2]];
        let j = [[1.0, 0.0, 0.0], [-1.0, 2.0, 0.0], [0.0, 0.0, 1.0]];
        let mut ev = Evaluation::cost_only(0.5 * r.iter().map(|v| v * v).sum::<f64>());
        if jac {
            ev.gradient = (0..3)
                .map(|a| (0..3).map(|k| j[k][a] * r[k]).sum())
                .collect();
            ev.gauss_newton = Mat::from_fn(3, 3, |a, b| (0..3).map(|k| j[k][a] * j[k][b]).sum());
        }
        Ok(ev)
    }
}

/// theta = (p0, p0 * p1, 0.5): a nonlinear map of two outer parameters.
struct Map;
impl ParameterMap for Map {
    fn map(&mut self, p: &[f64], jac: bool) -> crate::Result<(Vec<f64>, Option<Mat<f64>>)> {
        let th = vec![p[0], p[0] * p[1], 0.5];
        let m = jac.then(|| mat![[1.0, 0.0], [p[1], p[0]], [0.0, 0.0]]);
        Ok((th, m))
    }
}

#[test]
fn reparameterized_is_the_chain_rule() {
    let mut inner = Quad;
    let mut map = Map;
    let mut prob = Reparameterized::new(&mut inner, &mut map, 2);
    let p = [0.7, 1.9];
    let ev = prob.evaluate(&p, true).unwrap();
    for a in 0..2 {
        let h = 1e-7;
        let mut pp = p;
        pp[a] += h;
        let mut pm = p;
        pm[a] -= h;
        let fd = (prob.evaluate(&pp, false).unwrap().cost
            - prob.evaluate(&pm, false).unwrap().cost)
            / (2.0 * h);
        assert!((ev.gradient[a] - fd).abs() < 1e-7, "{a}");
    }
    // minimise in p: theta0 = 1, theta1 = theta0 / 2 -> p = (1, 0.5)
    let o = crate::optim::Options {
        tol_gradient: 1e-24,
        tol_cost: 1e-16,
        ..Default::default()
    };
    let sol =
        crate::optim::minimize(&mut prob, &p, &o, &mut |_| crate::optim::Flow::Continue).unwrap();
    assert!(
        (sol.theta[0] - 1.0).abs() < 1e-8 && (sol.theta[1] - 0.5).abs() < 1e-8,
        "{:?} {:?}",
        sol.theta,
        sol.stop
    );
}

/// A damped pendulum `x0' = x1, x1' = -w2 sin x0 - c x1 + b u`, `y = (x0, x0 x1)`, with
/// its derivatives for the sensitivity equations.
struct Pendulum;
impl super::ode::OdeModel for Pendulum {
    fn rhs(
        &mut self,
        _t: f64,
        x: faer::MatRef<'_, f64>,
        u: &[f64],
        p: faer::MatRef<'_, f64>,
    ) -> crate::Result<Mat<f64>> {
        Ok(Mat::from_fn(2, x.ncols(), |i, c| {
            if i == 0 {
                x[(1, c)]
            } else {
                -p[(0, c)] * x[(0, c)].sin() - p[(1, c)] * x[(1, c)] + p[(2, c)] * u[0]
            }
        }))
    }
    fn output(
        &mut self,
        _t: f64,
        x: faer::MatRef<'_, f64>,
        _u: &[f64],
        _p: faer::MatRef<'_, f64>,
    ) -> crate::Result<Mat<f64>> {
        Ok(Mat::from_fn(2, x.ncols(), |i, c| {
            if i == 0 {
                x[(0, c)]
            } else {
                x[(0, c)] * x[(1, c)]
            }
        }))
    }
    fn rhs_derivatives(
        &mut self,
        _t: f64,
        x: &[f64],
        u: &[f64],
        p: &[f64],
    ) -> crate::Result<Option<super::ode::Derivatives>> {
        let f = mat![[x[1]], [-p[0] * x[0].sin() - p[1] * x[1] + p[2] * u[0]]];
        let fx = mat![[0.0, 1.0], [-p[0] * x[0].cos(), -p[1]]];
        let fp = mat![[0.0, 0.0, 0.0], [-x[0].sin(), -x[1], u[0]]];
        Ok(Some((f, fx, fp)))
    }
    fn output_derivatives(
        &mut self,
        _t: f64,
        x: &[f64],
        _u: &[f64],
        _p: &[f64],
    ) -> crate::Result<Option<super::ode::Derivatives>> {
        let h = mat![[x[0]], [x[0] * x[1]]];
        Ok(Some((h, mat![[1.0, 0.0], [x[1], x[0]]], Mat::zeros(2, 3))))
    }
}

#[test]
fn sensitivity_jacobian_is_the_derivative_of_the_simulation() {
    use super::ode::{jacobian, Integrator, OdeJacobian, OdeOptions, OdeStructure};
    let u = Mat::from_fn(120, 1, |t, _| ((t / 15) % 2) as f64 * 2.0 - 1.0);
    let st = OdeStructure {
        nx: 2,
        p: vec![9.0, 0.4, 2.0],
        free_p: vec![0, 2],
        x0: vec![vec![0.6, -0.2]],
        free_x0: vec![(0, 1)],
        typical: vec![1.0; 3],
    };
    for integ in [
        Integrator::Rk4 { substeps: 2 },
        Integrator::Adaptive {
            rtol: 1e-11,
            atol: 1e-13,
        },
    ] {
        let o = OdeOptions {
            dt: 0.05,
            integrator: integ,
            jacobian: OdeJacobian::Sensitivity,
            ..Default::default()
        };
        let (y, j) = jacobian(&mut Pendulum, &[u.as_ref()], &st, &o).unwrap();
        // central differences of the simulation
        let mut o_fd = o.clone();
        o_fd.jacobian = OdeJacobian::FiniteDifference;
        for k in 0..3 {
            let h = 1e-6;
            let shifted = |d: f64| {
                let mut s = st.clone();
                if k < 2 {
                    s.p[s.free_p[k]] += d;
                } else {
                    s.x0[0][1] += d;
                }
                jacobian(&mut Pendulum, &[u.as_ref()], &s, &o_fd).unwrap().0
            };
            let (yp, ym) = (shifted(h), shifted(-h));
            let mut worst = 0.0f64;
            let mut scale = 0.0f64;
            for t in 0..y.nrows() {
                for i in 0..2 {
                    let fd = (yp[(t, i)] - ym[(t, i)]) / (2.0 * h);
                    worst = worst.max((j[(t * 2 + i, k)] - fd).abs());
                    scale = scale.max(fd.abs());
                }
            }
            let tol = match integ {
                Integrator::Rk4 { .. } => 1e-7,
                Integrator::Adaptive { .. } => 1e-5,
            };
            assert!(worst < tol * scale, "{integ:?} k={k}: {worst} of {scale}");
        }
    }
}

/// A discrete oscillator `A = r [[cos w, sin w], [-sin w, cos w]]`, `B = (0, g)`, `C = (1, 0)`,
/// `D = 0` in `p = (r, w, g)`: 2 x (2 + 1 + 1) + 1 = 9 entries of `(A, B, C, D)`.
struct Oscillator;

impl Oscillator {
    fn theta(p: &[f64]) -> Vec<f64> {
        let (r, w, g) = (p[0], p[1], p[2]);
        let (c, s) = (w.cos(), w.sin());
        vec![r * c, r * s, -r * s, r * c, 0.0, g, 1.0, 0.0, 0.0]
    }
}

impl ParameterMap for Oscillator {
    fn map(&mut self, p: &[f64], jac: bool) -> crate::Result<(Vec<f64>, Option<Mat<f64>>)> {
        let (r, w) = (p[0], p[1]);
        let (c, s) = (w.cos(), w.sin());
        let m = jac.then(|| {
            let mut m = Mat::zeros(9, 3);
            for (i, (dr, dw)) in [(c, -r * s), (s, r * c), (-s, -r * c), (c, -r * s)]
                .into_iter()
                .enumerate()
            {
                m[(i, 0)] = dr;
                m[(i, 1)] = dw;
            }
            m[(5, 2)] = 1.0;
            m
        });
        Ok((Self::theta(p), m))
    }
}

/// Lines of the oscillator at `p`, unit weights.
fn oscillator_lines(p: &[f64], omega: &[f64]) -> (Mat<f64>, Mat<f64>, Mat<f64>) {
    let th = Oscillator::theta(p);
    let g: Vec<faer::c64> = omega
        .iter()
        .map(|&w| {
            // C (zI - A)^-1 B with C = e1, B = g e2: -a01 g / det(zI - A)
            let z = faer::c64::new(w.cos(), w.sin());
            let (a00, a01, a10, a11) = (th[0], th[1], th[2], th[3]);
            let det = (z - a00) * (z - a11) - faer::c64::new(a01 * a10, 0.0);
            faer::c64::new(a01 * th[5], 0.0) / det
        })
        .collect();
    let k = omega.len();
    (
        Mat::from_fn(k, 1, |i, _| g[i].re),
        Mat::from_fn(k, 1, |i, _| g[i].im),
        Mat::from_fn(k, 1, |_, _| 1.0),
    )
}

/// [`super::frequency::linear_frequency`] of the oscillator on `lines` from `(r0, 0.5, 1.0)`.
fn fit_oscillator(
    lines: &crate::pem::Lines<'_>,
    r0: f64,
    fixed: Option<Vec<bool>>,
) -> crate::Result<super::frequency::FrequencyFit> {
    let o = crate::optim::Options {
        fixed,
        ..Default::default()
    };
    super::frequency::linear_frequency(
        (2, 1, 1),
        lines,
        &mut Oscillator,
        &[r0, 0.5, 1.0],
        &o,
        &mut |_| crate::optim::Flow::Continue,
    )
}

#[test]
fn frequency_fit_recovers_the_parameters_from_exact_lines() {
    use crate::pem::Lines;
    let truth = [0.9, 0.6, 1.5];
    let omega: Vec<f64> = (1..30).map(|k| 0.1 * k as f64).collect();
    let (re, im, w) = oscillator_lines(&truth, &omega);
    let lines = Lines {
        omega: &omega,
        re: re.as_ref(),
        im: im.as_ref(),
        weight: w.as_ref(),
    };
    let r = fit_oscillator(&lines, 0.8, None).unwrap();
    for (a, b) in r.p.iter().zip(truth) {
        assert!((a - b).abs() < 1e-10, "{:?}", r.p);
    }
    assert_eq!(r.covariance.rank, 3);
    assert!(r.spectral_radius < 1.0 && (r.spectral_radius - 0.9).abs() < 1e-10);
    // a fixed parameter stays, has no variance, and the others absorb what they can
    let r = fit_oscillator(&lines, 0.8, Some(vec![false, false, true])).unwrap();
    assert_eq!(r.p[2], 1.0);
    assert_eq!(r.covariance.covariance[(2, 2)], 0.0);
    // too few lines for the free parameters, an unstable start: clear errors
    let one = [0.5];
    let (re1, im1, w1) = oscillator_lines(&truth, &one);
    let few = Lines {
        omega: &one,
        re: re1.as_ref(),
        im: im1.as_ref(),
        weight: w1.as_ref(),
    };
    let e = fit_oscillator(&few, 0.8, None).unwrap_err();
    assert!(e.to_string().contains("excite more lines"), "{e}");
    let e = fit_oscillator(&lines, 1.2, None).unwrap_err();
    assert!(e.to_string().contains("unit circle"), "{e}");
}
