//! The figures of typical runs, checked for well-formed SVG, labels, proportions and size; with
//! `DMP_PLOT_DUMP=<dir>` set, each test also writes its figure there.

use dmp::{Agent, Obstacle, Shape, Superquadric, Trajectory};

use crate::data::bounds::fit_equal_aspect;
use crate::data::decimate::{MAX_POINTS, decimated};
use crate::data::geometry::convex_hull;
use crate::data::outline::OUTLINE_SAMPLES_2D;
use crate::draw::style::{fmt_num, fmt_tick};
use crate::figures::time::MAX_TIME_PANELS;

mod elements;
mod pose;
mod safety;
use super::{PlotError, PlotInput, render_svg};

pub(super) fn ellipse(id: &str, center: Vec<f64>, axes: Vec<f64>, velocity: Option<Vec<f64>>) -> Obstacle {
    let n = axes.len();
    Obstacle::new(
        id,
        Shape::Superquadric(Superquadric::new(axes, vec![1.0; n]).unwrap()),
        center,
        None,
        velocity,
    )
    .unwrap()
}

/// A trajectory of `rows` rows over `[0, 1]` from `f(s)`.
pub(super) fn traj(d: usize, rows: usize, f: impl Fn(f64) -> Vec<f64>) -> Trajectory {
    let mut tr = Trajectory::with_capacity(d, rows);
    let zero = vec![0.0; d];
    for k in 0..rows {
        let s = k as f64 / (rows - 1) as f64;
        tr.push(s, &f(s), &zero, &zero);
    }
    tr
}

pub(super) fn bump(s: f64) -> f64 {
    (std::f64::consts::PI * s).sin()
}

/// The SVG parsed (a well-formed XML document, or the test fails).
pub(super) fn parse(svg: &str) -> roxmltree::Document<'_> {
    roxmltree::Document::parse(svg).unwrap_or_else(|e| panic!("not well-formed XML: {e}"))
}

/// The text of every `<text>` element.
pub(super) fn texts(svg: &str) -> Vec<String> {
    let doc = parse(svg);
    doc.descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|n| n.text().unwrap_or("").trim().to_string())
        .collect()
}

pub(super) fn count_text(svg: &str, s: &str) -> usize {
    texts(svg).iter().filter(|t| t.as_str() == s).count()
}

/// The groups of class `class`.
pub(super) fn groups<'a, 'i>(doc: &'a roxmltree::Document<'i>, class: &str) -> Vec<roxmltree::Node<'a, 'i>> {
    doc.descendants().filter(|n| n.has_tag_name("g") && n.attribute("class") == Some(class)).collect()
}

/// The elements named `tag` under the groups of class `class`.
pub(super) fn in_class<'a, 'i>(
    doc: &'a roxmltree::Document<'i>,
    class: &str,
    tag: &str,
) -> Vec<roxmltree::Node<'a, 'i>> {
    groups(doc, class)
        .into_iter()
        .flat_map(|g| g.descendants().filter(|n| n.has_tag_name(tag)).collect::<Vec<_>>())
        .collect()
}

/// The `points` of a polygon or polyline, in pixels.
pub(super) fn points(n: &roxmltree::Node<'_, '_>) -> Vec<(f64, f64)> {
    n.attribute("points")
        .unwrap_or("")
        .split_whitespace()
        .map(|xy| {
            let (x, y) = xy.split_once(',').unwrap();
            (x.parse().unwrap(), y.parse().unwrap())
        })
        .collect()
}

/// Width over height of the bounding box of `pts`.
pub(super) fn aspect(pts: &[(f64, f64)]) -> f64 {
    let (w0, w1) = pts.iter().fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (h0, h1) = pts.iter().fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.1), b.max(p.1)));
    (w1 - w0) / (h1 - h0)
}

