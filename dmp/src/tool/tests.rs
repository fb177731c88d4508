//! The tool's field against finite differences: force and moment of the static methods are minus the derivatives
//! of the summed potential, each point's velocity is the derivative of its place; every method stays finite.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use proptest::prelude::*;

use super::*;
use crate::avoidance::{
    Avoidance, DynamicPoint, DynamicVolumetric, Method, StaticPoint, StaticVolumetric, SteeringAngle,
    static_point, static_volumetric,
};
use crate::field::{Agent, Scene};
use crate::integrate::Perturbation;
use crate::isopotential::{NestedSuperquadric, Shape, Superquadric};
use crate::obstacle::{Obstacle, WorldEval};
use crate::orientation::jacobian::exp_jacobian;
use crate::orientation::quaternion::{exp, log};

const H: f64 = 1e-6;
const SAMPLES: usize = 40;

fn bar(sampling: ControlPoints) -> Tool {
    let shape = Superquadric::new(vec![0.3, 0.02, 0.02], vec![2.0, 2.0, 2.0]).unwrap();
    Tool::new(Shape::Superquadric(shape), [0.0, 0.0, 0.0], sampling).unwrap()
}

fn tray() -> Tool {
    let shape = Superquadric::new(vec![0.15, 0.1, 0.02], vec![2.0, 2.0, 1.0]).unwrap();
    Tool::new(Shape::Superquadric(shape), [0.05, 0.0, 0.1], ControlPoints::Surface { count: 24 }).unwrap()
}

fn q_ref() -> UnitQuaternion<f64> {
    exp(&Vector3::new(0.3, -0.5, 0.9))
}

/// Two obstacles: a rotated rounded box moving slowly and a still ellipsoid.
fn obstacles() -> Vec<Obstacle> {
    let a = 0.6f64;
    let rot = vec![vec![a.cos(), -a.sin(), 0.0], vec![a.sin(), a.cos(), 0.0], vec![0.0, 0.0, 1.0]];
    vec![
        Obstacle::new(
            "box",
            Shape::Superquadric(Superquadric::new(vec![0.12, 0.08, 0.1], vec![2.0, 2.0, 1.0]).unwrap()),
            vec![0.4, 0.1, 0.0],
            Some(rot),
            Some(vec![0.1, -0.05, 0.02]),
        )
        .unwrap(),
        Obstacle::new(
            "ball",
            Shape::Nested(NestedSuperquadric::new([0.1, 0.07, 0.09], 1.0, 2.0).unwrap()),
            vec![-0.3, 0.2, 0.1],
            None,
            None,
        )
        .unwrap(),
    ]
}

/// `U(c)` of a static method at time `t`, summed over the obstacles (`None` where a point is too near for the
/// finite differences).
fn potential(method: &Method, obstacles: &[Obstacle], t: f64, c: &Vector3<f64>) -> Option<f64> {
    let mut u = 0.0;
    for o in obstacles {
        let mut center = vec![0.0; 3];
        o.center_at(t, &mut center);
        match method {
            Method::StaticPoint(p) => {
                for off in o.boundary_offsets(SAMPLES).chunks_exact(3) {
                    let r: Vec<f64> = (0..3).map(|i| c[i] - center[i] - off[i]).collect();
                    let d = r.iter().map(|v| v * v).sum::<f64>().sqrt();
                    if d < 0.02 || (d - p.p0).abs() < 1e-4 {
                        return None;
                    }
                    u += static_point::potential(&r, p.eta, p.p0);
                }
            }
            Method::StaticVolumetric(p) => {
                let cv = WorldEval::new(3).value(o.shape(), o.rotation(), &center, c.as_slice());
                if cv < 0.05 {
                    return None;
                }
                u += static_volumetric::potential(cv, p.a, p.eta);
            }
            _ => unreachable!("static methods only"),
        }
    }
    Some(u)
}

/// `sum_i U(p + R(q) r_i)`.
fn tool_potential(
    method: &Method,
    tool: &Tool,
    t: f64,
    p: &Vector3<f64>,
    q: &UnitQuaternion<f64>,
) -> Option<f64> {
    let r = q.to_rotation_matrix();
    tool.control_points().iter().map(|ri| potential(method, &obstacles(), t, &(p + r * ri))).sum()
}

