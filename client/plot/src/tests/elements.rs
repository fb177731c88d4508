//! What each figure must contain, found by the classes of its groups: true shapes and isopotentials, contacts,
//! the legend of the runs, the time strip with its events, marked times of moving obstacles, the zoom on the
//! motion, sub-pixel coordinates and units.

use dmp::{Obstacle, Trajectory};

use super::{
    aspect, bump, check_common, count_text, dump, ellipse, groups, in_class, parse, points, texts, traj,
};
use crate::draw::backend::SCALE;
use crate::{Event, PlotInput, Series, Solid, SolidShape, render_svg};

fn input<'a>(free: &'a Trajectory, adapted: &'a Trajectory, obstacles: &'a [Obstacle]) -> PlotInput<'a> {
    PlotInput {
        title: "test",
        demonstration: &[],
        demonstration_t: None,
        free,
        adapted,
        goal: None,
        obstacles,
        robots: &[],
        obstacle_time: f64::NAN,
        solids: &[],
        method: "dynamic_volumetric",
        clearance: None,
        events: &[],
        pose: None,
    }
}

/// A 2-D run from (0, 0) to (1, 0), bent by `bend` at its middle.
fn bent(bend: f64) -> Trajectory {
    traj(2, 501, |s| vec![s, bend * bump(s)])
}

#[test]
fn true_shape_under_a_lighter_isopotential() {
    let (free, adapted) = (bent(0.0), bent(0.3));
    // A box of half-sides 0.1 x 0.05 at (0.5, 0.1), planned as an ellipse inflated around it.
    let solids = vec![Solid::new("box", SolidShape::Box { half: vec![0.1, 0.05] }, vec![0.5, 0.1])];
    let obstacles = vec![ellipse("box", vec![0.5, 0.1], vec![0.2, 0.12], None)];
    let svg = render_svg(&PlotInput { solids: &solids, ..input(&free, &adapted, &obstacles) }).unwrap();
    dump("true_shape_under_a_lighter_isopotential", &svg);
    check_common(&svg);
    let doc = parse(&svg);
    let truth = in_class(&doc, "obstacle-true", "polygon");
    let iso = in_class(&doc, "isopotential", "polygon");
    assert_eq!((truth.len(), iso.len()), (1, 1));
    // The box is drawn as a box (4 corners, 2:1) inside its isopotential, which is lighter.
    let b = points(&truth[0]);
    assert_eq!(b.len(), 4);
    assert!((aspect(&b) - 2.0).abs() < 0.01, "{}", aspect(&b));
    let e = points(&iso[0]);
    let span = |p: &[(f64, f64)]| {
        p.iter().fold(f64::MIN, |m, q| m.max(q.0)) - p.iter().fold(f64::MAX, |m, q| m.min(q.0))
    };
    assert!(span(&e) > 1.9 * span(&b), "the isopotential is wider than the box");
    let opacity = |n: &roxmltree::Node<'_, '_>| n.attribute("opacity").unwrap().parse::<f64>().unwrap();
    assert!(opacity(&iso[0]) < opacity(&truth[0]), "the isopotential is lighter");
    assert_eq!(count_text(&svg, "obstacle (true shape)"), 1);
    assert_eq!(count_text(&svg, "isopotential avoided"), 1);
}

#[test]
fn contacts_are_marked_where_the_path_enters_a_true_shape() {
    let free = bent(0.0);
    // The free path crosses the ball at (0.5, 0); the adapted path (the same) touches it: a contact.
    let obstacles = vec![ellipse("ball", vec![0.5, 0.0], vec![0.1, 0.1], None)];
    let svg = render_svg(&PlotInput { method: "none", ..input(&free, &free, &obstacles) }).unwrap();
    dump("contacts_are_marked", &svg);
    check_common(&svg);
    let doc = parse(&svg);
    let marks = in_class(&doc, "contact", "polyline");
    assert_eq!(marks.len(), 1, "one contact stretch");
    assert_eq!(count_text(&svg, "contact"), 1, "in the legend");
    // The clearance given by the caller decides: never below zero, no contact.
    let clear = vec![Series { t: free.t.clone(), v: vec![0.2; free.len()] }];
    let svg = render_svg(&PlotInput { clearance: Some(&clear), ..input(&free, &free, &obstacles) }).unwrap();
    assert!(in_class(&parse(&svg), "contact", "polyline").is_empty());
    assert_eq!(count_text(&svg, "contact"), 0);
    // A path that goes round it has none either.
    let adapted = bent(0.3);
    let svg = render_svg(&input(&free, &adapted, &obstacles)).unwrap();
    assert!(in_class(&parse(&svg), "contact", "polyline").is_empty());
}

