//! Every potential-based force equals minus the finite-difference gradient of its potential; the steering term
//! always points away from the obstacle.

use proptest::prelude::*;

use super::*;

#[test]
fn integer_powers_are_a_runtime_powi_to_the_bit() {
    for k in -7..=7 {
        for x in [0.01f64, 0.5, 0.7, 1.0, 3.0, 123.456] {
            let want = x.powi(std::hint::black_box(k));
            assert_eq!(int_pow(x, k).to_bits(), want.to_bits(), "{x}^{k}");
        }
    }
}

#[test]
fn pow_matches_powf() {
    for p in [-3.0, -2.0, -1.5, -1.0, -0.5, 0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 0.3, 2.7] {
        for x in [0.01, 0.5, 1.0, 3.0] {
            assert!((pow(x, p) - x.powf(p)).abs() <= 1e-14 * x.powf(p).max(1.0));
        }
    }
}
use crate::isopotential::{NestedSuperquadric, Shape, Superquadric};
use crate::obstacle::{Obstacle, WorldEval};

const H: f64 = 1e-6;

/// Central finite-difference gradient of `f` at `x`.
fn fd_gradient(f: &dyn Fn(&[f64]) -> f64, x: &[f64]) -> Vec<f64> {
    (0..x.len())
        .map(|j| {
            let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
            xp[j] += H;
            xm[j] -= H;
            (f(&xp) - f(&xm)) / (2.0 * H)
        })
        .collect()
}

fn assert_close(force: &[f64], minus_grad: &[f64]) {
    let scale = 1.0 + force.iter().map(|v| v.abs()).fold(0.0, f64::max);
    for (a, b) in force.iter().zip(minus_grad) {
        assert!((a - b).abs() <= 1e-5 * scale, "force {force:?} vs -grad {minus_grad:?}");
    }
}

fn rotation(d: usize, angle: f64) -> Vec<Vec<f64>> {
    let (c, s) = (angle.cos(), angle.sin());
    if d == 2 {
        vec![vec![c, -s], vec![s, c]]
    } else {
        // A rotation about the axis (1, 1, 1) / sqrt(3) (Rodrigues).
        let k = 1.0 / 3f64.sqrt();
        let kk = [k, k, k];
        let mut r = vec![vec![0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                let cross = match (i, j) {
                    (0, 1) => -kk[2],
                    (0, 2) => kk[1],
                    (1, 0) => kk[2],
                    (1, 2) => -kk[0],
                    (2, 0) => -kk[1],
                    (2, 1) => kk[0],
                    _ => 0.0,
                };
                r[i][j] = if i == j { c } else { 0.0 } + s * cross + (1.0 - c) * kk[i] * kk[j];
            }
        }
        r
    }
}

/// An obstacle of dimension `d` with exponents `n`, rotated by `angle`, moving with `vel`.
fn obstacle(d: usize, n: f64, angle: f64, vel: f64, nested: bool) -> Obstacle {
    let shape = if nested {
        Shape::Nested(NestedSuperquadric::new([0.3, 0.2, 0.25], n, n + 1.0).unwrap())
    } else {
        let a = [0.3, 0.2, 0.25][..d].to_vec();
        Shape::Superquadric(Superquadric::new(a, vec![n; d]).unwrap())
    };
    let center = [0.1, -0.2, 0.05][..d].to_vec();
    let v = [vel, -0.5 * vel, 0.3 * vel][..d].to_vec();
    Obstacle::new("o", shape, center, Some(rotation(d, angle)), Some(v)).unwrap()
}

/// `C(x)` with its derivatives at time `t`.
fn c_at(o: &Obstacle, x: &[f64], t: f64) -> WorldEval {
    let mut e = WorldEval::new(o.dim());
    let mut c = vec![0.0; o.dim()];
    o.center_at(t, &mut c);
    e.eval(o.shape(), o.rotation(), &c, x);
    e
}

