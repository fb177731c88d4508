//! The Gaussian basis of the forcing term.

use crate::error::{InvalidInput, Result};

/// Relative cut-off of the Gaussians: a basis function whose exponent lies more than this below the largest one
/// contributes less than `exp(-CUTOFF)` (about 1e-17, below the rounding of a double) of the sum and is not
/// evaluated.
const CUTOFF: f64 = 39.0;

/// `N + 1` Gaussians over the phase (paper, `eq:gaussian_bf`, `eq:gbf_center`, `eq:bgf_width`).
///
/// # Formula
/// `psi_i(s) = exp(-h_i (s - c_i)^2)`, `c_i = exp(-alpha * i / N)`, `h_i = 1 / (c_{i+1} - c_i)^2` for
/// `i < N` and `h_N = h_{N-1}`. The centres are the paper's with `T = tau` (ERRATA.md): the basis spans the phase of
/// exactly one demonstration, whatever its duration.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct GaussianBasis {
    centers: Vec<f64>,
    widths: Vec<f64>,
}

impl GaussianBasis {
    /// The basis for the paper's `N` (so `N + 1` functions) and the canonical decay `alpha`.
    pub(crate) fn new(n: usize, alpha: f64) -> Result<Self> {
        if n < 1 {
            return Err(InvalidInput::new("N", "must be at least 1 (the basis has N + 1 functions)").into());
        }
        // A decay outside the range makes neighbouring centres coincide (a width of 1 / 0) or underflow.
        crate::ranges::check_range("alpha", alpha, &crate::ranges::ALPHA, "")?;
        let centers: Vec<f64> = (0..=n).map(|i| (-alpha * i as f64 / n as f64).exp()).collect();
        let mut widths: Vec<f64> = centers.windows(2).map(|c| 1.0 / (c[1] - c[0]).powi(2)).collect();
        widths.push(widths[n - 1]);
        Ok(Self { centers, widths })
    }

    /// Number of functions, `N + 1`.
    pub(crate) fn len(&self) -> usize {
        self.centers.len()
    }

    /// The centres `c_i`.
    #[cfg(test)]
    pub(crate) fn centers(&self) -> &[f64] {
        &self.centers
    }

    /// The widths `h_i`.
    #[cfg(test)]
    pub(crate) fn widths(&self) -> &[f64] {
        &self.widths
    }

    /// Normalised activations `psi_i(s) / sum_j psi_j(s)` written into `out` (length `N + 1`); returns the range
    /// of indices that are not negligible. Computed with the largest exponent factored out, so the sum never
    /// underflows even for a phase far below the last centre.
    pub(crate) fn normalized(&self, s: f64, out: &mut [f64]) -> std::ops::Range<usize> {
        let mut max = f64::NEG_INFINITY;
        for ((o, &c), &h) in out.iter_mut().zip(&self.centers).zip(&self.widths) {
            let e = -h * (s - c) * (s - c);
            *o = e;
            max = max.max(e);
        }
        let (mut lo, mut hi, mut sum) = (usize::MAX, 0, 0.0);
        for (i, o) in out.iter_mut().enumerate() {
            if *o > max - CUTOFF {
                *o = (*o - max).exp();
                sum += *o;
                lo = lo.min(i);
                hi = i + 1;
            } else {
                *o = 0.0;
            }
        }
        if lo > hi {
            // Not a single finite activation (a phase that is not finite): nothing is active.
            return 0..0;
        }
        for o in &mut out[lo..hi] {
            *o /= sum;
        }
        lo..hi
    }
}

/// The learned forcing term of all `d` dimensions (paper, `eq:forcing_term`).
///
/// # Formula
/// `f_p(s) = s * sum_i w_{p,i} psi_i(s) / sum_i psi_i(s)`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ForcingTerm {
    basis: GaussianBasis,
    /// Row-major `d x (N + 1)`.
    weights: Vec<f64>,
    dim: usize,
    /// Every weight is zero (a straight-line primitive): `f = 0` without evaluating the basis.
    null: bool,
    scratch: Vec<f64>,
}

impl ForcingTerm {
    /// Builds the term from its basis and the weights of each dimension (`weights[p][i]`).
    pub(crate) fn new(basis: GaussianBasis, weights: &[Vec<f64>]) -> Self {
        let n1 = basis.len();
        let flat = weights.iter().flat_map(|row| row.iter().copied()).collect::<Vec<_>>();
        debug_assert_eq!(flat.len(), weights.len() * n1);
        let null = flat.iter().all(|w| *w == 0.0);
        Self { scratch: vec![0.0; n1], basis, weights: flat, dim: weights.len(), null }
    }

    /// Writes `f(s)` into `out` (length `d`).
    pub(crate) fn eval(&mut self, s: f64, out: &mut [f64]) {
        if self.null {
            // The sum below is of zeros: the same result, without the N + 1 exponentials.
            out[..self.dim].fill(0.0);
            return;
        }
        let n1 = self.basis.len();
        let range = self.basis.normalized(s, &mut self.scratch);
        for (p, o) in out.iter_mut().enumerate().take(self.dim) {
            let row = &self.weights[p * n1..(p + 1) * n1];
            let acc: f64 =
                row[range.clone()].iter().zip(&self.scratch[range.clone()]).map(|(w, a)| w * a).sum();
            *o = s * acc;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centres_and_widths_follow_the_paper() {
        let b = GaussianBasis::new(4, 2.0).unwrap();
        assert_eq!(b.len(), 5);
        assert!((b.centers()[0] - 1.0).abs() < 1e-15);
        assert!((b.centers()[4] - (-2.0f64).exp()).abs() < 1e-15);
        let h0 = 1.0 / (b.centers()[1] - b.centers()[0]).powi(2);
        assert!((b.widths()[0] - h0).abs() < 1e-9);
        assert_eq!(b.widths()[4], b.widths()[3]);
    }

    #[test]
    fn normalised_activations_sum_to_one_even_for_tiny_phases() {
        let b = GaussianBasis::new(50, 4.0).unwrap();
        let mut out = vec![0.0; b.len()];
        for s in [1.0, 0.5, 0.02, 1e-6, 1e-30, 0.0] {
            let r = b.normalized(s, &mut out);
            let sum: f64 = out[r].iter().sum();
            assert!((sum - 1.0).abs() < 1e-12, "s = {s}: sum {sum}");
            assert!(out.iter().all(|v| v.is_finite()));
        }
    }

    #[test]
    fn bad_parameters_are_refused() {
        assert!(GaussianBasis::new(0, 4.0).is_err());
        assert!(GaussianBasis::new(5, 0.0).is_err());
        assert!(GaussianBasis::new(5, f64::NAN).is_err());
    }
}