fn field(tool: Tool, method: Method) -> ToolField {
    ToolField::new(tool, Scene::with_obstacles(obstacles(), Avoidance::new(method), SAMPLES), q_ref())
        .unwrap()
}

fn state(p: &Vector3<f64>, q: &UnitQuaternion<f64>) -> Vec<f64> {
    let y = log(&(q * q_ref().conjugate()));
    p.iter().chain(y.iter()).copied().collect()
}

fn assert_close(what: &str, got: &Vector3<f64>, want: &Vector3<f64>) {
    let scale = 1.0 + got.amax().max(want.amax());
    assert!((got - want).amax() <= 2e-5 * scale, "{what}: {got:?} vs finite differences {want:?}");
}

fn static_method(pick: bool, gain: f64) -> Method {
    if pick {
        Method::StaticPoint(StaticPoint { eta: gain, p0: 0.3 })
    } else {
        Method::StaticVolumetric(StaticVolumetric { a: gain, eta: 1.0 })
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, max_global_rejects: 4096, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn static_force_and_moment_are_minus_the_derivatives_of_the_summed_potential(
        p in proptest::array::uniform3(-0.35f64..0.35), y in proptest::array::uniform3(-2.0f64..2.0),
        t in 0.0f64..1.0, point in any::<bool>(), axis in any::<bool>(), gain in 0.1f64..5.0
    ) {
        let method = static_method(point, gain);
        let tool = if axis { bar(ControlPoints::Axis { count: 9 }) } else { tray() };
        // Between the two obstacles, where both act.
        let p = Vector3::from(p) + Vector3::new(0.05, 0.15, 0.05);
        let q = exp(&Vector3::from(y)) * q_ref();
        prop_assume!(tool_potential(&method, &tool, t, &p, &q).is_some());
        let mut f = field(tool.clone(), method);
        let w = f.wrench(t, &state(&p, &q), &[0.0; 6], 1.0);
        prop_assume!(w.force.norm() > 1e-6);
        let (mut dp, mut dq) = (Vector3::zeros(), Vector3::zeros());
        for k in 0..3 {
            let e = Vector3::ith(k, H);
            let u = |p: Vector3<f64>, q: UnitQuaternion<f64>| tool_potential(&method, &tool, t, &p, &q);
            let (Some(a), Some(b)) = (u(p + e, q), u(p - e, q)) else { return Ok(()) };
            dp[k] = -(a - b) / (2.0 * H);
            let (Some(a), Some(b)) = (u(p, exp(&e) * q), u(p, exp(&-e) * q)) else { return Ok(()) };
            dq[k] = -(a - b) / (2.0 * H);
        }
        assert_close("force", &w.force, &dp);
        assert_close("moment", &w.moment, &dq);
    }

    #[test]
    fn each_point_moves_at_the_derivative_of_its_place(
        p0 in proptest::array::uniform3(-1.0f64..1.0), pd in proptest::array::uniform3(-2.0f64..2.0),
        y0 in proptest::array::uniform3(-1.8f64..1.8), yd in proptest::array::uniform3(-3.0f64..3.0),
        tau in 0.3f64..3.0, k in 0usize..24
    ) {
        let tool = tray();
        let r = tool.control_points()[k];
        let (p0, pd, y0, yd) = (Vector3::from(p0), Vector3::from(pd), Vector3::from(y0), Vector3::from(yd));
        // p(t) = p0 + pd t + pd t² / 2 and y(t) = y0 + yd t - yd t² / 3, at t = 0.4.
        let at = |t: f64| -> (Vec<f64>, Vec<f64>) {
            let (p, y) = (p0 + pd * (t + 0.5 * t * t), y0 + yd * (t - t * t / 3.0));
            let (dp, dy) = (pd * (1.0 + t), yd * (1.0 - 2.0 * t / 3.0));
            let x = p.iter().chain(y.iter()).copied().collect();
            let v = dp.iter().chain(dy.iter()).map(|d| tau * d).collect();
            (x, v)
        };
        let t = 0.4;
        let (x, v) = at(t);
        let m = ToolPose::from_state(&x, &v, &q_ref()).point(&r);
        let place = |t: f64| {
            let (x, v) = at(t);
            ToolPose::from_state(&x, &v, &q_ref()).point(&r).position
        };
        let fd = (place(t + H) - place(t - H)) / (2.0 * H);
        assert_close("tau ċ / tau", &(m.velocity / tau), &fd);
        // The arm turns at ω: d(R r)/dt = ω × R r.
        let pose = ToolPose::from_state(&x, &v, &q_ref());
        prop_assert!((pose.angular_velocity - exp_jacobian(&pose.chart) * Vector3::from_column_slice(&v[3..])).amax() < 1e-12);
    }

    #[test]
    fn every_method_is_finite_in_random_scenes(
        which in 0usize..5, gain in 0.1f64..100.0, beta in 1.0f64..4.0, eta in 0.2f64..3.0,
        centers in proptest::collection::vec(proptest::array::uniform3(-0.5f64..0.5), 1..4),
        axes in proptest::array::uniform3(0.01f64..0.3), n in 1u32..4, moving in any::<bool>(),
        p in proptest::array::uniform3(-0.6f64..0.6), y in proptest::array::uniform3(-7.0f64..7.0),
        v in proptest::array::uniform6(-50.0f64..50.0), tau in 0.05f64..5.0, t in 0.0f64..3.0,
        axis in any::<bool>(), relative in any::<bool>()
    ) {
        let method = match which {
            0 => Method::StaticPoint(StaticPoint { eta: gain, p0: 0.3 }),
            1 => Method::DynamicPoint(DynamicPoint { lambda: gain, beta }),
            2 => Method::SteeringAngle(SteeringAngle { gamma: gain, beta }),
            3 => Method::StaticVolumetric(StaticVolumetric { a: gain, eta }),
            _ => Method::DynamicVolumetric(DynamicVolumetric { lambda: gain, beta, eta }),
        };
        let obstacles: Vec<Obstacle> = centers
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let shape = Superquadric::new(axes.to_vec(), vec![n as f64; 3]).unwrap();
                let vel = moving.then(|| vec![0.3 * c[1], -0.2, 0.1 * i as f64]);
                Obstacle::new(format!("o{i}"), Shape::Superquadric(shape), c.to_vec(), None, vel).unwrap()
            })
            .collect();
        let tool = if axis { bar(ControlPoints::axis()) } else { tray() };
        let scene = Scene::with_obstacles(obstacles, Avoidance { method, relative_velocity: relative }, 30);
        let mut f = ToolField::new(tool, scene, q_ref()).unwrap();
        let x: Vec<f64> = p.iter().chain(&y).copied().collect();
        let mut out = [0.0; 6];
        f.add(t, &x, &v, tau, &mut out);
        prop_assert!(out.iter().all(|o| o.is_finite()), "{out:?}");
        // The control point at an obstacle's centre (the point terms' undefined direction) too.
        let c = Vector3::from(centers[0]);
        let arm = ToolPose::from_state(&x, &v, &q_ref()).rotation * f.tool().control_points()[0];
        let at_center: Vec<f64> = (c - arm).iter().chain(&y).copied().collect();
        let mut out = [0.0; 6];
        f.add(t, &at_center, &v, tau, &mut out);
        prop_assert!(out.iter().all(|o| o.is_finite()), "{out:?}");
    }
}

