//! What a run was to keep: the jerk panel of every figure, the limit lines of a run with limits (and none without),
//! the profile named in the legend, and the safety margin outlined around the true shapes.

use dmp::Trajectory;

use super::{bump, check_common, dump, ellipse, groups, in_class, parse, points, texts};
use crate::{PlotInput, PoseTrace, Safety, Solid, SolidShape, render_svg, render_svg_with};

/// A 2-D run from (0, 0) to (1, 0) over 1 s at 1 ms, bent up at its middle, with its velocities and accelerations.
fn bent() -> Trajectory {
    let pi = std::f64::consts::PI;
    let mut tr = Trajectory::with_capacity(2, 1001);
    for k in 0..=1000 {
        let s = k as f64 / 1000.0;
        let (x, v, a) = (0.3 * bump(s), 0.3 * pi * (pi * s).cos(), -0.3 * pi * pi * bump(s));
        tr.push(s, &[s, x], &[1.0, v], &[0.0, a]);
    }
    tr
}

fn input<'a>(adapted: &'a Trajectory, solids: &'a [Solid], obstacles: &'a [dmp::Obstacle]) -> PlotInput<'a> {
    PlotInput {
        title: "limits",
        demonstration: &[],
        demonstration_t: None,
        free: adapted,
        adapted,
        goal: None,
        obstacles,
        robots: &[],
        obstacle_time: f64::NAN,
        solids,
        method: "dynamic_volumetric",
        clearance: None,
        events: &[],
        pose: None,
    }
}

/// The server's default profile: speed, acceleration and a jerk limit far above the run's jerk; no angular limit.
fn profile() -> Safety {
    Safety {
        max_speed: 1.7,
        max_acceleration: 5.0,
        max_jerk: 6500.0,
        profile: "server default".into(),
        ..Safety::default()
    }
}

/// The `data-limit` of the limit lines in the strip's panel of class `class`.
fn limits_in(svg: &str, class: &str) -> Vec<String> {
    let doc = parse(svg);
    groups(&doc, class)
        .iter()
        .flat_map(|g| {
            g.descendants()
                .filter(|n| n.has_tag_name("g") && n.attribute("class") == Some("limit"))
                .map(|n| n.attribute("data-limit").unwrap_or("").to_string())
                .collect::<Vec<_>>()
        })
        .collect()
}

#[test]
fn a_figure_with_limits_draws_them_beside_a_jerk_panel_and_names_the_profile() {
    let run = bent();
    let svg = render_svg_with(&input(&run, &[], &[]), &profile()).unwrap();
    dump("limits_2d", &svg);
    check_common(&svg);
    let doc = parse(&svg);
    // The jerk panel, with the run's jerk as the third difference of its positions (about 0.3 pi³ = 9.3 m/s³).
    assert_eq!(groups(&doc, "jerk").len(), 1);
    assert!(texts(&svg).iter().any(|t| t == "jerk (m/s³)"));
    let jerk = in_class(&doc, "jerk", "polyline");
    assert!(!jerk.is_empty(), "the jerk is drawn");
    // A line at each limit, on its panel; the jerk limit, far above the run's, said in words at the top.
    assert_eq!(limits_in(&svg, "speed"), ["1.7"]);
    assert_eq!(limits_in(&svg, "acceleration"), ["5"]);
    assert_eq!(limits_in(&svg, "jerk"), ["6500"]);
    assert!(in_class(&doc, "limit", "polyline").len() == 2, "speed and acceleration drawn to scale");
    assert!(texts(&svg).iter().any(|t| t == "limit 1.7 m/s"), "{:?}", texts(&svg));
    assert!(texts(&svg).iter().any(|t| t.starts_with("limit 6500 m/s³") && t.contains("off scale")));
    assert!(limits_in(&svg, "clearance").is_empty());
    // The profile in the legend.
    let legend: Vec<String> = groups(&doc, "legend-limits")
        .iter()
        .flat_map(|g| g.descendants().filter(|n| n.has_tag_name("text")).filter_map(|n| n.text()))
        .map(|t| t.trim().to_string())
        .filter(|t| !t.is_empty())
        .collect();
    assert_eq!(legend, ["limits: server default"]);
    // An unlimited field has no line; a jerk limit near the run's jerk is drawn to scale.
    let tight = Safety { max_acceleration: 0.0, max_jerk: 12.0, ..profile() };
    let svg = render_svg_with(&input(&run, &[], &[]), &tight).unwrap();
    assert!(limits_in(&svg, "acceleration").is_empty());
    assert_eq!(limits_in(&svg, "jerk"), ["12"]);
    let doc = parse(&svg);
    let line = groups(&doc, "jerk")[0]
        .descendants()
        .filter(|n| n.has_tag_name("g") && n.attribute("class") == Some("limit"))
        .flat_map(|g| g.descendants().filter(|n| n.has_tag_name("polyline")).collect::<Vec<_>>())
        .count();
    assert_eq!(line, 1, "the jerk limit drawn as a line");
}

