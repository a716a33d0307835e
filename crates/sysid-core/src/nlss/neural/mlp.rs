//! A small multilayer perceptron (tanh hidden layers, linear output, optional linear skip
//! `W_s input`) over a flat parameter slice, with its backward pass.

/// Layer widths `[input, hidden..., output]` and whether a linear skip term is added.
///
/// ```
/// use sysid_core::nlss::neural::Mlp;
/// let net = Mlp::new(vec![2, 3, 1], true);
/// assert_eq!(net.n_params(), 2 + (2 * 3 + 3) + (3 + 1));
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Mlp {
    sizes: Vec<usize>,
    skip: bool,
}

impl Mlp {
    /// A network with the given widths (at least input and output).
    pub fn new(sizes: Vec<usize>, skip: bool) -> Self {
        Mlp { sizes, skip }
    }

    /// Input width.
    pub fn n_in(&self) -> usize {
        self.sizes[0]
    }

    /// Output width.
    pub fn n_out(&self) -> usize {
        *self.sizes.last().unwrap()
    }

    /// Number of parameters: skip `out x in`, then per layer weights `out x in` and biases.
    pub fn n_params(&self) -> usize {
        let s = if self.skip {
            self.n_in() * self.n_out()
        } else {
            0
        };
        s + self
            .sizes
            .windows(2)
            .map(|w| w[0] * w[1] + w[1])
            .sum::<usize>()
    }

    /// Activations needed by [`Mlp::backward`]: the input and every layer's output.
    pub fn n_acts(&self) -> usize {
        self.sizes.iter().sum()
    }

    /// Forward pass: `acts` (length [`Mlp::n_acts`]) gets the input and layer outputs;
    /// returns the offset of the output in `acts`.
    pub fn forward(&self, p: &[f64], input: &[f64], acts: &mut [f64]) -> usize {
        let nl = self.sizes.len() - 1;
        acts[..self.n_in()].copy_from_slice(input);
        let mut po = if self.skip {
            self.n_in() * self.n_out()
        } else {
            0
        };
        let mut ai = 0;
        for k in 0..nl {
            let (ni, no) = (self.sizes[k], self.sizes[k + 1]);
            let ao = ai + ni;
            let (head, tail) = acts.split_at_mut(ao);
            let x = &head[ai..ao];
            for j in 0..no {
                let w = &p[po + j * ni..po + (j + 1) * ni];
                let mut v = p[po + ni * no + j];
                for i in 0..ni {
                    v += w[i] * x[i];
                }
                tail[j] = if k + 1 < nl { v.tanh() } else { v };
            }
            po += ni * no + no;
            ai = ao;
        }
        if self.skip {
            let (ni, no) = (self.n_in(), self.n_out());
            for j in 0..no {
                let mut v = 0.0;
                for i in 0..ni {
                    v += p[j * ni + i] * acts[i];
                }
                acts[ai + j] += v;
            }
        }
        ai
    }

    /// Backward pass from `grad_out` (dL/doutput) with the activations of the forward pass:
    /// adds dL/dparams into `gp` and dL/dinput into `gin` (`scratch` at least twice the
    /// widest layer).
    pub fn backward(
        &self,
        p: &[f64],
        acts: &[f64],
        grad_out: &[f64],
        gp: &mut [f64],
        gin: &mut [f64],
        scratch: &mut [f64],
    ) {
        let nl = self.sizes.len() - 1;
        let wmax = *self.sizes.iter().max().unwrap();
        let (d, dprev) = scratch.split_at_mut(wmax);
        let no = self.n_out();
        d[..no].copy_from_slice(grad_out);
        let ni0 = self.n_in();
        if self.skip {
            for j in 0..no {
                for i in 0..ni0 {
                    gp[j * ni0 + i] += grad_out[j] * acts[i];
                    gin[i] += p[j * ni0 + i] * grad_out[j];
                }
            }
        }
        // offsets of each layer's parameters and activations
        let mut pofs = Vec::with_capacity(nl);
        let mut aofs = Vec::with_capacity(nl + 1);
        let mut po = if self.skip { ni0 * no } else { 0 };
        let mut ai = 0;
        for k in 0..nl {
            pofs.push(po);
            aofs.push(ai);
            po += self.sizes[k] * self.sizes[k + 1] + self.sizes[k + 1];
            ai += self.sizes[k];
        }
        aofs.push(ai);
        for k in (0..nl).rev() {
            let (ni, no) = (self.sizes[k], self.sizes[k + 1]);
            let po = pofs[k];
            let x = &acts[aofs[k]..aofs[k] + ni];
            if k + 1 < nl {
                // through tanh: d(out)/d(pre) = 1 - out^2
                let out = &acts[aofs[k + 1]..aofs[k + 1] + no];
                for j in 0..no {
                    d[j] *= 1.0 - out[j] * out[j];
                }
            }
            dprev[..ni].iter_mut().for_each(|v| *v = 0.0);
            for j in 0..no {
                let dj = d[j];
                if dj == 0.0 {
                    continue;
                }
                gp[po + ni * no + j] += dj;
                let w = &p[po + j * ni..po + (j + 1) * ni];
                let g = &mut gp[po + j * ni..po + (j + 1) * ni];
                for i in 0..ni {
                    g[i] += dj * x[i];
                    dprev[i] += w[i] * dj;
                }
            }
            d[..ni].copy_from_slice(&dprev[..ni]);
        }
        for i in 0..ni0 {
            gin[i] += d[i];
        }
    }
}