/// The angular term is the chart's image of the angular acceleration `I_w⁻¹ M`: `I_w J(y) out_y = M`.
#[test]
fn the_angular_term_is_the_angular_acceleration_of_the_moment_in_the_chart() {
    let method = Method::StaticVolumetric(StaticVolumetric { a: 2.0, eta: 1.0 });
    let mut f = field(tray(), method);
    let mut checked = 0;
    for k in 0..20 {
        let p = Vector3::new(0.1 * k as f64 - 0.9, 0.15, 0.05);
        let y = Vector3::new(0.5, -1.2 + 0.1 * k as f64, 0.8);
        let x: Vec<f64> = p.iter().chain(y.iter()).copied().collect();
        let mut out = [0.0; 6];
        f.add(0.3, &x, &[0.0; 6], 1.0, &mut out);
        let w = f.wrench(0.3, &x, &[0.0; 6], 1.0);
        let pose = ToolPose::from_state(&x, &[0.0; 6], &q_ref());
        let iw = pose.rotation * f.tool().inertia() * pose.rotation.transpose();
        let angular = Vector3::from_column_slice(&out[3..]);
        if angular.norm() >= 0.999 * crate::field::DEFAULT_MAX_PERTURBATION {
            continue; // capped
        }
        let m = iw * exp_jacobian(&y) * angular;
        assert_close("I_w J out_y", &m, &w.moment);
        assert_close("out_p", &Vector3::from_column_slice(&out[..3]), &w.force);
        checked += usize::from(w.moment.norm() > 1e-3);
    }
    assert!(checked >= 5, "only {checked} poses with a moment");
}

