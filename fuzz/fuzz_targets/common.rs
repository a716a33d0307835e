//! Decoding fuzz bytes into sizes and records (shared by the targets).

use faer::Mat;

/// Reads the fuzz input front to back; runs out gracefully (zeros).
pub struct Bytes<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> Bytes<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        Self { data, pos: 0 }
    }

    pub fn byte(&mut self) -> u8 {
        let b = self.data.get(self.pos).copied().unwrap_or(0);
        self.pos += 1;
        b
    }

    /// A size: mostly small, sometimes huge (to exercise the size checks).
    pub fn size(&mut self, small: usize) -> usize {
        match self.byte() {
            250 => usize::MAX,
            251 => 1 << 40,
            252 => 1 << 20,
            253 => 100_000,
            b => (b as usize) % (small + 1),
        }
    }

    /// A small count in `0..=max` (for the harness's own loops, never huge).
    pub fn small(&mut self, max: usize) -> usize {
        self.byte() as usize % (max + 1)
    }

    /// A sample value: ordinary numbers, with zeros, repeats, huge, tiny and non-finite ones.
    pub fn value(&mut self) -> f64 {
        match self.byte() {
            0 => 0.0,
            1 => f64::NAN,
            2 => f64::INFINITY,
            3 => 1e300,
            4 => 1e-310,
            5 => -1e200,
            b => (b as f64 - 128.0) / 16.0,
        }
    }

    /// An `n x c` matrix of values.
    pub fn mat(&mut self, n: usize, c: usize) -> Mat<f64> {
        let mut m = Mat::zeros(n, c);
        for j in 0..c {
            for i in 0..n {
                m[(i, j)] = self.value();
            }
        }
        m
    }
}
