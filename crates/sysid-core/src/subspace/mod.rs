//! Subspace identification on a compressed record (placeholder while the engine lands).
use crate::error::{Result, SysidError};
use crate::hankel::HankelFactor;

/// Weighting of the subspace method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// PO-MOESP (past inputs and outputs as instruments).
    #[default]
    Moesp,
}

/// Options.
#[derive(Debug, Clone, Default)]
#[non_exhaustive]
pub struct SubspaceOptions {
    /// Weighting.
    pub method: Method,
}

/// Weighted SVD of a compressed record.
#[derive(Debug, Clone)]
pub struct Subspace {
    sv: Vec<f64>,
}

impl Subspace {
    /// Computes the weighted SVD.
    pub fn new(_factor: &HankelFactor, _opts: &SubspaceOptions) -> Result<Self> {
        Err(SysidError::invalid("method", "not implemented yet"))
    }
    /// Automatic order.
    pub fn auto_order(&self) -> usize {
        self.sv.len()
    }
}
