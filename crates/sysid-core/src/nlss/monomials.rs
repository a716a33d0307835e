//! Monomials of chosen total degrees in a subset of the variables `z = [x; u]`.

use crate::error::{Result, SysidError};

/// Which variables the monomials use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Terms {
    /// States and inputs.
    Full,
    /// States only.
    States,
    /// Inputs only.
    Inputs,
}

crate::names::option_names! { Terms, "terms", false, [
    ("full", Terms::Full), ("states", Terms::States), ("inputs", Terms::Inputs),
] }

/// A list of monomials, each a non-decreasing list of variable indices into `z = [x; u]`
/// (`[0, 0, 3]` is `z0^2 z3`).
///
/// ```
/// use sysid_core::nlss::{Monomials, Terms};
/// let m = Monomials::new(2, 1, Terms::Full, &[2]).unwrap();
/// assert_eq!(m.len(), 6); // x0^2 x0x1 x0u x1^2 x1u u^2
/// let mut v = vec![0.0; 6];
/// m.eval(&[1.0, 2.0, 3.0], &mut v);
/// assert_eq!(v, vec![1.0, 2.0, 3.0, 4.0, 6.0, 9.0]);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Monomials {
    nx: usize,
    terms: Vec<Vec<usize>>,
}

fn multisets(vars: &[usize], degree: usize, out: &mut Vec<Vec<usize>>) {
    fn rec(
        vars: &[usize],
        start: usize,
        left: usize,
        cur: &mut Vec<usize>,
        out: &mut Vec<Vec<usize>>,
    ) {
        if left == 0 {
            out.push(cur.clone());
            return;
        }
        for i in start..vars.len() {
            cur.push(vars[i]);
            rec(vars, i, left - 1, cur, out);
            cur.pop();
        }
    }
    rec(vars, 0, degree, &mut Vec::new(), out);
}

impl Monomials {
    /// All monomials of the given total degrees (each >= 2) in the variables `terms` selects,
    /// for `nx` states and `nu` inputs.
    pub fn new(nx: usize, nu: usize, terms: Terms, degrees: &[usize]) -> Result<Self> {
        if let Some(d) = degrees.iter().find(|&&d| !(2..=9).contains(&d)) {
            return Err(SysidError::invalid(
                "degree",
                format!("monomial degrees must lie in 2..9, got {d}"),
            ));
        }
        let vars: Vec<usize> = match terms {
            Terms::Full => (0..nx + nu).collect(),
            Terms::States => (0..nx).collect(),
            Terms::Inputs => (nx..nx + nu).collect(),
        };
        let mut ds = degrees.to_vec();
        ds.sort_unstable();
        ds.dedup();
        let mut out = Vec::new();
        for d in ds {
            multisets(&vars, d, &mut out);
        }
        Ok(Monomials { nx, terms: out })
    }

    /// No monomials.
    pub fn empty(nx: usize) -> Self {
        Monomials {
            nx,
            terms: Vec::new(),
        }
    }

    /// From explicit index lists (indices below `nx + nu`; an empty list is the constant 1).
    pub fn from_terms(nx: usize, nu: usize, mut terms: Vec<Vec<usize>>) -> Result<Self> {
        if let Some(t) = terms.iter().find(|t| t.iter().any(|&v| v >= nx + nu)) {
            return Err(SysidError::invalid(
                "monomials",
                format!(
                    "term {t:?} uses a variable beyond the {} of z = [x; u]",
                    nx + nu
                ),
            ));
        }
        terms.iter_mut().for_each(|t| t.sort_unstable());
        Ok(Monomials { nx, terms })
    }

    /// The index lists.
    pub fn terms(&self) -> &[Vec<usize>] {
        &self.terms
    }

    /// Number of monomials.
    pub fn len(&self) -> usize {
        self.terms.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// Values at `z` into `out` (length [`Self::len`]).
    #[inline]
    pub fn eval(&self, z: &[f64], out: &mut [f64]) {
        for (o, t) in out.iter_mut().zip(&self.terms) {
            *o = t.iter().map(|&v| z[v]).product();
        }
    }

    /// Derivatives in the states at `z` into `out` (row-major `len x nx`, overwritten).
    #[inline]
    pub fn dx(&self, z: &[f64], out: &mut [f64]) {
        let nx = self.nx;
        out.iter_mut().for_each(|v| *v = 0.0);
        for (k, t) in self.terms.iter().enumerate() {
            for (i, &v) in t.iter().enumerate() {
                if v < nx {
                    let p: f64 = t
                        .iter()
                        .enumerate()
                        .filter(|&(j, _)| j != i)
                        .map(|(_, &w)| z[w])
                        .product();
                    out[k * nx + v] += p;
                }
            }
        }
    }
}
