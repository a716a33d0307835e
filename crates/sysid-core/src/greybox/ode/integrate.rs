//! Integration of the state (and sensitivity) equations over one sample interval: the
//! right-hand side on all columns, classical Runge-Kutta with sub-steps, Dormand-Prince 5(4)
//! with error control, and the outputs with their sensitivities.

use super::problem::OdeProblem;
use super::Integrator;
use crate::error::{Result, SysidError};
use faer::Mat;

impl OdeProblem<'_> {
    pub(super) fn rhs(
        &mut self,
        t: f64,
        x: &Mat<f64>,
        u: &[f64],
        p: &Mat<f64>,
    ) -> Result<Mat<f64>> {
        if self.sens_cols.is_some() {
            return self.rhs_sensitivity(t, x, u, p);
        }
        self.rhs_calls += 1;
        let d = self.model.rhs(t, x.as_ref(), u, p.as_ref())?;
        if d.nrows() != x.nrows() || d.ncols() != x.ncols() {
            return Err(SysidError::invalid(
                "f",
                format!(
                    "returned a {}x{} array for {} states and {} columns",
                    d.nrows(),
                    d.ncols(),
                    x.nrows(),
                    x.ncols()
                ),
            ));
        }
        Ok(d)
    }

    /// `[f, f_x S + f_p]` for the state in column 0 and the sensitivities in the others.
    pub(super) fn rhs_sensitivity(
        &mut self,
        t: f64,
        x: &Mat<f64>,
        u: &[f64],
        p: &Mat<f64>,
    ) -> Result<Mat<f64>> {
        self.rhs_calls += 1;
        let nx = x.nrows();
        let np = p.nrows();
        let xs: Vec<f64> = (0..nx).map(|i| x[(i, 0)]).collect();
        let ps: Vec<f64> = (0..np).map(|i| p[(i, 0)]).collect();
        let (f, fx, fp) = self
            .model
            .rhs_derivatives(t, &xs, u, &ps)?
            .ok_or_else(no_derivatives)?;
        check_derivatives("f", &f, &fx, &fp, nx, nx, np)?;
        let cols = self.sens_cols.as_ref().expect("sensitivity columns");
        let nfp = self.st.free_p.len();
        let mut out = &fx * x;
        for i in 0..nx {
            out[(i, 0)] = f[(i, 0)];
        }
        for (c, &k) in cols.iter().enumerate() {
            if k < nfp {
                let pi = self.st.free_p[k];
                for i in 0..nx {
                    out[(i, c + 1)] += fp[(i, pi)];
                }
            }
        }
        Ok(out)
    }

    /// Advances `x` over one sample interval `[t, t + dt]` with input `u` held.
    pub(super) fn advance(
        &mut self,
        t: f64,
        x: &mut Mat<f64>,
        u: &[f64],
        p: &Mat<f64>,
    ) -> Result<()> {
        let dt = self.opt.dt;
        match self.opt.integrator {
            Integrator::Rk4 { substeps } => {
                let h = dt / substeps as f64;
                for s in 0..substeps {
                    let ts = t + s as f64 * h;
                    let k1 = self.rhs(ts, x, u, p)?;
                    let x2 = &*x + &k1 * (0.5 * h);
                    let k2 = self.rhs(ts + 0.5 * h, &x2, u, p)?;
                    let x3 = &*x + &k2 * (0.5 * h);
                    let k3 = self.rhs(ts + 0.5 * h, &x3, u, p)?;
                    let x4 = &*x + &k3 * h;
                    let k4 = self.rhs(ts + h, &x4, u, p)?;
                    *x = &*x + (&k1 + &k2 * 2.0 + &k3 * 2.0 + &k4) * (h / 6.0);
                }
                Ok(())
            }
            Integrator::Adaptive { rtol, atol } => self.dopri(t, x, u, p, rtol, atol),
        }
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn dopri(
        &mut self,
        t0: f64,
        x: &mut Mat<f64>,
        u: &[f64],
        p: &Mat<f64>,
        rtol: f64,
        atol: f64,
    ) -> Result<()> {
        const C: [f64; 7] = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0];
        const A: [[f64; 6]; 7] = [
            [0.0; 6],
            [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
            [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
            [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
            [
                19372.0 / 6561.0,
                -25360.0 / 2187.0,
                64448.0 / 6561.0,
                -212.0 / 729.0,
                0.0,
                0.0,
            ],
            [
                9017.0 / 3168.0,
                -355.0 / 33.0,
                46732.0 / 5247.0,
                49.0 / 176.0,
                -5103.0 / 18656.0,
                0.0,
            ],
            [
                35.0 / 384.0,
                0.0,
                500.0 / 1113.0,
                125.0 / 192.0,
                -2187.0 / 6784.0,
                11.0 / 84.0,
            ],
        ];
        // 5th-order weights are A[6] (with 0 for k7); error weights b5 - b4:
        const E: [f64; 7] = [
            71.0 / 57600.0,
            0.0,
            -71.0 / 16695.0,
            71.0 / 1920.0,
            -17253.0 / 339200.0,
            22.0 / 525.0,
            -1.0 / 40.0,
        ];
        let dt = self.opt.dt;
        let t_end = t0 + dt;
        let mut t = t0;
        let mut h = self.h_last.min(dt);
        let mut rejected = 0usize;
        while t < t_end - 1e-14 * dt {
            h = h.min(t_end - t);
            let mut k: Vec<Mat<f64>> = Vec::with_capacity(7);
            for s in 0..7 {
                let mut xs = x.clone();
                for (j, kj) in k.iter().enumerate() {
                    if A[s][j] != 0.0 {
                        xs += kj * (h * A[s][j]);
                    }
                }
                k.push(self.rhs(t + C[s] * h, &xs, u, p)?);
            }
            let mut xn = x.clone();
            for j in 0..6 {
                if A[6][j] != 0.0 {
                    xn += &k[j] * (h * A[6][j]);
                }
            }
            let mut err = 0.0f64;
            for c in 0..x.ncols() {
                let mut s = 0.0;
                for i in 0..x.nrows() {
                    let mut e = 0.0;
                    for j in 0..7 {
                        e += E[j] * k[j][(i, c)];
                    }
                    let sc = atol + rtol * x[(i, c)].abs().max(xn[(i, c)].abs());
                    s += (h * e / sc).powi(2);
                }
                err = err.max((s / x.nrows().max(1) as f64).sqrt());
            }
            if !err.is_finite() {
                return Err(SysidError::numerical(
                    "adaptive integrator",
                    "the state became non-finite; the parameters make the model blow up",
                ));
            }
            if err <= 1.0 {
                t += h;
                *x = xn;
                let fac = if err == 0.0 {
                    5.0
                } else {
                    (0.9 * err.powf(-0.2)).clamp(0.2, 5.0)
                };
                self.h_last = h * fac;
                h *= fac;
            } else {
                rejected += 1;
                if rejected > 10_000 || h < 1e-12 * dt {
                    return Err(SysidError::numerical(
                        "adaptive integrator",
                        "the step size fell below 1e-12 of the sample time (a stiff or \
                         blowing-up model); use integrator=\"rk4\" with more substeps",
                    ));
                }
                h *= (0.9 * err.powf(-0.2)).clamp(0.1, 1.0);
            }
        }
        Ok(())
    }

    /// `h` at the state in column 0, and `dy/dtheta = h_x S + h_p` into `dy`.
    pub(super) fn sensitivity_output(
        &mut self,
        t: f64,
        x: &Mat<f64>,
        u: &[f64],
        p: &Mat<f64>,
        cols: &[usize],
        dy: &mut Mat<f64>,
    ) -> Result<Mat<f64>> {
        let nx = x.nrows();
        let np = p.nrows();
        let l = self.l;
        let xs: Vec<f64> = (0..nx).map(|i| x[(i, 0)]).collect();
        let ps: Vec<f64> = (0..np).map(|i| p[(i, 0)]).collect();
        let (h, hx, hp) = self
            .model
            .output_derivatives(t, &xs, u, &ps)?
            .ok_or_else(no_derivatives)?;
        check_derivatives("h", &h, &hx, &hp, l, nx, np)?;
        let hs = &hx * x;
        let nfp = self.st.free_p.len();
        for (c, &k) in cols.iter().enumerate() {
            for i in 0..l {
                dy[(i, k)] = hs[(i, c + 1)]
                    + if k < nfp {
                        hp[(i, self.st.free_p[k])]
                    } else {
                        0.0
                    };
            }
        }
        Ok(h)
    }
}

fn no_derivatives() -> SysidError {
    SysidError::invalid(
        "jacobian",
        "the sensitivity equations need the model's derivatives (df/dx, df/dp, dh/dx, \
         dh/dp); give them, or use finite differences",
    )
}

fn check_derivatives(
    what: &'static str,
    v: &Mat<f64>,
    dx: &Mat<f64>,
    dp: &Mat<f64>,
    rows: usize,
    nx: usize,
    np: usize,
) -> Result<()> {
    if v.nrows() != rows
        || v.ncols() != 1
        || dx.nrows() != rows
        || dx.ncols() != nx
        || dp.nrows() != rows
        || dp.ncols() != np
    {
        return Err(SysidError::invalid(
            what,
            format!(
                "its derivatives have shapes {}x{}, {}x{}, {}x{}; expected {rows}x1, \
                 {rows}x{nx} (d/dx) and {rows}x{np} (d/dp, every parameter)",
                v.nrows(),
                v.ncols(),
                dx.nrows(),
                dx.ncols(),
                dp.nrows(),
                dp.ncols()
            ),
        ));
    }
    Ok(())
}
