//! A pose run's figure: the held tool outlined along the path at the marked times, and its rotation over time in
//! a panel of the strip.

use super::{check_common, ellipse, groups, in_class, parse, texts, traj};
use crate::{PlotError, PlotInput, PoseTrace, render_svg};

/// A bar (0.6 m along its x axis, 2 cm square) turning a quarter turn about z while its middle goes from (0, 0, 1) to (0, 0, -1).
fn bar_surface() -> Vec<[f64; 3]> {
    let corners = [[-0.01, -0.01], [-0.01, 0.01], [0.01, -0.01], [0.01, 0.01]];
    [-0.3, 0.3].iter().flat_map(|&x| corners.map(|[y, z]| [x, y, z])).collect()
}

fn turning(rows: usize, turn: f64) -> Vec<[f64; 4]> {
    (0..rows)
        .map(|k| {
            let a = 0.5 * turn * k as f64 / (rows - 1) as f64;
            [0.0, 0.0, a.sin(), a.cos()]
        })
        .collect()
}

#[test]
fn a_held_tool_is_outlined_along_the_path_and_its_rotation_has_a_panel() {
    let path = traj(3, 301, |s| vec![0.0, 0.0, 1.0 - 2.0 * s]);
    let obstacles = [ellipse("peg", vec![0.0, 0.2, 0.0], vec![0.05, 0.05, 0.2], None)];
    let (turned, held, surface) =
        (turning(301, std::f64::consts::FRAC_PI_2), turning(301, 0.0), bar_surface());
    let pose = PoseTrace { orientations: &turned, free_orientations: &held, tool_surface: &surface };
    let input = PlotInput {
        title: "bar",
        demonstration: &[],
        demonstration_t: None,
        free: &path,
        adapted: &path,
        goal: None,
        obstacles: &obstacles,
        robots: &[],
        obstacle_time: f64::NAN,
        solids: &[],
        method: "static_volumetric",
        clearance: None,
        events: &[],
        pose: Some(pose),
    };
    let svg = render_svg(&input).unwrap();
    check_common(&svg);
    let doc = parse(&svg);
    // The tool at every marked time, in each of the three projections.
    let outlines =
        in_class(&doc, "footprint", "polygon").len() + in_class(&doc, "footprint", "polyline").len();
    assert!(outlines >= 3 * 4, "the tool is outlined at the marked times: {outlines}");
    assert!(texts(&svg).iter().any(|t| t == "tool at t (s)"), "the legend names the outlines");
    let strip = groups(&doc, "orientation");
    assert_eq!(strip.len(), 1, "a panel of the strip for the rotation");
    assert!(texts(&svg).iter().any(|t| t == "turn from start (°)"));
    // A mismatched orientation list is refused, naming it.
    let short = turning(10, 0.0);
    let err = render_svg(&PlotInput { pose: Some(PoseTrace { orientations: &short, ..pose }), ..input })
        .unwrap_err();
    assert!(matches!(err, PlotError::Length { .. }), "{err}");
}
