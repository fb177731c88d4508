//! Dense output: the trajectory between two integration steps, so that a coarse internal step can serve a fine
//! output rate.
//!
//! Between two knots `a` (time `t0`) and `b` (time `t1 = t0 + h`) that carry position, velocity and acceleration,
//! the quintic Hermite polynomial
//!
//! `p(θ) = c0 + c1 θ + c2 θ² + c3 θ³ + c4 θ⁴ + c5 θ⁵`, `θ = (t - t0) / h`,
//!
//! with `c0 = x_a`, `c1 = h v_a`, `c2 = h² a_a / 2` and
//!
//! `c3 = 10 Δ - 4 Δv + Δa / 2`, `c4 = -15 Δ + 7 Δv - Δa`, `c5 = 6 Δ - 3 Δv + Δa / 2`,
//!
//! where `Δ = x_b - x_a - h v_a - h² a_a / 2`, `Δv = h (v_b - v_a) - h² a_a`, `Δa = h² (a_b - a_a)`, matches
//! position, velocity and acceleration at both knots. For a smooth trajectory its error is `O(h⁶)` in position
//! (`O(h⁵)` in velocity, `O(h⁴)` in acceleration), far below RK4's own `O(h⁴)` global error at the same `h`.
//!
//! The phase decays as `s(t) = s_a exp(-α (t - t0) / τ)` while `τ` is constant and stays put while holding: both
//! are the log-linear interpolation `s(θ) = s_a (s_b / s_a)^θ`, exact for either.

/// A point of the internal grid: time, phase, and position, velocity `dx/dt` and acceleration `d²x/dt²`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Knot {
    /// Time.
    pub(crate) t: f64,
    /// Phase.
    pub(crate) s: f64,
    /// Position.
    pub(crate) x: Vec<f64>,
    /// Velocity `dx/dt`.
    pub(crate) xd: Vec<f64>,
    /// Acceleration.
    pub(crate) xdd: Vec<f64>,
}

impl Knot {
    /// A knot of dimension `dim`, all zero, at time 0 and phase 1.
    pub(crate) fn zeros(dim: usize) -> Self {
        Self { t: 0.0, s: 1.0, x: vec![0.0; dim], xd: vec![0.0; dim], xdd: vec![0.0; dim] }
    }
}

/// Writes position, velocity and acceleration at time `t` (within `[a.t, b.t]`) of the quintic Hermite
/// interpolant of `a` and `b` into `x`, `xd` and `xdd`; returns the phase at `t`. At `t = a.t` (or `b.t`) the
/// knot's values are returned exactly. For many points between the same knots, [`Interpolant`] computes the
/// coefficients once.
pub(crate) fn interpolate(a: &Knot, b: &Knot, t: f64, x: &mut [f64], xd: &mut [f64], xdd: &mut [f64]) -> f64 {
    let h = b.t - a.t;
    if t == a.t || h <= 0.0 {
        return copy_knot(a, x, xd, xdd);
    }
    if t == b.t {
        return copy_knot(b, x, xd, xdd);
    }
    let inv_h = 1.0 / h;
    let th = (t - a.t) * inv_h;
    for i in 0..x.len() {
        (x[i], xd[i], xdd[i]) = evaluate(a.x[i], coefficients(a, b, i, h), th, inv_h);
    }
    phase(a, b, th, log_ratio(a, b))
}

/// The quintic Hermite interpolant of two knots with its coefficients computed once, for the many output points
/// between them: the same polynomial as [`interpolate`]. The knots' values are returned exactly at their times.
#[derive(Debug, Clone, Default)]
pub(crate) struct Interpolant {
    t0: f64,
    t1: f64,
    inv_h: f64,
    /// `ln(s_b / s_a)`, when both phases are positive (the phase is then log-linear).
    log_ratio: Option<f64>,
    /// `c1 .. c5` of each dimension (`c0` is the first knot's position).
    c: Vec<[f64; 5]>,
}

