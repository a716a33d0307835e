//! A step that would leave the admissible set, turned along its boundary.
//!
//! Halving such a step keeps its direction: at a boundary the search then takes shorter and
//! shorter steps into it (halved 20 times and more) and stops on the cost tolerance far from
//! the best admissible point (an integrating plant refined with a stable `A` stalled at 300
//! times the cost it reaches along the bound). Removing the part of the step beyond the
//! boundary (to first order, along the gradient of the boundary's margin,
//! [`super::Problem::bound_margin`], in the search's scaled metric) takes the step to the
//! boundary and along it; halving then only corrects its curvature.

use super::search::{project, Point};
use super::{Options, Problem};

/// Relative finite-difference step for the margin's gradient.
const H_REL: f64 = 1e-7;

/// `step` with its part beyond the linearised boundary removed along the margin's gradient
/// at `pt` (metric: the Gauss-Newton diagonal, Marquardt's scaling): it reaches the boundary
/// and slides along it. `None` when the provider measures no margin, the gradient vanishes,
/// or the turned step is no descent direction (at a point where the cost's gradient is
/// against the boundary's, nothing is left to slide along).
fn along_boundary(
    problem: &mut dyn Problem,
    pt: &Point,
    step: &[f64],
    moving: &[bool],
) -> Option<Vec<f64>> {
    let p = step.len();
    let m0 = problem.bound_margin(&pt.theta)?;
    // central differences over the parameters that move
    let mut c = vec![0.0; p];
    let mut th = pt.theta.clone();
    for i in (0..p).filter(|&i| moving[i]) {
        let h = H_REL * pt.theta[i].abs().max(1.0);
        th[i] = pt.theta[i] + h;
        let up = problem.bound_margin(&th)?;
        th[i] = pt.theta[i] - h;
        let down = problem.bound_margin(&th)?;
        th[i] = pt.theta[i];
        c[i] = (up - down) / (2.0 * h);
    }
    // the metric's inverse square: 1 / H_ii (1 where the diagonal is not positive)
    let w: Vec<f64> = (0..p)
        .map(|i| {
            let v = pt.h[(i, i)];
            if v > 0.0 && v.is_finite() {
                1.0 / v
            } else {
                1.0
            }
        })
        .collect();
    let cs: f64 = (0..p).map(|i| c[i] * step[i]).sum();
    let cwc: f64 = (0..p).map(|i| c[i] * w[i] * c[i]).sum();
    // the part of the step beyond the (linearised) boundary: the step goes to it, then
    // along it
    let excess = cs + m0;
    if !(cwc > 0.0 && cwc.is_finite() && excess > 0.0) {
        return None;
    }
    let turned: Vec<f64> = (0..p)
        .map(|i| step[i] - excess / cwc * w[i] * c[i])
        .collect();
    let slope: f64 = (0..p).map(|i| pt.g[i] * turned[i]).sum();
    (slope < 0.0 && turned.iter().all(|x| x.is_finite())).then_some(turned)
}

/// A step made admissible: the trial point, the fraction of the step it took, the halvings
/// and whether the step was turned along the admissible set's boundary.
pub(super) struct Shaped {
    pub trial: Vec<f64>,
    pub alpha: f64,
    pub halvings: usize,
    pub turned: bool,
}

/// `theta + step` projected onto the bounds and made admissible: turned along the
/// boundary (when `turn` and the provider measures it), then halved up to 30 times; `None`
/// when no admissible point results.
pub(super) fn shape(
    problem: &mut dyn Problem,
    options: &Options,
    pt: &Point,
    mut step: Vec<f64>,
    blocked: &[bool],
    turn: bool,
) -> Option<Shaped> {
    let p = step.len();
    let at = |s: &[f64], alpha: f64| {
        let mut t: Vec<f64> = (0..p).map(|i| pt.theta[i] + alpha * s[i]).collect();
        project(options, &mut t);
        t
    };
    let mut trial = at(&step, 1.0);
    let mut ok = problem.admissible(&trial);
    let mut turned = false;
    if !ok && turn {
        // turned along the boundary before any halving (the halving keeps it there)
        let moving: Vec<bool> = blocked.iter().map(|b| !b).collect();
        if let Some(t) = along_boundary(problem, pt, &step, &moving) {
            turned = true;
            step = t;
            trial = at(&step, 1.0);
            ok = problem.admissible(&trial);
        }
    }
    let (mut alpha, mut halvings) = (1.0, 0);
    while !ok && halvings < 30 {
        alpha *= 0.5;
        halvings += 1;
        trial = at(&step, alpha);
        ok = problem.admissible(&trial);
    }
    ok.then_some(Shaped {
        trial,
        alpha,
        halvings,
        turned,
    })
}
