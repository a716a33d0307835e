//! Candidate terms: polynomial monomials of any degree, or radial basis functions.

use faer::Mat;

use crate::error::{Result, SysidError};

/// One term of a NARX equation.
#[derive(Debug, Clone, PartialEq)]
pub enum Term {
    /// Product of the lagged variables listed (non-decreasing indices, repeats are powers);
    /// the empty list is the constant term.
    Monomial(Vec<usize>),
    /// Gaussian radial basis function number `c` of the basis.
    Rbf(usize),
    /// The user-supplied regressor held in variable `v` (a [`Signal::Custom`] variable of
    /// the lag spec, after the lagged ones).
    ///
    /// [`Signal::Custom`]: super::regressors::Signal::Custom
    Custom(usize),
}

/// Gaussian radial basis functions `exp(-|z - c_k|^2 / (2 w_k^2))` of the scaled variables
/// `z_v = (x_v - shift_v) / scale_v`.
#[derive(Debug, Clone, PartialEq)]
pub struct RbfBasis {
    /// Centres, one row per function, in scaled coordinates (`n_centres x n_vars`).
    pub centres: Mat<f64>,
    /// Width of each function (scaled units).
    pub widths: Vec<f64>,
    /// Per-variable shift.
    pub shift: Vec<f64>,
    /// Per-variable scale (positive).
    pub scale: Vec<f64>,
}

/// The family of candidate terms.
#[derive(Debug, Clone, PartialEq)]
pub enum Basis {
    /// All monomials of the lagged variables of degree `0..=degree`.
    Polynomial {
        /// Largest total degree.
        degree: usize,
    },
    /// The constant, the linear terms, and the radial basis functions.
    Rbf(RbfBasis),
}

impl Basis {
    /// Value of `term` at the lagged variables `x`.
    #[inline]
    pub fn eval(&self, term: &Term, x: &[f64]) -> f64 {
        match term {
            Term::Monomial(v) => v.iter().map(|&i| x[i]).product(),
            Term::Rbf(c) => match self {
                Basis::Rbf(r) => r.eval(*c, x),
                Basis::Polynomial { .. } => f64::NAN,
            },
            Term::Custom(v) => x[*v],
        }
    }

    /// Checks the basis against `n_vars` lagged variables.
    pub fn check(&self, n_vars: usize) -> Result<()> {
        if let Basis::Rbf(r) = self {
            if r.centres.ncols() != n_vars
                || r.shift.len() != n_vars
                || r.scale.len() != n_vars
                || r.widths.len() != r.centres.nrows()
            {
                return Err(SysidError::invalid(
                    "basis",
                    format!(
                        "RBF centres must be (n_centres, {n_vars}) with one width per centre \
                         and one shift and scale per lagged variable"
                    ),
                ));
            }
            if r.widths
                .iter()
                .chain(&r.scale)
                .any(|w| !(*w > 0.0 && w.is_finite()))
            {
                return Err(SysidError::invalid(
                    "basis",
                    "RBF widths and scales must be positive and finite",
                ));
            }
        }
        Ok(())
    }
}

impl RbfBasis {
    #[inline]
    fn eval(&self, c: usize, x: &[f64]) -> f64 {
        let mut s = 0.0;
        for v in 0..self.shift.len() {
            let d = (x[v] - self.shift[v]) / self.scale[v] - self.centres[(c, v)];
            s += d * d;
        }
        let w = self.widths[c];
        (-s / (2.0 * w * w)).exp()
    }
}