impl Interpolant {
    /// Computes the coefficients between `a` and `b` (in place: no allocation once the dimension is known).
    pub(crate) fn fit(&mut self, a: &Knot, b: &Knot) {
        let h = b.t - a.t;
        self.t0 = a.t;
        self.t1 = b.t;
        self.inv_h = if h > 0.0 { 1.0 / h } else { 0.0 };
        self.log_ratio = log_ratio(a, b);
        self.c.resize(a.x.len(), [0.0; 5]);
        for (i, c) in self.c.iter_mut().enumerate() {
            *c = coefficients(a, b, i, h);
        }
    }

    /// As [`interpolate`], for the knots `a` and `b` it was fitted to.
    pub(crate) fn eval(
        &self,
        a: &Knot,
        b: &Knot,
        t: f64,
        x: &mut [f64],
        xd: &mut [f64],
        xdd: &mut [f64],
    ) -> f64 {
        debug_assert!(a.t == self.t0 && b.t == self.t1, "fitted to other knots");
        if t == a.t || self.inv_h == 0.0 {
            return copy_knot(a, x, xd, xdd);
        }
        if t == b.t {
            return copy_knot(b, x, xd, xdd);
        }
        let th = (t - self.t0) * self.inv_h;
        for (i, c) in self.c.iter().enumerate() {
            (x[i], xd[i], xdd[i]) = evaluate(a.x[i], *c, th, self.inv_h);
        }
        phase(a, b, th, self.log_ratio)
    }
}

/// A knot's own values, and its phase.
fn copy_knot(k: &Knot, x: &mut [f64], xd: &mut [f64], xdd: &mut [f64]) -> f64 {
    x.copy_from_slice(&k.x);
    xd.copy_from_slice(&k.xd);
    xdd.copy_from_slice(&k.xdd);
    k.s
}

/// `c1 .. c5` of dimension `i` between `a` and `b`, `h = b.t - a.t` (the module's formulas).
#[inline]
fn coefficients(a: &Knot, b: &Knot, i: usize, h: f64) -> [f64; 5] {
    let h2 = h * h;
    let (xa, va, aa) = (a.x[i], a.xd[i], a.xdd[i]);
    let c1 = h * va;
    let c2 = 0.5 * h2 * aa;
    let dx = b.x[i] - xa - c1 - c2;
    let dv = h * (b.xd[i] - va) - h2 * aa;
    let da = h2 * (b.xdd[i] - aa);
    [c1, c2, 10.0 * dx - 4.0 * dv + 0.5 * da, -15.0 * dx + 7.0 * dv - da, 6.0 * dx - 3.0 * dv + 0.5 * da]
}

/// Position, velocity and acceleration at `θ` of the polynomial `x0 + c1 θ + ... + c5 θ⁵` (Horner on p, p', p'').
#[inline]
fn evaluate(x0: f64, [c1, c2, c3, c4, c5]: [f64; 5], th: f64, inv_h: f64) -> (f64, f64, f64) {
    (
        x0 + th * (c1 + th * (c2 + th * (c3 + th * (c4 + th * c5)))),
        (c1 + th * (2.0 * c2 + th * (3.0 * c3 + th * (4.0 * c4 + th * 5.0 * c5)))) * inv_h,
        (2.0 * c2 + th * (6.0 * c3 + th * (12.0 * c4 + th * 20.0 * c5))) * inv_h * inv_h,
    )
}

/// `ln(s_b / s_a)` when both phases are positive.
fn log_ratio(a: &Knot, b: &Knot) -> Option<f64> {
    (a.s > 0.0 && b.s > 0.0).then(|| (b.s / a.s).ln())
}

