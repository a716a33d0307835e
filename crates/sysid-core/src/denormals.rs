//! Subnormal operands read as zero while a per-sample kernel runs.
//!
//! The sensitivity recursions of the prediction-error and nonlinear state-space fits multiply
//! small matrices (a state by parameter block by the state-slope matrix) once per sample,
//! through faer's matrix product. On x86-64 that product packs a tall-thin left factor into a
//! microkernel tile whose unused rows keep whatever an earlier product left in the thread's
//! packing buffer; the results of those rows are never stored, but when a stale value is
//! subnormal every multiply that reads it takes a microcode assist (about a hundred cycles on
//! Intel cores). Which stale values sit there depends on what ran before on the thread, so the
//! same pass took 2 to 6 times as long from one call to the next (a `pem` structured pass 1.2
//! against 0.24 s), with bit-identical results.
//!
//! [`DenormalsAreZero`] sets the processor's denormals-are-zero mode (MXCSR bit 6) for as long
//! as it lives and restores the caller's mode when dropped (also on unwinding). It changes
//! only operands below `f64::MIN_POSITIVE` (2.2e-308), read as zero of the same sign;
//! results are not flushed. On other targets it does nothing.
//!
//! Use it only around kernels made of products and sums (a simulation pass with its
//! sensitivities), never around a whole algorithm: decompositions scale by the smallest
//! normal number and rely on gradual underflow. Set around the whole optimiser, it moved
//! `pem` on a synthetic 2 x 28 record from its modal to its slower structured
//! parameterisation (6 times the time; final cost equal to 12 digits).
//!
//! ```
//! use sysid_core::denormals::DenormalsAreZero;
//!
//! let tiny = std::hint::black_box(f64::MIN_POSITIVE / 4.0); // a subnormal
//! {
//!     let _daz = DenormalsAreZero::new();
//!     let product = std::hint::black_box(tiny) * 1.0;
//!     #[cfg(target_arch = "x86_64")]
//!     assert_eq!(product, 0.0); // read as zero inside the guard
//!     # let _ = product;
//! }
//! assert_eq!(std::hint::black_box(tiny) * 1.0, tiny); // the caller's mode is back
//! ```

/// Denormals-are-zero mode for the current thread while the guard lives.
#[must_use = "the mode is restored when the guard is dropped"]
pub struct DenormalsAreZero {
    #[cfg(target_arch = "x86_64")]
    saved: u32,
}

#[cfg(target_arch = "x86_64")]
const DAZ: u32 = 1 << 6;

impl DenormalsAreZero {
    /// Sets denormals-are-zero on this thread; the mode it replaces comes back on drop.
    pub fn new() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            let saved = read_csr();
            if saved & DAZ == 0 {
                write_csr(saved | DAZ);
            }
            DenormalsAreZero { saved }
        }
        #[cfg(not(target_arch = "x86_64"))]
        DenormalsAreZero {}
    }
}

impl Default for DenormalsAreZero {
    fn default() -> Self {
        Self::new()
    }
}

impl Drop for DenormalsAreZero {
    fn drop(&mut self) {
        #[cfg(target_arch = "x86_64")]
        if self.saved & DAZ == 0 {
            write_csr(read_csr() & !DAZ);
        }
    }
}

#[cfg(target_arch = "x86_64")]
fn read_csr() -> u32 {
    let mut csr: u32 = 0;
    // SAFETY: stmxcsr stores the 32-bit control/status register to a valid, aligned u32
    unsafe {
        std::arch::asm!(
            "stmxcsr [{}]",
            in(reg) &mut csr as *mut u32,
            options(nostack, preserves_flags)
        );
    }
    csr
}

#[cfg(target_arch = "x86_64")]
fn write_csr(csr: u32) {
    // SAFETY: ldmxcsr loads a value read by stmxcsr with only the DAZ bit changed, which the
    // architecture defines on every x86-64 processor (SSE2 and later)
    unsafe {
        std::arch::asm!(
            "ldmxcsr [{}]",
            in(reg) &csr as *const u32,
            options(nostack, preserves_flags, readonly)
        );
    }
}

#[cfg(test)]
mod tests {
    use super::DenormalsAreZero;
    use std::hint::black_box;

    #[test]
    fn subnormal_operands_read_as_zero_only_inside_the_guard() {
        let tiny = black_box(f64::MIN_POSITIVE / 8.0);
        assert!(tiny > 0.0 && !tiny.is_normal());
        {
            let _outer = DenormalsAreZero::new();
            {
                let _inner = DenormalsAreZero::new(); // nested: the outer mode is kept
            }
            let inside = black_box(tiny) + black_box(0.0);
            if cfg!(target_arch = "x86_64") {
                assert_eq!(inside, 0.0);
            }
        }
        // results are not flushed and the caller's mode is back after the guard
        assert_eq!(black_box(tiny) + black_box(0.0), tiny);
        assert_eq!(black_box(f64::MIN_POSITIVE) / 8.0, tiny);
    }
}