#[test]
fn the_legend_tells_the_free_run_from_the_adapted_one() {
    let (free, adapted) = (bent(0.0), bent(0.2));
    let obstacles = vec![ellipse("ball", vec![0.5, 0.0], vec![0.1, 0.1], None)];
    for (method, text) in [
        ("none", "run without avoidance (none)"),
        ("steering_angle", "with avoidance: steering angle"),
        ("dynamic_volumetric", "with avoidance: dynamic volumetric"),
    ] {
        let svg = render_svg(&PlotInput { method, ..input(&free, &adapted, &obstacles) }).unwrap();
        let doc = parse(&svg);
        let legend = |class: &str| -> Vec<String> {
            groups(&doc, class)
                .iter()
                .flat_map(|g| g.descendants().filter(|n| n.has_tag_name("text")).filter_map(|n| n.text()))
                .map(str::trim)
                .filter(|t| !t.is_empty())
                .map(String::from)
                .collect()
        };
        assert_eq!(legend("legend-adapted"), vec![text.to_string()], "{method}");
        assert_eq!(legend("legend-free"), vec!["obstacle-free DMP".to_string()], "{method}");
        if method == "none" {
            assert!(!svg.contains("with avoidance"), "a run without avoidance is labelled as one");
        }
        // Each run is drawn, in the path panel and in the time strip.
        assert!(
            in_class(&doc, "path-free", "polyline").len() >= 2
                && in_class(&doc, "path-adapted", "polyline").len() >= 2
        );
    }
}

#[test]
fn a_time_strip_with_speed_acceleration_clearance_and_events() {
    let mut adapted = Trajectory::with_capacity(2, 101);
    for k in 0..=100 {
        let t = k as f64 / 100.0;
        adapted.push(t, &[t, 0.3 * t * t], &[1.0, 0.6 * t], &[0.0, 0.6]);
    }
    let obstacles = vec![ellipse("ball", vec![0.5, 0.5], vec![0.1, 0.1], None)];
    let events = vec![Event::new(0.25, "box appears"), Event::new(0.6, "scene version 3")];
    let svg = render_svg(&PlotInput { events: &events, ..input(&adapted, &adapted, &obstacles) }).unwrap();
    dump("a_time_strip", &svg);
    check_common(&svg);
    let doc = parse(&svg);
    for (class, unit) in
        [("speed", "speed (m/s)"), ("acceleration", "acceleration (m/s²)"), ("clearance", "clearance (m)")]
    {
        let g = groups(&doc, class);
        assert_eq!(g.len(), 1, "{class}");
        assert!(g[0].descendants().any(|n| n.has_tag_name("polyline")), "{class} drawn");
        assert_eq!(count_text(&svg, unit), 1);
        // Every panel of the strip has both events as lines.
        let lines: Vec<_> = g[0].descendants().filter(|n| n.attribute("class") == Some("event")).collect();
        assert_eq!(lines.len(), 2, "{class}");
        assert_eq!(lines[0].attribute("data-t"), Some("0.25"));
    }
    assert_eq!(count_text(&svg, "box appears (0.25 s)"), 1);
    assert_eq!(count_text(&svg, "scene version 3 (0.6 s)"), 1);
    assert_eq!(count_text(&svg, "t (s)"), 1);
    // The speed |(1, 0.6 t)| grows: drawn upwards (smaller y on screen) from left to right.
    let strip = groups(&doc, "speed")[0];
    let speed: Vec<(f64, f64)> = strip
        .descendants()
        .filter(|n| n.attribute("class") == Some("path-adapted"))
        .flat_map(|g| {
            g.descendants()
                .filter(|n| n.has_tag_name("polyline"))
                .flat_map(|p| points(&p))
                .collect::<Vec<_>>()
        })
        .collect();
    let (first, last) = (speed.first().unwrap(), speed.last().unwrap());
    assert!(first.0 < last.0 && first.1 > last.1, "{first:?} to {last:?}");
}