/// A moving obstacle acts on a point through the relative velocity: the tool moving at `w` past a still obstacle
/// feels what it feels at rest beside the obstacle moving at `-w`.
#[test]
fn moving_obstacles_act_through_the_relative_velocity() {
    let tau = 1.7;
    let (x, v) = (
        [0.15, 0.05, 0.0, 0.3, 0.2, -0.1],
        [1.2, -0.4, 0.3, 0.0, 0.0, 0.0], // tau ṗ only: every point moves at ṗ
    );
    for method in [
        Method::DynamicPoint(DynamicPoint { lambda: 2.0, beta: 2.0 }),
        Method::SteeringAngle(SteeringAngle { gamma: 20.0, beta: 3.0 }),
        Method::DynamicVolumetric(DynamicVolumetric { lambda: 10.0, beta: 2.0, eta: 0.5 }),
    ] {
        let still = Obstacle::new(
            "o",
            Shape::Superquadric(Superquadric::ellipsoid(vec![0.1, 0.15, 0.1]).unwrap()),
            vec![0.45, 0.0, 0.05],
            None,
            None,
        )
        .unwrap();
        let vel: Vec<f64> = v[..3].iter().map(|vi| -vi / tau).collect();
        let moving =
            Obstacle::new("o", still.shape().clone(), still.center().to_vec(), None, Some(vel)).unwrap();
        let mk = |o: Obstacle| {
            ToolField::new(tray(), Scene::with_obstacles(vec![o], Avoidance::new(method), SAMPLES), q_ref())
                .unwrap()
        };
        let a = mk(still).wrench(0.0, &x, &v, tau);
        let mut rest = v;
        rest[..3].fill(0.0);
        let b = mk(moving).wrench(0.0, &x, &rest, tau);
        assert!(a.force.norm() > 1e-6, "{}: no term at all", method.name());
        if !matches!(method, Method::SteeringAngle(_)) {
            // The steering term turns the robot's own velocity v, which differs between the two.
            assert_close(method.name(), &a.force, &b.force);
            assert_close(method.name(), &a.moment, &b.moment);
        }
    }
}

#[test]
fn axis_samples_span_the_longest_axis_tips_included_and_cannot_twist_it() {
    let tool = bar(ControlPoints::Axis { count: 5 });
    for (r, want) in tool.control_points().iter().zip([-0.3, -0.15, 0.0, 0.15, 0.3]) {
        assert!((r[0] - want).abs() < 1e-15, "{r:?}");
    }
    assert!(tool.control_points().iter().all(|r| r[1] == 0.0 && r[2] == 0.0));
    // No inertia about the axis, and its pseudo-inverse gives no turn about it.
    assert!((tool.inertia_inverse() * Vector3::x()).norm() < 1e-12);
    assert!((tool.inertia_inverse()[(1, 1)] - 1.0 / 0.045).abs() < 1e-9);
    let reach = ControlPoints::Axis { count: 5 }.reach(tool.shape()).unwrap();
    assert!((reach - (0.02 * std::f64::consts::SQRT_2 + 0.075)).abs() < 1e-12);
    assert_eq!(ControlPoints::default().reach(tool.shape()), None);
    // Surface samples lie on the surface.
    let surface = bar(ControlPoints::default());
    assert_eq!(surface.control_points().len(), sampling::DEFAULT_SURFACE_POINTS);
    let sq = Superquadric::new(vec![0.3, 0.02, 0.02], vec![2.0, 2.0, 2.0]).unwrap();
    use crate::isopotential::Isopotential;
    for r in surface.control_points() {
        assert!(sq.value(r.as_slice()).abs() < 1e-9);
    }
}

