//! Hoffmann's steering angle (paper, `eq:perturb_steering_angle`), in 2-D and 3-D.

use super::{dot, norm};

/// Adds the steering term to `out`.
///
/// # Formula
/// `phi = gamma R v vartheta exp(-beta vartheta)` when `vartheta < pi / 2`, where `vartheta` is the angle between
/// `o - x = -r` and the relative velocity `u`, and `R` the rotation by `+pi/2` about `(o - x) x v` (ERRATA.md,
/// term 3). For `v` orthogonal to that axis, `R v = (a x v) / |a|`, which always points away from the obstacle.
/// In 2-D the axis is `+z` or `-z` by the sign of the z-component of `(o - x) x v`: the rotation is counter-
/// clockwise or clockwise accordingly. When the axis vanishes (heading straight at the point) nothing is added.
/// Dimensions other than 2 and 3 are refused by validation and add nothing here.
pub(crate) fn add_force(r: &[f64], v: &[f64], u: &[f64], gamma: f64, beta: f64, out: &mut [f64]) {
    let (p, un) = (norm(r), norm(u));
    if p == 0.0 || un == 0.0 {
        return;
    }
    let cos = (-dot(r, u) / (p * un)).clamp(-1.0, 1.0);
    if cos <= 0.0 {
        return;
    }
    let theta = cos.acos();
    let k = gamma * theta * (-beta * theta).exp();
    match r.len() {
        2 => {
            // (o - x) x v, z-component, with o - x = -r.
            let z = -r[0] * v[1] + r[1] * v[0];
            if z > 0.0 {
                out[0] += -k * v[1];
                out[1] += k * v[0];
            } else if z < 0.0 {
                out[0] += k * v[1];
                out[1] += -k * v[0];
            }
        }
        3 => {
            let w = [-r[0], -r[1], -r[2]];
            let a = [w[1] * v[2] - w[2] * v[1], w[2] * v[0] - w[0] * v[2], w[0] * v[1] - w[1] * v[0]];
            let an = norm(&a);
            if an == 0.0 {
                return;
            }
            // R v for v orthogonal to the unit axis: (a / |a|) x v.
            let rv = [a[1] * v[2] - a[2] * v[1], a[2] * v[0] - a[0] * v[2], a[0] * v[1] - a[1] * v[0]];
            for i in 0..3 {
                out[i] += k * rv[i] / an;
            }
        }
        _ => {}
    }
}