#[test]
fn moving_obstacles_and_paths_at_marked_times() {
    let (free, adapted) = (bent(0.0), bent(0.3));
    let obstacles = vec![ellipse("cart", vec![0.2, 0.5], vec![0.1, 0.1], Some(vec![0.6, 0.0]))];
    let svg = render_svg(&input(&free, &adapted, &obstacles)).unwrap();
    dump("moving_obstacles", &svg);
    check_common(&svg);
    let doc = parse(&svg);
    // Five marked times: the cart outlined at each, the path ticked at each, both labelled.
    assert_eq!(in_class(&doc, "obstacle-true", "polygon").len(), 5);
    assert_eq!(in_class(&doc, "time-mark", "circle").len(), 5);
    for t in ["0 s", "0.25 s", "0.5 s", "0.75 s", "1 s"] {
        assert_eq!(count_text(&svg, t), 2, "{t}: the cart's outline and the path's tick");
    }
}

#[test]
fn zoomed_on_the_motion_not_on_a_large_obstacle() {
    // A 4 m table under a motion of 0.1 m.
    let free = traj(2, 201, |s| vec![0.1 * s, 0.02 * bump(s)]);
    let solids = vec![Solid::new("table", SolidShape::Box { half: vec![2.0, 2.0] }, vec![0.0, 0.0])];
    let obstacles = vec![ellipse("table", vec![0.0, 0.0], vec![2.1, 2.1], None)];
    let svg = render_svg(&PlotInput { solids: &solids, ..input(&free, &free, &obstacles) }).unwrap();
    dump("zoomed_on_the_motion", &svg);
    let doc = parse(&svg);
    let panel = doc.descendants().find(|n| n.attribute("id") == Some("panel-0")).unwrap();
    let ticks: Vec<f64> = panel
        .descendants()
        .filter(|n| n.has_tag_name("text"))
        .filter_map(|n| n.text()?.trim().parse().ok())
        .collect();
    let (lo, hi) = ticks.iter().fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
    assert!(hi - lo < 0.3, "axes span {lo} to {hi}: not zoomed on a motion of 0.1 m");
}

#[test]
fn crisp_sub_pixel_coordinates_with_units() {
    let (free, adapted) = (bent(0.0), bent(0.3));
    let obstacles = vec![ellipse("ball", vec![0.5, 0.1], vec![0.1, 0.1], None)];
    let svg = render_svg(&input(&free, &adapted, &obstacles)).unwrap();
    let doc = parse(&svg);
    let root = doc.root_element();
    let (w, h): (f64, f64) = (
        root.attribute("width").unwrap().parse().unwrap(),
        root.attribute("height").unwrap().parse().unwrap(),
    );
    assert_eq!(root.attribute("viewBox"), Some(format!("0 0 {w} {h}").as_str()));
    assert!(w > 600.0 && w < 3000.0 && h > 400.0 && h < 3000.0, "{w} x {h} px");
    let coords: Vec<f64> = in_class(&doc, "path-adapted", "polyline")
        .iter()
        .flat_map(|p| points(p))
        .flat_map(|p| [p.0, p.1])
        .collect();
    let fractional = coords.iter().filter(|v| v.fract() != 0.0).count();
    assert!(
        fractional > coords.len() / 2,
        "{fractional} of {} coordinates off the whole pixel",
        coords.len()
    );
    assert!(coords.iter().all(|v| (v * f64::from(SCALE)).fract() == 0.0), "on the 1/{SCALE} pixel grid");
    for unit in ["x1 (m)", "x2 (m)", "t (s)"] {
        assert_eq!(count_text(&svg, unit), 1, "{unit}");
    }
    assert!(
        texts(&svg)
            .iter()
            .all(|t| t != "-0" && !t.starts_with("-0.0") || t.parse::<f64>().is_ok_and(|v| v != 0.0))
    );
}