#[test]
fn refusals_name_the_field() {
    let sq2 = Shape::Superquadric(Superquadric::ellipsoid(vec![0.1, 0.2]).unwrap());
    let field_of = |e: crate::DmpError| match e {
        crate::DmpError::Invalid(i) => i.field,
        other => panic!("{other}"),
    };
    let e = Tool::new(sq2, [0.0; 3], ControlPoints::default()).unwrap_err();
    assert_eq!(field_of(e), "tool.shape.semi_axes");
    let sq3 = Shape::Superquadric(Superquadric::ellipsoid(vec![0.1, 0.2, 0.3]).unwrap());
    let e = Tool::new(sq3.clone(), [0.0, f64::NAN, 0.0], ControlPoints::default()).unwrap_err();
    assert_eq!(field_of(e), "tool.offset[1]");
    for bad in [ControlPoints::Axis { count: 1 }, ControlPoints::Surface { count: 3 }] {
        let e = Tool::new(sq3.clone(), [0.0; 3], bad).unwrap_err();
        assert_eq!(field_of(e), "tool.control_points.count");
    }
    let nan = UnitQuaternion::new_unchecked(Quaternion::new(f64::NAN, 0.0, 0.0, 0.0));
    let e = ToolField::new(tray(), Scene::empty(), nan).unwrap_err();
    assert_eq!(field_of(e), "q_ref");
    let mut scene = Scene::empty();
    scene.agents.push(Agent { id: "r".into(), dims: vec![0, 1, 2], footprint: None });
    assert_eq!(field_of(ToolField::new(tray(), scene, q_ref()).unwrap_err()), "robots");
    let scene = Scene::with_obstacles(
        obstacles(),
        Avoidance::new(Method::StaticPoint(StaticPoint { eta: 1.0, p0: 0.2 })),
        0,
    );
    assert_eq!(field_of(ToolField::new(tray(), scene, q_ref()).unwrap_err()), "point_samples");
    // A state of another dimension adds nothing.
    let mut f = field(tray(), static_method(false, 1.0));
    let mut out = [0.0; 3];
    f.add(0.0, &[0.4, 0.1, 0.0], &[0.0; 3], 1.0, &mut out);
    assert_eq!(out, [0.0; 3]);
}

/// Each of the five methods pushes and turns a tool that moves toward an obstacle off its centre line.
#[test]
fn every_method_pushes_and_turns_the_tool() {
    let obstacle = Obstacle::new(
        "o",
        Shape::Superquadric(Superquadric::ellipsoid(vec![0.1, 0.1, 0.1]).unwrap()),
        vec![0.5, 0.2, 0.0],
        None,
        None,
    )
    .unwrap();
    // The bar across the x axis (tool x along world y), its middle at the origin, moving along +x: its +y half
    // heads for the obstacle.
    let q = exp(&Vector3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2));
    let x = state(&Vector3::new(0.3, 0.0, 0.0), &q);
    let mut v = [0.0; 6];
    v[0] = 1.0;
    for method in [
        Method::StaticPoint(StaticPoint { eta: 1.0, p0: 0.3 }),
        Method::DynamicPoint(DynamicPoint { lambda: 2.0, beta: 2.0 }),
        Method::SteeringAngle(SteeringAngle { gamma: 20.0, beta: 3.0 }),
        Method::StaticVolumetric(StaticVolumetric { a: 10.0, eta: 1.0 }),
        Method::DynamicVolumetric(DynamicVolumetric { lambda: 10.0, beta: 2.0, eta: 0.5 }),
    ] {
        let scene = Scene::with_obstacles(vec![obstacle.clone()], Avoidance::new(method), SAMPLES);
        let mut f = ToolField::new(bar(ControlPoints::axis()), scene, q_ref()).unwrap();
        let w = f.wrench(0.0, &x, &v, 1.0);
        assert!(w.force.norm() > 1e-6, "{}: {w:?}", method.name());
        assert!(w.moment.norm() > 1e-6, "{}: {w:?}", method.name());
        let mut out = [0.0; 6];
        f.add(0.0, &x, &v, 1.0, &mut out);
        assert!(out[3..].iter().any(|o| o.abs() > 1e-6), "{}: {out:?}", method.name());
    }
}