/// Polygons of the true shapes.
fn polygons(svg: &str) -> Vec<Vec<(f64, f64)>> {
    let doc = parse(svg);
    in_class(&doc, "obstacle-true", "polygon").iter().map(points).collect()
}

/// With `DMP_PLOT_DUMP=dir` set, tests write their figures there (to look at them).
pub(super) fn dump(name: &str, svg: &str) {
    if let Some(dir) = std::env::var_os("DMP_PLOT_DUMP") {
        std::fs::write(std::path::Path::new(&dir).join(format!("{name}.svg")), svg).unwrap();
    }
}

pub(super) fn check_common(svg: &str) {
    parse(svg);
    assert!(!svg.contains("NaN") && !svg.contains("inf"), "non-finite number in the SVG");
    assert!(svg.contains("<text"), "no text at all");
    for t in texts(svg) {
        assert!(!t.starts_with("-0") || t.parse::<f64>().is_ok_and(|v| v != 0.0), "label {t:?}");
    }
}

struct Case2d {
    demo: Vec<Vec<f64>>,
    free: Trajectory,
    adapted: Trajectory,
    obstacles: Vec<Obstacle>,
}

fn case_2d() -> Case2d {
    Case2d {
        demo: (0..=200)
            .map(|k| {
                let s = k as f64 / 200.0;
                vec![s, s + 0.05 * bump(s)]
            })
            .collect(),
        free: traj(2, 1001, |s| vec![s, s]),
        adapted: traj(2, 1001, |s| vec![s + 0.25 * bump(s), s - 0.25 * bump(s)]),
        obstacles: vec![ellipse("ellipse", vec![0.5, 0.5], vec![0.3, 0.1], None)],
    }
}

fn input_2d(c: &Case2d) -> PlotInput<'_> {
    PlotInput {
        title: "2-D: one ellipse",
        demonstration: &c.demo,
        demonstration_t: None,
        free: &c.free,
        adapted: &c.adapted,
        goal: None,
        obstacles: &c.obstacles,
        robots: &[],
        obstacle_time: 0.0,
        solids: &[],
        method: "dynamic_volumetric",
        clearance: None,
        events: &[],
        pose: None,
    }
}

#[test]
fn plot_2d_one_ellipse() {
    let c = case_2d();
    let svg = render_svg(&input_2d(&c)).unwrap();
    dump("plot_2d_one_ellipse", &svg);
    check_common(&svg);
    for label in [
        "2-D: one ellipse",
        "x1 (m)",
        "x2 (m)",
        "demonstration",
        "obstacle-free DMP",
        "with avoidance: dynamic volumetric",
    ] {
        assert_eq!(count_text(&svg, label), 1, "text {label:?}");
    }
    assert!(svg.contains("#D62728") && svg.contains("#1F77B4"), "adapted / free colours");
    // One obstacle in one panel; its outline has the ellipse's 3:1 shape on screen (equal aspect ratio).
    let polys = polygons(&svg);
    assert_eq!(polys.len(), 1);
    let a = aspect(&polys[0]);
    assert!((a - 3.0).abs() < 0.02, "ellipse drawn with aspect {a}");
    assert_eq!(polys[0].len(), OUTLINE_SAMPLES_2D);
    assert!(svg.len() < 300_000, "{} bytes", svg.len());
    // Deterministic.
    assert_eq!(svg, render_svg(&input_2d(&c)).unwrap());
}

