//! Fitting an ellipse to a 2-D point cloud, as the paper's perception pipeline does for an unknown object
//! (superquadric exponents `n = m = 1`).
//!
//! # Formula
//! PCA-aligned bounding ellipse: with `m` the mean of the points and `C` their covariance, the axes are the
//! eigenvectors of `C`, at angle `theta = atan2(2 C_xy, C_xx - C_yy) / 2` from `x`. In that frame the points span
//! the rectangle `[u_min, u_max] x [w_min, w_max]`, of centre `c` and half-sides `(h_u, h_w)`; the smallest ellipse
//! with those axes that contains the rectangle passes through its corners, with semi-axes `sqrt(2) (h_u, h_w)`
//! (among ellipses `(u/a)^2 + (w/b)^2 <= 1` through `(h_u, h_w)`, the area `pi a b` is least at `a = sqrt(2) h_u`).
//! The robot's size is then added to both semi-axes (the ellipse of semi-axes `a + r, b + r` contains every point
//! within `r` of the ellipse `a, b`), which the server does with the obstacle's `margin`.

/// A fitted ellipse.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Ellipse {
    /// Centre.
    pub(crate) center: [f64; 2],
    /// Semi-axes along the two axes (before any margin).
    pub(crate) semi_axes: [f64; 2],
    /// Angle of the first axis from `x`, radians.
    pub(crate) angle: f64,
}

/// Smallest half-side of the bounding rectangle, metres (a cloud on a line still gives an ellipse).
pub(crate) const MIN_HALF_SIDE: f64 = 1e-3;

impl Ellipse {
    /// The PCA-aligned bounding ellipse of `points` (at least one).
    pub(crate) fn fit(points: &[[f64; 2]]) -> Option<Self> {
        if points.is_empty() {
            return None;
        }
        let n = points.len() as f64;
        let mx = points.iter().map(|p| p[0]).sum::<f64>() / n;
        let my = points.iter().map(|p| p[1]).sum::<f64>() / n;
        let (mut cxx, mut cyy, mut cxy) = (0.0, 0.0, 0.0);
        for p in points {
            let (dx, dy) = (p[0] - mx, p[1] - my);
            cxx += dx * dx;
            cyy += dy * dy;
            cxy += dx * dy;
        }
        let angle = 0.5 * (2.0 * cxy).atan2(cxx - cyy);
        let (c, s) = (angle.cos(), angle.sin());
        let (mut umin, mut umax, mut wmin, mut wmax) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for p in points {
            let (dx, dy) = (p[0] - mx, p[1] - my);
            let (u, w) = (c * dx + s * dy, -s * dx + c * dy);
            umin = umin.min(u);
            umax = umax.max(u);
            wmin = wmin.min(w);
            wmax = wmax.max(w);
        }
        let (cu, cw) = (0.5 * (umin + umax), 0.5 * (wmin + wmax));
        let hu = (0.5 * (umax - umin)).max(MIN_HALF_SIDE);
        let hw = (0.5 * (wmax - wmin)).max(MIN_HALF_SIDE);
        let center = [mx + c * cu - s * cw, my + s * cu + c * cw];
        let r2 = std::f64::consts::SQRT_2;
        let e = Self { center, semi_axes: [r2 * hu, r2 * hw], angle };
        e.is_finite().then_some(e)
    }

    fn is_finite(&self) -> bool {
        self.center.iter().chain(&self.semi_axes).all(|v| v.is_finite()) && self.angle.is_finite()
    }

    /// The rotation `R` (rows; its columns are the axes).
    pub(crate) fn rotation(&self) -> Vec<Vec<f64>> {
        let (c, s) = (self.angle.cos(), self.angle.sin());
        vec![vec![c, -s], vec![s, c]]
    }

    /// `(x/a)^2 + (y/b)^2 - 1` in the ellipse's frame, inflated by `margin`: negative inside.
    #[cfg(test)]
    pub(crate) fn value(&self, p: [f64; 2], margin: f64) -> f64 {
        let (c, s) = (self.angle.cos(), self.angle.sin());
        let (dx, dy) = (p[0] - self.center[0], p[1] - self.center[1]);
        let (u, w) = (c * dx + s * dy, -s * dx + c * dy);
        (u / (self.semi_axes[0] + margin)).powi(2) + (w / (self.semi_axes[1] + margin)).powi(2) - 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rotated_rectangle_is_inside_its_ellipse() {
        let (a, b, th) = (0.3, 0.1, 0.4_f64);
        let (c, s) = (th.cos(), th.sin());
        let mut pts = Vec::new();
        for i in 0..=40 {
            let f = i as f64 / 40.0 * 2.0 - 1.0;
            for (u, w) in [(f * a, b), (f * a, -b), (a, f * b), (-a, f * b)] {
                pts.push([1.0 + c * u - s * w, 2.0 + s * u + c * w]);
            }
        }
        let e = Ellipse::fit(&pts).unwrap();
        assert!((e.center[0] - 1.0).abs() < 1e-9 && (e.center[1] - 2.0).abs() < 1e-9, "{e:?}");
        assert!((e.semi_axes[0] - a * 2f64.sqrt()).abs() < 1e-9, "{e:?}");
        assert!((e.semi_axes[1] - b * 2f64.sqrt()).abs() < 1e-9, "{e:?}");
        for p in &pts {
            assert!(e.value(*p, 0.0) <= 1e-9);
        }
        // A point 0.2 outside a side is inside the ellipse inflated by 0.2.
        assert!(e.value([1.0 - s * (b + 0.2), 2.0 + c * (b + 0.2)], 0.2) <= 0.0);
    }
}