#[test]
fn a_figure_without_limits_has_a_jerk_panel_and_no_limit_line() {
    let run = bent();
    for svg in [
        render_svg(&input(&run, &[], &[])).unwrap(),
        // Limits of older data: all unlimited, no profile.
        render_svg_with(&input(&run, &[], &[]), &Safety::default()).unwrap(),
    ] {
        check_common(&svg);
        let doc = parse(&svg);
        assert!(!in_class(&doc, "jerk", "polyline").is_empty());
        assert!(groups(&doc, "limit").is_empty() && groups(&doc, "legend-limits").is_empty());
        assert!(!svg.contains("limit "), "no limit label");
        assert!(in_class(&doc, "margin", "polyline").is_empty() && groups(&doc, "legend-margin").is_empty());
    }
}

#[test]
fn a_margin_is_outlined_that_far_around_the_true_shape() {
    let run = bent();
    // A box of half-sides 0.1 x 0.05 at (0.5, 0.45), planned as an ellipse inflated around it.
    let solids = [Solid::new("box", SolidShape::Box { half: vec![0.1, 0.05] }, vec![0.5, 0.45])];
    let obstacles = [ellipse("box", vec![0.5, 0.45], vec![0.2, 0.1], None)];
    // The run's margin is 2 cm, the box's own 5 cm: the box keeps 5 cm.
    let safety = Safety { margin: 0.02, obstacle_margins: vec![("box".into(), 0.05)], ..Safety::default() };
    let svg = render_svg_with(&input(&run, &solids, &obstacles), &safety).unwrap();
    dump("margin_2d", &svg);
    check_common(&svg);
    let doc = parse(&svg);
    let margin = in_class(&doc, "margin", "polyline");
    assert_eq!(margin.len(), 1);
    assert!(margin[0].attribute("stroke-dasharray").is_some(), "dashed");
    let truth = points(&in_class(&doc, "obstacle-true", "polygon")[0]);
    let grown = points(&margin[0]);
    let width = |p: &[(f64, f64)]| {
        let (lo, hi) = p.iter().fold((f64::MAX, f64::MIN), |(a, b), q| (a.min(q.0), b.max(q.0)));
        hi - lo
    };
    // 0.2 m wide, 0.3 m with the margin: the same scale on screen.
    let ratio = width(&grown) / width(&truth);
    assert!((ratio - 1.5).abs() < 0.02, "margin outline {ratio} times the box's width");
    assert!(texts(&svg).iter().any(|t| t == "safety margin 0.05 m"), "{:?}", texts(&svg));
    // Without a margin, no outline.
    let svg = render_svg_with(&input(&run, &solids, &obstacles), &profile()).unwrap();
    assert!(in_class(&parse(&svg), "margin", "polyline").is_empty());
}

#[test]
fn a_pose_run_has_angular_panels_with_their_limits() {
    let path = super::traj(3, 1001, |s| vec![0.2 * s, 0.0, 1.0 - 0.5 * s]);
    let (turned, held): (Vec<[f64; 4]>, Vec<[f64; 4]>) = (0..1001)
        .map(|k| {
            let a = 0.25 * std::f64::consts::PI * (1.0 - (std::f64::consts::PI * k as f64 / 1000.0).cos());
            ([0.0, 0.0, (a / 2.0).sin(), (a / 2.0).cos()], [0.0, 0.0, 0.0, 1.0])
        })
        .unzip();
    let pose = PoseTrace { orientations: &turned, free_orientations: &held, tool_surface: &[] };
    let obstacles = [ellipse("peg", vec![0.1, 0.05, 0.75], vec![0.03, 0.03, 0.1], None)];
    let plot = PlotInput { pose: Some(pose), ..input(&path, &[], &obstacles) };
    let safety = Safety { max_angular_speed: 2.5, max_angular_jerk: 60.0, margin: 0.03, ..profile() };
    let svg = render_svg_with(&plot, &safety).unwrap();
    dump("limits_pose", &svg);
    check_common(&svg);
    let doc = parse(&svg);
    for class in ["angular-speed", "angular-acceleration", "angular-jerk", "orientation"] {
        assert!(!in_class(&doc, class, "polyline").is_empty(), "{class}");
    }
    assert_eq!(limits_in(&svg, "angular-speed"), ["2.5"]);
    assert!(limits_in(&svg, "angular-acceleration").is_empty());
    assert_eq!(limits_in(&svg, "angular-jerk"), ["60"]);
    for unit in ["ang. speed (rad/s)", "ang. jerk (rad/s³)"] {
        assert!(texts(&svg).iter().any(|t| t == unit), "{unit}");
    }
    // The peg keeps the run's margin, in each of the three projections.
    assert_eq!(in_class(&doc, "margin", "polyline").len(), 3);
}