fn vec_strategy(d: usize, r: f64) -> impl Strategy<Value = Vec<f64>> {
    proptest::collection::vec(-r..r, d)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn static_point_force_is_minus_gradient(d in 2usize..4, r in vec_strategy(3, 0.1), eta in 0.2f64..3.0) {
        let r = &r[..d];
        let p0 = 0.12;
        let p = norm(r);
        prop_assume!(p > 0.01 && p < p0 - 1e-3);
        let mut f = vec![0.0; d];
        static_point::add_force(r, eta, p0, &mut f);
        let g = fd_gradient(&|x| static_point::potential(x, eta, p0), r);
        assert_close(&f, &g.iter().map(|v| -v).collect::<Vec<_>>());
    }

    #[test]
    fn dynamic_point_force_is_minus_gradient(
        d in 2usize..4, r in vec_strategy(3, 1.0), u in vec_strategy(3, 2.0), lambda in 0.1f64..5.0, beta in 1.0f64..4.0
    ) {
        let (r, u) = (&r[..d], &u[..d]);
        prop_assume!(norm(r) > 0.05 && norm(u) > 0.05);
        let cos = dot(r, u) / (norm(r) * norm(u));
        prop_assume!(cos < -0.05);
        let mut f = vec![0.0; d];
        dynamic_point::add_force(r, u, lambda, beta, &mut f);
        let g = fd_gradient(&|x| dynamic_point::potential(x, u, lambda, beta), r);
        assert_close(&f, &g.iter().map(|v| -v).collect::<Vec<_>>());
    }

    #[test]
    fn static_volumetric_force_is_minus_gradient(
        d in 2usize..4, x in vec_strategy(3, 1.0), n in 1u32..3, angle in 0.0f64..3.0, t in 0.0f64..1.0,
        vel in -0.5f64..0.5, a in 0.5f64..20.0, eta in 0.3f64..2.5, nested in any::<bool>()
    ) {
        let nested = nested && d == 3;
        let o = obstacle(d, n as f64, angle, vel, nested);
        let x = &x[..d];
        let e = c_at(&o, x, t);
        prop_assume!(e.c > 0.05);
        let mut f = vec![0.0; d];
        static_volumetric::add_force(e.c, &e.grad, a, eta, &mut f);
        let g = fd_gradient(&|y| static_volumetric::potential(c_at(&o, y, t).c, a, eta), x);
        assert_close(&f, &g.iter().map(|v| -v).collect::<Vec<_>>());
    }

    #[test]
    fn dynamic_volumetric_force_is_minus_gradient(
        d in 2usize..4, x in vec_strategy(3, 1.0), u in vec_strategy(3, 2.0), n in 1u32..3, angle in 0.0f64..3.0,
        t in 0.0f64..1.0, vel in -0.5f64..0.5, lambda in 0.5f64..20.0, beta in 1.0f64..4.0, eta in 0.2f64..2.5,
        nested in any::<bool>()
    ) {
        let nested = nested && d == 3;
        let o = obstacle(d, n as f64, angle, vel, nested);
        let (x, u) = (&x[..d], &u[..d]);
        let e = c_at(&o, x, t);
        prop_assume!(e.c > 0.05 && norm(u) > 0.05 && norm(&e.grad) > 1e-3);
        let cos = dot(&e.grad, u) / (norm(&e.grad) * norm(u));
        prop_assume!(cos < -0.05);
        let params = DynamicVolumetric { lambda, beta, eta };
        let mut f = vec![0.0; d];
        let mut e = e;
        let hess = e.hessian(o.rotation()).to_vec();
        let hu: Vec<f64> = (0..d).map(|i| dot(&hess[i * d..(i + 1) * d], u)).collect();
        let hg: Vec<f64> = (0..d).map(|i| dot(&hess[i * d..(i + 1) * d], &e.grad)).collect();
        dynamic_volumetric::add_force(e.c, &e.grad, &hu, &hg, u, &params, &mut f);
        let g = fd_gradient(&|y| { let e = c_at(&o, y, t); dynamic_volumetric::potential(e.c, &e.grad, u, &params) }, x);
        assert_close(&f, &g.iter().map(|v| -v).collect::<Vec<_>>());
    }

    #[test]
    fn steering_angle_points_away(
        d in 2usize..4, r in vec_strategy(3, 1.0), v in vec_strategy(3, 2.0), ov in vec_strategy(3, 0.5),
        gamma in 1.0f64..50.0, beta in 0.0f64..5.0
    ) {
        let (r, v, ov) = (&r[..d], &v[..d], &ov[..d]);
        prop_assume!(norm(r) > 1e-3);
        let u: Vec<f64> = v.iter().zip(ov).map(|(a, b)| a - b).collect();
        let mut f = vec![0.0; d];
        steering_angle::add_force(r, v, &u, gamma, beta, &mut f);
        // o - x = -r: the term never has a component toward the obstacle.
        prop_assert!(dot(&f, r) >= -1e-12 * (1.0 + norm(&f) * norm(r)));
        prop_assert!(f.iter().all(|v| v.is_finite()));
        // It is orthogonal to v (a rotation by pi / 2).
        prop_assert!(dot(&f, v).abs() <= 1e-9 * (1.0 + norm(&f) * norm(v)));
    }
}

#[test]
fn steering_angle_in_2d_turns_toward_the_free_side() {
    // Obstacle ahead and slightly to the left (+y): the term must push right (-y).
    let r = [-1.0, -0.1]; // x - o: o = x + (1, 0.1)
    let v = [1.0, 0.0];
    let mut f = [0.0; 2];
    steering_angle::add_force(&r, &v, &v, 20.0, 3.0, &mut f);
    assert!(f[1] < 0.0, "{f:?}");
    // Mirrored: obstacle to the right, push left.
    let r = [-1.0, 0.1];
    let mut f = [0.0; 2];
    steering_angle::add_force(&r, &v, &v, 20.0, 3.0, &mut f);
    assert!(f[1] > 0.0, "{f:?}");
}

#[test]
fn dynamic_terms_vanish_at_rest_and_moving_away() {
    let mut f = [0.0; 2];
    dynamic_point::add_force(&[0.5, 0.0], &[0.0, 0.0], 1.0, 2.0, &mut f);
    dynamic_point::add_force(&[0.5, 0.0], &[1.0, 0.0], 1.0, 2.0, &mut f);
    let p = DynamicVolumetric { lambda: 1.0, beta: 2.0, eta: 1.0 };
    dynamic_volumetric::add_force(0.5, &[1.0, 0.0], &[0.0, 0.0], &[2.0, 0.0], &[0.0, 0.0], &p, &mut f);
    dynamic_volumetric::add_force(0.5, &[1.0, 0.0], &[2.0, 0.0], &[2.0, 0.0], &[1.0, 0.0], &p, &mut f);
    assert_eq!(f, [0.0, 0.0]);
}

#[test]
fn parameters_are_validated_with_the_field_named() {
    let m = Method::DynamicVolumetric(DynamicVolumetric { lambda: 1.0, beta: 0.5, eta: 1.0 });
    let e = m.validate("avoidance", 2).unwrap_err();
    assert_eq!(e.field, "avoidance.beta");
    let m = Method::SteeringAngle(SteeringAngle { gamma: 1.0, beta: 1.0 });
    assert_eq!(m.validate("avoidance", 4).unwrap_err().field, "avoidance.method");
    let m = Method::StaticPoint(StaticPoint { eta: f64::NAN, p0: 0.1 });
    assert_eq!(m.validate("avoidance", 2).unwrap_err().field, "avoidance.eta");
}
