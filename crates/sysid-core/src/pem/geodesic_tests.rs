//! The substituted-residual gradient pass (`J^T W x`) of the geodesic acceleration against
//! the dense Jacobian by central differences of the errors.

use super::tests::{data, noise, options, truth, truth_with_feedthrough};
use super::*;
use crate::model::StateSpace;
use crate::optim::Problem;

#[test]
fn substituted_gradient_equals_the_dense_jacobian_product() {
    let (sys, k) = truth_with_feedthrough();
    let (u1, u2) = (noise(120, 2, 31), noise(70, 2, 32));
    let e1 = noise(120, 2, 33) * faer::Scale(0.3);
    let y1 = data(&sys, &k, &u1, &e1, &[0.3, 0.0, -0.2]);
    let y2 = data(
        &sys,
        &k,
        &u2,
        &(noise(70, 2, 34) * faer::Scale(0.3)),
        &[0.0; 3],
    );
    let views = [(u1.as_ref(), y1.as_ref()), (u2.as_ref(), y2.as_ref())];
    for (focus, est_d, est_k, x0) in [
        (Focus::Prediction, true, true, vec![InitialState::Estimate]),
        (Focus::Prediction, false, false, vec![InitialState::Zero]),
        (Focus::Simulation, true, false, vec![InitialState::Estimate]),
    ] {
        let o = options(focus, est_d, est_k, x0, 9);
        let mut pr = Predictor::new(&sys, Some(k.as_ref()), &views, &o).unwrap();
        let th = pr.pack(
            &sys,
            k.as_ref(),
            &[vec![0.1, -0.2, 0.3], vec![0.05, 0.0, 0.1]],
        );
        // a weighting that is not the identity
        pr.reweight_at(&th).unwrap();
        let w = pr.rinv.transpose() * &pr.rinv;
        let (nr, l) = (pr.n_samples * pr.l, pr.l);
        let x: Vec<f64> = (0..nr)
            .map(|i| ((i * 7919 % 23) as f64 - 11.0) / 5.0)
            .collect();
        // dense: column j of J = d e / d theta_j by central differences
        let mut dense = vec![0.0; th.len()];
        for (j, dj) in dense.iter_mut().enumerate() {
            let h = 1e-6;
            let (mut tp, mut tm) = (th.clone(), th.clone());
            tp[j] += h;
            tm[j] -= h;
            let (rp, rm) = (pr.residuals(&tp), pr.residuals(&tm));
            for s in 0..nr / l {
                for a in 0..l {
                    let wx: f64 = (0..l).map(|b| w[(a, b)] * x[s * l + b]).sum();
                    *dj += (rp[s * l + a] - rm[s * l + a]) / (2.0 * h) * wx;
                }
            }
        }
        let scale = dense.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for modal in [true, false] {
            pr.modal = modal;
            let jtx = pr
                .gradient_with_residuals(&th, 0.0, x.clone())
                .unwrap()
                .unwrap();
            for (j, (a, b)) in jtx.iter().zip(&dense).enumerate() {
                assert!(
                    (a - b).abs() < 1e-6 * scale,
                    "{focus:?} modal {modal} param {j}: {a} vs {b}"
                );
            }
            // c e + 0 with c = 1 is the gradient itself
            let g = pr
                .gradient_with_residuals(&th, 1.0, vec![0.0; nr])
                .unwrap()
                .unwrap();
            let ev = pr.evaluate(&th, true).unwrap();
            let gs = ev.gradient.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (a, b) in g.iter().zip(&ev.gradient) {
                assert!((a - b).abs() < 1e-11 * gs, "{a} vs {b}");
            }
        }
        pr.modal = true;
        // the plain (row) path has no substituted pass: no acceleration
        pr.structured = false;
        assert!(pr.geodesic_gradient(&th, &th, 0.1).unwrap().is_none());
        pr.structured = true;
    }
}

/// A search with geodesic acceleration: the accelerated steps are taken, the result is
/// bit-for-bit the same for any thread count and not above the start's cost.
#[test]
fn accelerated_search_is_identical_for_any_thread_count() {
    let (sys, k) = truth();
    let u = noise(400, 2, 41);
    let y = data(
        &sys,
        &k,
        &u,
        &(noise(400, 2, 42) * faer::Scale(0.3)),
        &[0.0; 3],
    );
    let start = StateSpace::new(
        &sys.a + noise(3, 3, 43) * faer::Scale(0.1),
        &sys.b + noise(3, 2, 44) * faer::Scale(0.3),
        sys.c.clone(),
        sys.d.clone(),
    )
    .unwrap();
    let views = [(u.as_ref(), y.as_ref())];
    let mut o = options(
        Focus::Simulation,
        true,
        false,
        vec![InitialState::Estimate],
        16,
    );
    o.reweight = false;
    o.optim.geodesic = true;
    let run = |threads: usize| {
        crate::optim::dense::on_threads(threads, || {
            pem(&start, None, &views, &o, &mut |_| {
                crate::optim::Flow::Continue
            })
            .unwrap()
        })
    };
    let serial = run(1);
    let parallel = run(2);
    assert_eq!(serial.theta, parallel.theta);
    assert_eq!(serial.solution.geodesic, parallel.solution.geodesic);
    let sol = &serial.solution;
    assert!(sol.geodesic.accepted > 0, "{:?}", sol.geodesic);
    assert!(
        sol.cost <= sol.history[0],
        "{} > {}",
        sol.cost,
        sol.history[0]
    );
}