/// The enumerated candidate terms of a basis over `n_vars` lagged variables.
///
/// Monomials are listed by degree; each of degree `d >= 1` is its parent (degree `d - 1`,
/// also listed) times one variable, so a block of candidate columns costs one product per
/// sample and term. Only the columns of parents are stored while a block is generated.
#[derive(Debug, Clone)]
pub struct Candidates {
    /// The terms, in candidate order.
    pub terms: Vec<Term>,
    /// The basis they come from.
    pub basis: Basis,
    parent: Vec<Option<(usize, usize)>>,
    slot: Vec<Option<usize>>,
    n_slots: usize,
    n_vars: usize,
    /// Runs of consecutive leaf monomials with the same parent and consecutive last
    /// variables: `(parent, first term, first variable, count)`.
    groups: Vec<(usize, usize, usize, usize)>,
    grouped: Vec<bool>,
}

/// Largest number of candidate terms accepted.
pub const MAX_CANDIDATES: usize = 5_000_000;

impl Candidates {
    /// Enumerates the candidates of `basis` over `n_vars` variables.
    ///
    /// ```
    /// use sysid_core::narx::basis::{Basis, Candidates};
    /// // 2 variables, degree 2: 1, x0, x1, x0^2, x0 x1, x1^2
    /// assert_eq!(Candidates::new(&Basis::Polynomial { degree: 2 }, 2).unwrap().len(), 6);
    /// ```
    pub fn new(basis: &Basis, n_vars: usize) -> Result<Self> {
        Self::with_custom(basis, n_vars, 0)
    }

    /// The candidates of `basis` over `n_lagged` lagged variables, followed by `n_custom`
    /// user-supplied regressors (variables `n_lagged..n_lagged + n_custom`, one term each).
    ///
    /// ```
    /// use sysid_core::narx::basis::{Basis, Candidates, Term};
    /// let c = Candidates::with_custom(&Basis::Polynomial { degree: 2 }, 2, 1).unwrap();
    /// assert_eq!((c.len(), c.terms[6].clone()), (7, Term::Custom(2)));
    /// ```
    pub fn with_custom(basis: &Basis, n_lagged: usize, n_custom: usize) -> Result<Self> {
        let n_vars = n_lagged;
        basis.check(n_vars)?;
        let mut terms = vec![Term::Monomial(vec![])];
        let mut parent = vec![None];
        match basis {
            Basis::Polynomial { degree } => {
                // number of monomials: binomial(n_vars + degree, degree)
                let mut count: f64 = 1.0;
                for k in 1..=*degree {
                    count = count * (n_vars + k) as f64 / k as f64;
                }
                if count > MAX_CANDIDATES as f64 {
                    return Err(SysidError::invalid(
                        "degree",
                        format!(
                            "{count:.0} candidate monomials of degree <= {degree} in {n_vars} \
                             lagged variables exceed {MAX_CANDIDATES}; lower the lags or degree"
                        ),
                    ));
                }
                let mut prev = 0..1;
                for _ in 0..*degree {
                    let start = terms.len();
                    for p in prev.clone() {
                        let Term::Monomial(ref vars) = terms[p] else {
                            unreachable!()
                        };
                        let first = vars.last().copied().unwrap_or(0);
                        let base = vars.clone();
                        for v in first..n_vars {
                            let mut t = base.clone();
                            t.push(v);
                            terms.push(Term::Monomial(t));
                            parent.push(Some((p, v)));
                        }
                    }
                    prev = start..terms.len();
                }
            }
            Basis::Rbf(r) => {
                for v in 0..n_vars {
                    terms.push(Term::Monomial(vec![v]));
                    parent.push(Some((0, v)));
                }
                for c in 0..r.centres.nrows() {
                    terms.push(Term::Rbf(c));
                    parent.push(None);
                }
            }
        }
        for c in 0..n_custom {
            terms.push(Term::Custom(n_lagged + c));
            parent.push(None);
        }
        let n_vars = n_lagged + n_custom;
        // parents keep their block column while children are generated
        let mut is_parent = vec![false; terms.len()];
        for p in parent.iter().flatten() {
            is_parent[p.0] = true;
        }
        let mut n_slots = 0;
        let slot: Vec<Option<usize>> = is_parent
            .iter()
            .map(|&b| {
                b.then(|| {
                    n_slots += 1;
                    n_slots - 1
                })
            })
            .collect();
        let mut groups: Vec<(usize, usize, usize, usize)> = Vec::new();
        let mut grouped = vec![false; terms.len()];
        for k in 0..terms.len() {
            let (Some((p, v)), None) = (parent[k], slot[k]) else {
                continue;
            };
            grouped[k] = true;
            match groups.last_mut() {
                Some(g) if g.0 == p && g.1 + g.3 == k && g.2 + g.3 == v => g.3 += 1,
                _ => groups.push((p, k, v, 1)),
            }
        }
        Ok(Self {
            terms,
            basis: basis.clone(),
            parent,
            slot,
            n_slots,
            n_vars,
            groups,
            grouped,
        })
    }

