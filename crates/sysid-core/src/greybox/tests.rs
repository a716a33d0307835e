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