#[test]
fn plot_3d_three_projections() {
    let demo: Vec<Vec<f64>> = (0..=100).map(|k| vec![k as f64 / 100.0; 3]).collect();
    let free = traj(3, 801, |s| vec![s, s, s]);
    let adapted = traj(3, 801, |s| vec![s + 0.2 * bump(s), s - 0.1 * bump(s), s]);
    let obstacles = vec![ellipse("ellipsoid", vec![0.5, 0.5, 0.5], vec![0.2, 0.1, 0.15], None)];
    let input = PlotInput {
        title: "3-D",
        demonstration: &demo,
        demonstration_t: None,
        free: &free,
        adapted: &adapted,
        goal: None,
        obstacles: &obstacles,
        robots: &[],
        obstacle_time: 0.0,
        solids: &[],
        method: "dynamic_volumetric",
        clearance: None,
        events: &[],
        pose: None,
    };
    let svg = render_svg(&input).unwrap();
    dump("plot_3d_three_projections", &svg);
    check_common(&svg);
    for caption in ["x1 - x2", "x1 - x3", "x2 - x3"] {
        assert_eq!(count_text(&svg, caption), 1, "panel {caption:?}");
    }
    for axis in ["x1 (m)", "x2 (m)", "x3 (m)"] {
        assert_eq!(count_text(&svg, axis), 2, "axis name {axis:?}");
    }
    // The ellipsoid in each projection, with the right proportions.
    let polys = polygons(&svg);
    assert_eq!(polys.len(), 3);
    for (poly, ratio) in polys.iter().zip([2.0, 0.2 / 0.15, 0.1 / 0.15]) {
        let a = aspect(poly);
        assert!((a - ratio).abs() < 0.02 * ratio, "aspect {a}, expected {ratio}");
    }
}

#[test]
fn plot_three_robots() {
    let d = 6;
    let starts = [(0.0, 0.0), (1.0, 0.0), (0.5, 1.0)];
    let goals = [(1.0, 1.0), (0.0, 1.0), (0.5, 0.0)];
    let path = |s: f64, w: f64| -> Vec<f64> {
        (0..3)
            .flat_map(|r| {
                let (a, b) = (starts[r], goals[r]);
                [a.0 + (b.0 - a.0) * s + w * bump(s), a.1 + (b.1 - a.1) * s]
            })
            .collect()
    };
    let free = traj(d, 2001, |s| path(s, 0.0));
    let adapted = traj(d, 2001, |s| path(s, 0.1));
    let demo: Vec<Vec<f64>> = (0..=50).map(|k| path(k as f64 / 50.0, 0.0)).collect();
    let circle = Shape::Superquadric(Superquadric::new(vec![0.08, 0.08], vec![1.0, 1.0]).unwrap());
    let robots: Vec<Agent> = (0..3)
        .map(|r| Agent {
            id: format!("youbot{}", r + 1),
            dims: vec![2 * r, 2 * r + 1],
            footprint: Some(circle.clone()),
        })
        .collect();
    let obstacles = vec![ellipse("box", vec![0.5, 0.5], vec![0.1, 0.1], Some(vec![0.1, 0.0]))];
    let input = PlotInput {
        title: "three youBots",
        demonstration: &demo,
        demonstration_t: None,
        free: &free,
        adapted: &adapted,
        goal: None,
        obstacles: &obstacles,
        robots: &robots,
        obstacle_time: 0.5,
        solids: &[],
        method: "dynamic_volumetric",
        clearance: None,
        events: &[],
        pose: None,
    };
    let svg = render_svg(&input).unwrap();
    dump("plot_three_robots", &svg);
    check_common(&svg);
    for r in &robots {
        assert_eq!(count_text(&svg, &format!("{}, with avoidance", r.id)), 1, "legend entry {}", r.id);
        assert_eq!(count_text(&svg, &format!("{}, obstacle-free", r.id)), 1, "legend entry {}", r.id);
    }
    for colour in ["#1F77B4", "#FF7F0E", "#2CA02C"] {
        assert!(svg.contains(&format!("stroke=\"{colour}\"")), "robot colour {colour}");
    }
    assert_eq!(count_text(&svg, "x1 (m)"), 1);
    // The moving obstacle at the five marked times (t = 0.5 among them).
    assert_eq!(polygons(&svg).len(), 5);
    assert_eq!(count_text(&svg, "0 s"), 1 + 3, "the obstacle and each robot's tick at t = 0");
    // The obstacle moves 0.1 m in all: its outlines are too close to label each; the robots' ticks are labelled.
    assert_eq!(count_text(&svg, "0.5 s"), 3, "each robot's tick at t = 0.5");
}