    /// Number of candidates.
    pub fn len(&self) -> usize {
        self.terms.len()
    }

    /// Whether there is no candidate (never: the constant is always one).
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// Number of variables (lagged ones and custom regressors).
    pub fn n_vars(&self) -> usize {
        self.n_vars
    }

    /// Scratch length (doubles) for [`Self::for_each_column`] on blocks of `len` rows.
    pub fn scratch_len(&self, len: usize) -> usize {
        (self.n_slots + 1) * len
    }

    /// Scratch length (doubles) for [`Self::accumulate`] on blocks of `len` rows and `np`
    /// probes.
    pub fn accumulate_scratch_len(&self, len: usize, np: usize) -> usize {
        (self.n_slots + 2 + np + self.n_vars) * len
    }

    /// For every candidate `k`: adds `phi_k . p_j` to `cross[k * np + j]` for the `np`
    /// probe columns `p` (column-major `len x np`) and, with `sq`, `phi_k . phi_k` to
    /// `sq[k]`, over the block of lagged variables `x` (column-major, `len x n_vars`).
    ///
    /// Leaf monomials (the highest degree, most of the candidates) are never formed: for a
    /// parent column `c`, `(c * x_v) . p = (c * p) . x_v`, one product per sample for all the
    /// parent's children.
    #[allow(clippy::too_many_arguments)]
    pub fn accumulate(
        &self,
        x: &[f64],
        len: usize,
        probes: &[f64],
        np: usize,
        cross: &mut [f64],
        mut sq: Option<&mut [f64]>,
        scratch: &mut [f64],
    ) {
        let (stored, rest) = scratch.split_at_mut(self.n_slots * len);
        let (leaf, rest) = rest.split_at_mut(len);
        let (p2, rest) = rest.split_at_mut(len);
        let (pw, rest) = rest.split_at_mut(np * len);
        let x2 = &mut rest[..self.n_vars * len];
        let mut row = vec![0.0; self.n_vars];
        for k in 0..self.terms.len() {
            if self.grouped[k] {
                continue;
            }
            self.column(k, x, len, stored, leaf, &mut row);
            for j in 0..np {
                cross[k * np + j] += dot(leaf, &probes[j * len..(j + 1) * len]);
            }
            if let Some(sq) = sq.as_deref_mut() {
                sq[k] += dot(leaf, leaf);
            }
        }
        if sq.is_some() {
            for i in 0..self.n_vars * len {
                x2[i] = x[i] * x[i];
            }
        }
        for &(p, k0, v0, count) in &self.groups {
            let s = self.slot[p].expect("parents are stored");
            let pc = &stored[s * len..(s + 1) * len];
            for j in 0..np {
                let pj = &probes[j * len..(j + 1) * len];
                let w = &mut pw[j * len..(j + 1) * len];
                for i in 0..len {
                    w[i] = pc[i] * pj[i];
                }
            }
            for c in 0..count {
                let xv = &x[(v0 + c) * len..(v0 + c + 1) * len];
                for j in 0..np {
                    cross[(k0 + c) * np + j] += dot(&pw[j * len..(j + 1) * len], xv);
                }
            }
            if let Some(sq) = sq.as_deref_mut() {
                for i in 0..len {
                    p2[i] = pc[i] * pc[i];
                }
                for c in 0..count {
                    sq[k0 + c] += dot(p2, &x2[(v0 + c) * len..(v0 + c + 1) * len]);
                }
            }
        }
    }

