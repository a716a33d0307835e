//! A step that would leave the admissible set, turned along its boundary.
//!
//! Halving such a step keeps its direction: at a boundary the search then takes shorter and
//! shorter steps into it (halved 20 times and more) and stops on the cost tolerance far from
//! the best admissible point (an integrating plant refined with a stable `A` stalled at 300
//! times the cost it reaches along the bound). Removing the part of the step beyond the
//! boundary (to first order, along the gradient of the boundary's margin,
//! [`super::Problem::bound_margin`], in the search's scaled metric) takes the step to the
//! boundary and along it; where the boundary curves away from that line, the step is moved
//! back along the boundary's normal by the margin measured at its end (the second-order
//! correction of sequential quadratic programming), and halving is the last resort. The
//! search uses it once it crawls ([`super::Solution::metric_switched_at`]).

use super::search::{project, Point};
use super::{Options, Problem};

/// Relative finite-difference step for the margin's gradient.
const H_REL: f64 = 1e-7;

/// How far inside the boundary a turned step aims (in the margin's units: a spectral radius
/// `1 - 1e-8` for a stability bound). Aimed at the boundary itself, a pole lands within
/// rounding of the unit circle, where another eigenvalue solver may put it outside.
const INSET: f64 = 1e-8;

/// Corrections of a turned step back onto the boundary (see [`shape`]).
const CORRECTIONS: usize = 4;

/// The margin's gradient `c` at a point and the metric's inverse square `w` (the step moves
/// by `w c` to change the margin).
struct Normal {
    c: Vec<f64>,
    w: Vec<f64>,
    cwc: f64,
}

impl Normal {
    /// `step` moved along `w c` so that its linearised margin changes by `-by`.
    fn shift(&self, step: &[f64], by: f64) -> Vec<f64> {
        (0..step.len())
            .map(|i| step[i] - by / self.cwc * self.w[i] * self.c[i])
            .collect()
    }
}

/// `step` with its part beyond the linearised boundary (less [`INSET`]) removed along the
/// margin's gradient at `pt` (metric: the Gauss-Newton diagonal, Marquardt's scaling): it
/// reaches the boundary and slides along it. `None` when the provider measures no margin,
/// the gradient vanishes, or the turned step is no descent direction (at a point where the
/// cost's gradient is against the boundary's, nothing is left to slide along).
fn along_boundary(
    problem: &mut dyn Problem,
    pt: &Point,
    step: &[f64],
    moving: &[bool],
) -> Option<(Vec<f64>, Normal)> {
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
        .map(|i| pt.diagonal(i).map_or(1.0, |v| 1.0 / v))
        .collect();
    let cs: f64 = (0..p).map(|i| c[i] * step[i]).sum();
    let cwc: f64 = (0..p).map(|i| c[i] * w[i] * c[i]).sum();
    // the part of the step beyond the (linearised) boundary: the step goes to it, then
    // along it
    let excess = cs + m0 + INSET;
    if !(cwc > 0.0 && cwc.is_finite() && excess > 0.0) {
        return None;
    }
    let normal = Normal { c, w, cwc };
    let turned = normal.shift(step, excess);
    let slope: f64 = (0..p).map(|i| pt.g[i] * turned[i]).sum();
    (slope < 0.0 && turned.iter().all(|x| x.is_finite())).then_some((turned, normal))
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
/// boundary (when `turn` and the provider measures it) and, where the boundary curves away
/// from its linearisation, moved back along its normal by the margin measured at the turned
/// point (the second-order correction of sequential quadratic programming), then halved up
/// to 30 times; `None` when no admissible point results.
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
        if let Some((t, normal)) = along_boundary(problem, pt, &step, &moving) {
            turned = true;
            step = t;
            trial = at(&step, 1.0);
            ok = problem.admissible(&trial);
            // where the boundary curves away from its linearisation: back along the normal
            // by the margin measured at the trial, a few times (Newton's iteration for the
            // boundary along that line)
            let mut back = step.clone();
            // the margin's change per unit of the linearised one along that line (secant)
            let (mut slope, mut last): (f64, Option<(f64, f64)>) = (1.0, None);
            for _ in 0..CORRECTIONS {
                if ok {
                    break;
                }
                let Some(m1) = problem.bound_margin(&trial).filter(|m| m.is_finite()) else {
                    break;
                };
                if let Some((m_prev, by)) = last {
                    let r = (m_prev - m1) / by;
                    if r.is_finite() && r > 0.1 {
                        slope = r.min(10.0);
                    }
                }
                let by = (m1 + INSET) / slope;
                back = normal.shift(&back, by);
                last = Some((m1, by));
                if !back.iter().all(|x| x.is_finite()) {
                    break;
                }
                trial = at(&back, 1.0);
                ok = problem.admissible(&trial);
            }
            if ok {
                step = back;
            }
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
