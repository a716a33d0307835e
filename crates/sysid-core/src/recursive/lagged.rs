//! Short delay lines and the time-varying filters of the gradient.

/// The last `n` values of a signal, newest first: `get(0)` is the latest pushed.
#[derive(Debug, Clone)]
pub(super) struct Lagged {
    buf: Vec<f64>,
}

impl Lagged {
    pub(super) fn new(n: usize) -> Self {
        Lagged { buf: vec![0.0; n] }
    }

    /// Value `k` samples back from the newest (0 beyond the start of the record).
    #[inline]
    pub(super) fn get(&self, k: usize) -> f64 {
        self.buf[k]
    }

    #[inline]
    pub(super) fn push(&mut self, x: f64) {
        if let Some(last) = self.buf.len().checked_sub(1) {
            self.buf.copy_within(0..last, 1);
            self.buf[0] = x;
        }
    }

    pub(super) fn clear(&mut self) {
        self.buf.iter_mut().for_each(|v| *v = 0.0);
    }
}

/// `out = (1 + num q^-1 ..) / (1 + den q^-1 ..) x`, coefficients given at each step.
#[derive(Debug, Clone)]
pub(super) struct Iir {
    x: Lagged,
    y: Lagged,
}

impl Iir {
    pub(super) fn new(n_num: usize, n_den: usize) -> Self {
        Iir {
            x: Lagged::new(n_num),
            y: Lagged::new(n_den),
        }
    }

    /// Filters one sample with the current coefficients (lengths at most the orders given).
    #[inline]
    pub(super) fn step(&mut self, x: f64, num: &[f64], den: &[f64]) -> f64 {
        let mut out = x;
        for (i, c) in num.iter().enumerate() {
            out += c * self.x.get(i);
        }
        for (i, c) in den.iter().enumerate() {
            out -= c * self.y.get(i);
        }
        self.x.push(x);
        self.y.push(out);
        out
    }
}