#[test]
fn plot_against_time_above_3d() {
    let d = 7;
    let free = traj(d, 5001, |s| (0..d).map(|i| s * i as f64).collect());
    let adapted = traj(d, 5001, |s| (0..d).map(|i| s * i as f64 + 0.1 * bump(s)).collect());
    let obstacles = vec![ellipse("ball", vec![0.5; d], vec![0.2; d], None)];
    let input = PlotInput {
        title: "7-D",
        demonstration: &[],
        demonstration_t: None,
        free: &free,
        adapted: &adapted,
        goal: None,
        obstacles: &obstacles,
        robots: &[],
        obstacle_time: 0.0,
        solids: &[],
        method: "dynamic_volumetric",
        clearance: None,
        events: &[],
        pose: None,
    };
    let svg = render_svg(&input).unwrap();
    dump("plot_against_time_above_3d", &svg);
    check_common(&svg);
    assert_eq!(count_text(&svg, "t (s)"), MAX_TIME_PANELS + 1, "each panel and the time strip");
    assert_eq!(count_text(&svg, "x6"), 1);
    assert_eq!(count_text(&svg, "x7"), 0);
    assert_eq!(count_text(&svg, "showing 6 of 7 coordinates"), 1);
    assert_eq!(polygons(&svg).len(), MAX_TIME_PANELS);
    // Decimated: no polyline has more than MAX_POINTS vertices.
    for pl in svg.split("<polyline").skip(1) {
        let pts = &pl[pl.find("points=\"").unwrap() + 8..];
        assert!(pts[..pts.find('"').unwrap()].split_whitespace().count() <= MAX_POINTS);
    }
}

#[test]
fn plot_1d_and_non_finite_rows() {
    let free = traj(1, 101, |s| vec![s]);
    let adapted = traj(1, 101, |s| vec![if (0.4..0.5).contains(&s) { f64::NAN } else { s * s }]);
    let obstacles = vec![ellipse("wall", vec![0.5], vec![0.05], None)];
    let demo = vec![vec![0.0], vec![0.5], vec![1.0]];
    let input = PlotInput {
        title: "1-D",
        demonstration: &demo,
        demonstration_t: None,
        free: &free,
        adapted: &adapted,
        goal: None,
        obstacles: &obstacles,
        robots: &[],
        obstacle_time: f64::NAN,
        solids: &[],
        method: "dynamic_volumetric",
        clearance: None,
        events: &[],
        pose: None,
    };
    let svg = render_svg(&input).unwrap();
    dump("plot_1d_and_non_finite_rows", &svg);
    check_common(&svg);
    assert_eq!(count_text(&svg, "x1"), 1);
}

#[test]
fn plot_rejects_inconsistent_input() {
    let c = case_2d();
    let wrong = vec![ellipse("ball", vec![0.5; 3], vec![0.2; 3], None)];
    let err = render_svg(&PlotInput { obstacles: &wrong, ..input_2d(&c) }).unwrap_err();
    assert!(matches!(err, PlotError::Dimension { expected: 2, found: 3, .. }), "{err}");
    let robots = vec![Agent { id: "a".into(), dims: vec![0, 5], footprint: None }];
    let err = render_svg(&PlotInput { robots: &robots, ..input_2d(&c) }).unwrap_err();
    assert!(matches!(err, PlotError::Robot { index: 0, .. }), "{err}");
    let empty = Trajectory::with_capacity(2, 0);
    let err = render_svg(&PlotInput { adapted: &empty, ..input_2d(&c) }).unwrap_err();
    assert!(matches!(err, PlotError::EmptyTrajectory("adapted")), "{err}");
}