/// The phase at `θ`: log-linear, `s_a exp(θ ln(s_b / s_a))`, or linear when a phase is not positive.
fn phase(a: &Knot, b: &Knot, th: f64, log_ratio: Option<f64>) -> f64 {
    match log_ratio {
        Some(l) => a.s * (th * l).exp(),
        None => a.s + th * (b.s - a.s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn knot(t: f64, f: impl Fn(f64) -> [f64; 3]) -> Knot {
        let [x, v, a] = f(t);
        Knot { t, s: (-t).exp(), x: vec![x], xd: vec![v], xdd: vec![a] }
    }

    fn at(a: &Knot, b: &Knot, t: f64) -> ([f64; 3], f64) {
        let (mut x, mut v, mut acc) = ([0.0], [0.0], [0.0]);
        let s = interpolate(a, b, t, &mut x, &mut v, &mut acc);
        ([x[0], v[0], acc[0]], s)
    }

    #[test]
    fn quintics_are_reproduced_exactly() {
        let p = |t: f64| {
            [
                1.0 - 2.0 * t + 0.5 * t * t + 3.0 * t.powi(3) - t.powi(4) + 0.7 * t.powi(5),
                -2.0 + t + 9.0 * t * t - 4.0 * t.powi(3) + 3.5 * t.powi(4),
                1.0 + 18.0 * t - 12.0 * t * t + 14.0 * t.powi(3),
            ]
        };
        let (a, b) = (knot(0.3, p), knot(1.1, p));
        for k in 0..=16 {
            let t = 0.3 + 0.8 * k as f64 / 16.0;
            let (got, s) = at(&a, &b, t);
            let want = p(t);
            for i in 0..3 {
                assert!((got[i] - want[i]).abs() < 1e-12 * (1.0 + want[i].abs()), "t {t} i {i}");
            }
            assert!((s - (-t).exp()).abs() < 1e-14, "the phase is log-linear");
        }
    }

    #[test]
    fn the_fitted_interpolant_is_the_same_polynomial() {
        let f = |t: f64| [(3.0 * t).sin(), 3.0 * (3.0 * t).cos(), -9.0 * (3.0 * t).sin()];
        let (a, b) = (knot(0.2, f), knot(0.27, f));
        let mut fitted = Interpolant::default();
        fitted.fit(&a, &b);
        for k in 0..=7 {
            let t = if k == 7 { b.t } else { 0.2 + 0.01 * k as f64 };
            let (mut x, mut v, mut acc) = ([0.0], [0.0], [0.0]);
            let s = fitted.eval(&a, &b, t, &mut x, &mut v, &mut acc);
            assert_eq!(([x[0], v[0], acc[0]], s), at(&a, &b, t), "t {t}: the same values to the bit");
        }
    }

    #[test]
    fn knots_are_returned_exactly() {
        let f = |t: f64| [t.sin(), t.cos(), -t.sin()];
        let (a, b) = (knot(0.0, f), knot(0.25, f));
        assert_eq!(at(&a, &b, 0.0).0, [a.x[0], a.xd[0], a.xdd[0]]);
        assert_eq!(at(&a, &b, 0.25).0, [b.x[0], b.xd[0], b.xdd[0]]);
    }

    /// Halving h divides the largest position error by about 2⁶ = 64 (velocity 2⁵, acceleration 2⁴).
    #[test]
    fn the_error_is_sixth_order() {
        let f = |t: f64| [(3.0 * t).sin(), 3.0 * (3.0 * t).cos(), -9.0 * (3.0 * t).sin()];
        let err = |h: f64| {
            let mut e = [0.0f64; 3];
            let (a, b) = (knot(0.2, f), knot(0.2 + h, f));
            for k in 1..100 {
                let t = 0.2 + h * k as f64 / 100.0;
                let (got, _) = at(&a, &b, t);
                let want = f(t);
                for i in 0..3 {
                    e[i] = e[i].max((got[i] - want[i]).abs());
                }
            }
            e
        };
        let (e1, e2) = (err(0.1), err(0.05));
        let ratios: Vec<f64> = (0..3).map(|i| (e1[i] / e2[i]).log2()).collect();
        assert!((ratios[0] - 6.0).abs() < 0.3, "{ratios:?}");
        assert!((ratios[1] - 5.0).abs() < 0.3, "{ratios:?}");
        assert!((ratios[2] - 4.0).abs() < 0.3, "{ratios:?}");
    }
}