    /// Candidate `k` over the block `x` (column-major, `len x n_vars`) into `leaf`: a
    /// monomial as its stored parent times one variable, an RBF row by row (`row` is scratch
    /// of `n_vars`); kept in `stored` when it is itself a parent.
    fn column(
        &self,
        k: usize,
        x: &[f64],
        len: usize,
        stored: &mut [f64],
        leaf: &mut [f64],
        row: &mut [f64],
    ) {
        let term = &self.terms[k];
        match (term, self.parent[k]) {
            (Term::Monomial(_), None) => leaf.fill(1.0),
            (Term::Monomial(_), Some((p, v))) => {
                let xv = &x[v * len..(v + 1) * len];
                if p == 0 {
                    leaf.copy_from_slice(xv);
                } else {
                    let s = self.slot[p].expect("parents are stored");
                    let pc = &stored[s * len..(s + 1) * len];
                    for i in 0..len {
                        leaf[i] = pc[i] * xv[i];
                    }
                }
            }
            (Term::Custom(v), _) => leaf.copy_from_slice(&x[v * len..(v + 1) * len]),
            (Term::Rbf(_), _) => {
                for i in 0..len {
                    for v in 0..self.n_vars {
                        row[v] = x[v * len + i];
                    }
                    leaf[i] = self.basis.eval(term, row);
                }
            }
        }
        if let Some(s) = self.slot[k] {
            stored[s * len..(s + 1) * len].copy_from_slice(leaf);
        }
    }

    /// Calls `f(k, column)` for every candidate `k` in order, on the block of lagged
    /// variables `x` (column-major, `len x n_vars`).
    pub fn for_each_column(
        &self,
        x: &[f64],
        len: usize,
        scratch: &mut [f64],
        mut f: impl FnMut(usize, &[f64]),
    ) {
        let (stored, leaf) = scratch.split_at_mut(self.n_slots * len);
        let leaf = &mut leaf[..len];
        let mut row = vec![0.0; self.n_vars];
        for k in 0..self.terms.len() {
            self.column(k, x, len, stored, leaf, &mut row);
            f(k, leaf);
        }
    }

    /// Readable name of a term from the variable names.
    pub fn term_name(&self, k: usize, names: &[String]) -> String {
        term_name(&self.terms[k], names)
    }
}

/// Readable name of a term: `1`, `y0(t-1)^2 u0(t-1)`, `rbf3`.
pub fn term_name(term: &Term, names: &[String]) -> String {
    match term {
        Term::Monomial(v) if v.is_empty() => "1".into(),
        Term::Monomial(v) => {
            let mut parts: Vec<String> = Vec::new();
            let mut i = 0;
            while i < v.len() {
                let mut j = i;
                while j < v.len() && v[j] == v[i] {
                    j += 1;
                }
                let n = &names[v[i]];
                parts.push(if j - i > 1 {
                    format!("{n}^{}", j - i)
                } else {
                    n.clone()
                });
                i = j;
            }
            parts.join(" ")
        }
        Term::Rbf(c) => format!("rbf{c}"),
        Term::Custom(v) => names[*v].clone(),
    }
}

/// Dot product with eight independent partial sums (vectorises without reassociation).
#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; 8];
    let ca = a.chunks_exact(8);
    let cb = b.chunks_exact(8);
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..8 {
            acc[l] += x[l] * y[l];
        }
    }
    let mut tail = 0.0;
    for (x, y) in ra.iter().zip(rb) {
        tail += x * y;
    }
    ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7])) + tail
}
