//! The compressed summary of a record: the triangular factor of its block-Hankel matrix.

use super::HankelLayout;
use crate::error::{Result, SysidError};
use crate::linalg::lq_lower;
use faer::{Mat, MatRef};

/// The four block rows of the data matrix.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Block {
    /// Future inputs U_f.
    UFuture,
    /// Past inputs U_p.
    UPast,
    /// Past outputs Y_p.
    YPast,
    /// Future outputs Y_f.
    YFuture,
}

/// Lower-triangular `L` with `H H^T = L L^T`, the data's block-Hankel matrix H compressed.
///
/// It is a value: it can be merged with the factor of another experiment recorded with the
/// same layout ([`HankelFactor::merge`]), stored, and used for many orders and weightings.
#[derive(Debug, Clone, PartialEq)]
pub struct HankelFactor {
    layout: HankelLayout,
    l: Mat<f64>,
    n_columns: usize,
    n_experiments: usize,
}

impl HankelFactor {
    /// Wraps a factor computed elsewhere; `l` must be k x k and lower triangular.
    pub fn from_parts(
        layout: HankelLayout,
        l: Mat<f64>,
        n_columns: usize,
        n_experiments: usize,
    ) -> Result<Self> {
        let k = layout.k();
        if l.nrows() != k || l.ncols() != k {
            return Err(SysidError::ShapeMismatch {
                what: "L".into(),
                expected: format!("({k}, {k})"),
                got: format!("({}, {})", l.nrows(), l.ncols()),
            });
        }
        crate::error::check_finite("L", l.as_ref())?;
        for j in 0..k {
            for i in 0..j {
                if l[(i, j)] != 0.0 {
                    return Err(SysidError::invalid("L", "must be lower triangular"));
                }
            }
        }
        Ok(Self {
            layout,
            l,
            n_columns,
            n_experiments,
        })
    }

    /// The layout (channel counts and horizons).
    pub fn layout(&self) -> &HankelLayout {
        &self.layout
    }

    /// The k x k lower-triangular factor.
    pub fn l(&self) -> MatRef<'_, f64> {
        self.l.as_ref()
    }

    /// Number of Hankel columns summarised (samples minus `p + f - 1` per experiment).
    pub fn n_columns(&self) -> usize {
        self.n_columns
    }

    /// Number of experiments summarised.
    pub fn n_experiments(&self) -> usize {
        self.n_experiments
    }

    /// Rows of L belonging to one block.
    pub fn rows(&self, b: super::Block) -> MatRef<'_, f64> {
        let (s, n) = self.layout.block(b);
        self.l.as_ref().subrows(s, n)
    }

    /// The factor of the concatenated experiments of `self` and `other`.
    pub fn merge(&self, other: &HankelFactor) -> Result<HankelFactor> {
        if self.layout != other.layout {
            return Err(SysidError::IncompatibleFactors {
                reason: format!("layouts differ: {:?} vs {:?}", self.layout, other.layout),
            });
        }
        let k = self.layout.k();
        let mut both = Mat::<f64>::zeros(k, 2 * k);
        both.as_mut().subcols_mut(0, k).copy_from(self.l.as_ref());
        both.as_mut().subcols_mut(k, k).copy_from(other.l.as_ref());
        Ok(HankelFactor {
            layout: self.layout,
            l: lq_lower(both.as_ref()),
            n_columns: self.n_columns + other.n_columns,
            n_experiments: self.n_experiments + other.n_experiments,
        })
    }
}