#[test]
fn plot_goal_marker() {
    let c = case_2d();
    let default = render_svg(&input_2d(&c)).unwrap();
    // The obstacle-free rollout ends at (1, 1): the same goal given explicitly draws the same figure.
    let same = render_svg(&PlotInput { goal: Some(&[1.0, 1.0]), ..input_2d(&c) }).unwrap();
    assert_eq!(same, default);
    let moved = render_svg(&PlotInput { goal: Some(&[1.2, 0.9]), ..input_2d(&c) }).unwrap();
    dump("plot_goal_marker", &moved);
    check_common(&moved);
    assert_ne!(moved, default);
    let err = render_svg(&PlotInput { goal: Some(&[1.0]), ..input_2d(&c) }).unwrap_err();
    assert!(matches!(err, PlotError::Dimension { expected: 2, found: 1, .. }), "{err}");
}

#[test]
fn plot_demonstration_times() {
    let free = traj(1, 101, |s| vec![s]);
    let adapted = traj(1, 101, |s| vec![s * s]);
    let demo = vec![vec![0.0], vec![0.4], vec![1.0]];
    let input = PlotInput {
        title: "1-D, timed demonstration",
        demonstration: &demo,
        demonstration_t: None,
        free: &free,
        adapted: &adapted,
        goal: None,
        obstacles: &[],
        robots: &[],
        obstacle_time: 0.0,
        solids: &[],
        method: "dynamic_volumetric",
        clearance: None,
        events: &[],
        pose: None,
    };
    let spread = render_svg(&input).unwrap();
    assert_eq!(count_text(&spread, "demonstration (time rescaled)"), 1);
    // Times starting at 3 are shifted to start with the rollouts, at 0: evenly spaced over the rollout's span, they
    // draw what the fallback draws, with the legend no longer saying the time is rescaled.
    let timed = render_svg(&PlotInput { demonstration_t: Some(&[3.0, 3.5, 4.0]), ..input }).unwrap();
    assert_eq!(timed, spread.replace("demonstration (time rescaled)", "demonstration"));
    // A demonstration longer than the rollouts widens the time axis.
    let long = render_svg(&PlotInput { demonstration_t: Some(&[3.0, 4.0, 5.0]), ..input }).unwrap();
    dump("plot_demonstration_times", &long);
    check_common(&long);
    assert_ne!(long.replace("demonstration", ""), timed.replace("demonstration", ""));
    assert_eq!(count_text(&long, "2"), 1, "tick at t = 2");
    let err = render_svg(&PlotInput { demonstration_t: Some(&[0.0, 1.0]), ..input }).unwrap_err();
    assert!(matches!(err, PlotError::Length { expected: 3, found: 2, .. }), "{err}");
}

#[test]
fn plot_helpers() {
    assert_eq!(decimated(5), vec![0, 1, 2, 3, 4]);
    let idx = decimated(1_000_001);
    assert!(idx.len() <= MAX_POINTS && idx[0] == 0 && *idx.last().unwrap() == 1_000_000);
    let hull = convex_hull(vec![(0.0, 0.0), (1.0, 0.0), (0.5, 0.5), (1.0, 1.0), (0.0, 1.0), (0.2, 0.8)]);
    assert_eq!(hull, vec![(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]);
    let ((x0, x1), (y0, y1)) = fit_equal_aspect((0.0, 1.0), (0.0, 3.0), 600.0, 300.0);
    assert!(((x1 - x0) / (y1 - y0) - 2.0).abs() < 1e-12 && (y1 - y0 - 3.0).abs() < 1e-12);
    assert_eq!(fmt_num(0.5), "0.5");
    assert_eq!(fmt_num(2.0), "2");
    assert_eq!(fmt_num(-0.0001), "0");
    assert_eq!(fmt_tick(-0.0), "0");
    assert_eq!(fmt_tick(0.1 + 0.2), "0.3");
    assert_eq!(fmt_tick(0.0025), "0.0025");
}
