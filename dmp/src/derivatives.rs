//! Second-order finite differences on a non-uniform grid.

/// First derivative of `f` sampled at increasing times `t` (at least 3 samples), second-order accurate: the
/// three-point non-uniform central formula inside, one-sided three-point formulas at both ends (as numpy's
/// `gradient(f, t, edge_order=2)`).
///
/// # Formula
/// Inside, with `h1 = t_i - t_{i-1}`, `h2 = t_{i+1} - t_i`:
/// `f'_i = -h2 / (h1 (h1 + h2)) f_{i-1} + (h2 - h1) / (h1 h2) f_i + h1 / (h2 (h1 + h2)) f_{i+1}`.
pub(crate) fn gradient(f: &[f64], t: &[f64]) -> Vec<f64> {
    let n = f.len();
    assert!(n >= 3 && t.len() == n, "gradient needs at least 3 samples");
    let mut out = vec![0.0; n];
    for i in 1..n - 1 {
        let (h1, h2) = (t[i] - t[i - 1], t[i + 1] - t[i]);
        out[i] = -h2 / (h1 * (h1 + h2)) * f[i - 1]
            + (h2 - h1) / (h1 * h2) * f[i]
            + h1 / (h2 * (h1 + h2)) * f[i + 1];
    }
    let (h1, h2) = (t[1] - t[0], t[2] - t[1]);
    out[0] = -(2.0 * h1 + h2) / (h1 * (h1 + h2)) * f[0] + (h1 + h2) / (h1 * h2) * f[1]
        - h1 / (h2 * (h1 + h2)) * f[2];
    let (h1, h2) = (t[n - 2] - t[n - 3], t[n - 1] - t[n - 2]);
    out[n - 1] = h2 / (h1 * (h1 + h2)) * f[n - 3] - (h1 + h2) / (h1 * h2) * f[n - 2]
        + (2.0 * h2 + h1) / (h2 * (h1 + h2)) * f[n - 1];
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_for_quadratics_on_a_non_uniform_grid() {
        let t: Vec<f64> = (0..20).map(|i| (i as f64).powf(1.3) * 0.01).collect();
        let f: Vec<f64> = t.iter().map(|t| 3.0 * t * t - 2.0 * t + 1.0).collect();
        let g = gradient(&f, &t);
        for (gi, ti) in g.iter().zip(&t) {
            assert!((gi - (6.0 * ti - 2.0)).abs() < 1e-9, "{gi} at {ti}");
        }
    }

    #[test]
    fn error_falls_by_four_when_the_step_halves() {
        let err = |n: usize| {
            let t: Vec<f64> = (0..=n).map(|i| i as f64 / n as f64).collect();
            let f: Vec<f64> = t.iter().map(|t| t.sin()).collect();
            gradient(&f, &t).iter().zip(&t).map(|(g, t)| (g - t.cos()).abs()).fold(0.0, f64::max)
        };
        let ratio = err(50) / err(100);
        assert!((3.5..4.5).contains(&ratio), "ratio {ratio}");
    }
}
