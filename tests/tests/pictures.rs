//! The figures of `dmpctl scenario run` (the same library): what each must show, found by the classes of its SVG
//! groups. The paper's runs that touch an obstacle have their contacts marked; the legend tells the obstacle-free
//! run from the adapted one and never calls a run without avoidance one with; moving obstacles and robots are
//! drawn at marked times.

use std::path::{Path, PathBuf};

use dmpctl::offline::run_scenario;

fn scenarios() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios")
}

/// Runs the scenario and returns its `plot.svg`.
fn figure(file: &str) -> String {
    let out = tempfile::tempdir().unwrap();
    let path = scenarios().join(file);
    run_scenario(&path, out.path()).unwrap_or_else(|e| panic!("{file}: {e}"));
    std::fs::read_to_string(out.path().join("plot.svg")).unwrap()
}

/// The elements named `tag` under the groups of class `class`.
fn count(doc: &roxmltree::Document<'_>, class: &str, tag: &str) -> usize {
    doc.descendants()
        .filter(|n| n.attribute("class") == Some(class))
        .flat_map(|g| g.descendants().filter(|n| n.has_tag_name(tag)).collect::<Vec<_>>())
        .count()
}

/// The legend texts of class `class`.
fn legend(doc: &roxmltree::Document<'_>, class: &str) -> Vec<String> {
    doc.descendants()
        .filter(|n| n.attribute("class") == Some(class))
        .flat_map(|g| {
            g.descendants().filter(|n| n.has_tag_name("text")).filter_map(|n| n.text()).collect::<Vec<_>>()
        })
        .map(|t| t.trim().to_string())
        .collect()
}

#[test]
fn the_steering_angle_run_touches_an_obstacle_and_shows_where() {
    let svg = figure("paper-two-obstacles-steering-angle.json");
    let doc = roxmltree::Document::parse(&svg).unwrap();
    assert!(count(&doc, "contact", "polyline") >= 1, "no contact marked");
    assert_eq!(legend(&doc, "legend-adapted"), ["with avoidance: steering angle"]);
    assert_eq!(legend(&doc, "legend-free"), ["obstacle-free DMP"]);
    assert_eq!(count(&doc, "obstacle-true", "polygon"), 2, "both ellipses");
    for class in ["speed", "acceleration", "clearance"] {
        assert!(count(&doc, class, "polyline") >= 1, "{class}");
    }
}

#[test]
fn the_run_without_avoidance_is_labelled_as_such_and_its_contact_marked() {
    let svg = figure("paper-one-obstacle/none.json");
    let doc = roxmltree::Document::parse(&svg).unwrap();
    assert_eq!(legend(&doc, "legend-adapted"), ["run without avoidance (none)"]);
    assert!(!svg.contains("with avoidance"));
    assert!(count(&doc, "contact", "polyline") >= 1, "no contact marked");
    // The same experiment with the paper's method goes round the ellipse: nothing marked.
    let svg = figure("paper-one-obstacle/dynamic_volumetric.json");
    let doc = roxmltree::Document::parse(&svg).unwrap();
    assert_eq!(count(&doc, "contact", "polyline"), 0);
    assert_eq!(legend(&doc, "legend-adapted"), ["with avoidance: dynamic volumetric"]);
}

#[test]
fn moving_obstacles_and_robots_are_drawn_at_marked_times() {
    let svg = figure("moving-obstacle-dynamic-volumetric.json");
    let doc = roxmltree::Document::parse(&svg).unwrap();
    assert_eq!(count(&doc, "obstacle-true", "polygon"), 5, "the obstacle at five times");
    assert_eq!(count(&doc, "time-mark", "circle"), 5, "the path ticked at the same times");
    let svg = figure("youbots-three-dynamic.json");
    let doc = roxmltree::Document::parse(&svg).unwrap();
    assert_eq!(count(&doc, "time-mark", "circle"), 3 * 5, "each robot ticked at five times");
    assert!(count(&doc, "footprint", "polyline") >= 3 * 5, "each robot's footprint at five times");
}
