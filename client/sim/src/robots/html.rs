//! `report.html`: one self-contained page per simulation, next to `report.json`. The figures inline (SVG), the table
//! of clearances and limits, and pass or fail per check; no script, no external URL, so it opens in any browser
//! from the disk.

use std::fmt::Write as _;
use std::path::Path;

use super::report::{CartesianLimits, RobotReport, SimReport};
use crate::error::SimError;

const STYLE: &str = "body{font-family:sans-serif;margin:2em;color:#222}\
table{border-collapse:collapse;margin:1em 0}\
th,td{border:1px solid #ccc;padding:.3em .6em;text-align:right}\
th{background:#f3f3f3}td.name,th.name{text-align:left}\
.pass{color:#176b1c;font-weight:bold}.fail{color:#b00020;font-weight:bold}\
figure{margin:1.5em 0}figure svg{max-width:100%;height:auto}figcaption{font-weight:bold;margin:.3em 0}small{font-weight:normal;color:#555}";

/// Text as HTML.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

fn verdict(ok: bool) -> &'static str {
    if ok { "<td class=\"pass\">pass</td>" } else { "<td class=\"fail\">fail</td>" }
}

/// A check: what, whether it passed, the figure behind it.
type Check = (&'static str, bool, String);

/// The checks of one robot.
fn checks(r: &RobotReport, realtime: bool, limits: Option<&CartesianLimits>) -> Vec<Check> {
    let mut c = vec![
        ("goal reached", r.reached_goal, format!("{:.4} m away, {}", r.final_error_m, r.final_status)),
        (
            "no contact",
            r.collisions.is_empty(),
            if r.collisions.is_empty() { "none".into() } else { r.collisions.join(", ") },
        ),
        (
            "continuous setpoints",
            r.discontinuities == 0,
            format!("{} discontinuous steps", r.discontinuities),
        ),
        ("finite values", r.non_finite == 0, format!("{} non-finite", r.non_finite)),
        ("setpoints", r.setpoints > 0, format!("{} in {} segments", r.setpoints, r.segments)),
    ];
    if realtime {
        let splices = if r.late_splices > 0 {
            format!(", {} jumps to late segments", r.late_splices)
        } else {
            String::new()
        };
        c.push(("on time", r.late_setpoints == 0, format!("{} late{splices}", r.late_setpoints)));
    }
    if let Some(l) = limits {
        c.push(("speed limit", r.peak_speed <= l.speed, format!("{:.3} ≤ {} m/s", r.peak_speed, l.speed)));
        c.push((
            "acceleration limit",
            r.peak_acceleration <= l.acceleration,
            format!("{:.3} ≤ {} m/s²", r.peak_acceleration, l.acceleration),
        ));
        c.push(("jerk limit", r.peak_jerk <= l.jerk, format!("{:.1} ≤ {} m/s³", r.peak_jerk, l.jerk)));
    }
    if let Some(p) = &r.pose {
        c.push((
            "goal orientation",
            p.final_orientation_error_deg <= super::pose::ORIENTATION_TOLERANCE_DEG,
            format!("{:.4}° from it", p.final_orientation_error_deg),
        ));
        c.push((
            "angular limits",
            p.angular_limit_violations == 0,
            format!(
                "peaks {:.3} rad/s, {:.2} rad/s², {:.0} rad/s³; {} setpoints over",
                p.peak_angular_speed,
                p.peak_angular_acceleration,
                p.peak_angular_jerk,
                p.angular_limit_violations
            ),
        ));
        c.push((
            "clearance of the true shape",
            p.min_body_clearance_m > 0.0,
            format!("{:.4} m ({})", p.min_body_clearance_m, p.body),
        ));
    }
    c
}

/// The page of `report`, with the figures read from `dir`.
pub(crate) fn render_html(report: &SimReport, dir: &Path) -> Result<String, SimError> {
    let limits = report.limits.as_ref();
    let all: Vec<(String, Vec<Check>)> =
        report.robots.iter().map(|(id, r)| (id.clone(), checks(r, report.realtime, limits))).collect();
    let passed = all.iter().all(|(_, c)| c.iter().all(|x| x.1));
    let mut h = String::new();
    let title = format!("Simulation {}", report.sim);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n",
        esc(&title)
    );
    let _ = writeln!(
        h,
        "<h1>{}</h1>\n<p id=\"verdict\" class=\"{}\">{}</p>\n<p>{}</p>",
        esc(&title),
        if passed { "pass" } else { "fail" },
        if passed { "every check passed" } else { "some checks failed" },
        if report.realtime { "paced on the wall clock" } else { "simulated clock" }
    );
    h.push_str("<h2>Checks</h2>\n<table id=\"checks\">\n<tr><th class=\"name\">robot</th>");
    for (what, _, _) in all.first().map(|(_, c)| c.as_slice()).unwrap_or_default() {
        let _ = write!(h, "<th>{what}</th>");
    }
    h.push_str("</tr>\n");
    for (id, cs) in &all {
        let _ = write!(h, "<tr><td class=\"name\">{}</td>", esc(id));
        for (_, ok, detail) in cs {
            let (class, word) = if *ok { ("pass", "pass") } else { ("fail", "fail") };
            let _ = write!(h, "<td class=\"{class}\">{word}<br><small>{}</small></td>", esc(detail));
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table>\n");
    clearance_table(&mut h, report);
    limits_table(&mut h, report);
    pose_table(&mut h, report);
    h.push_str("<h2>Figures</h2>\n");
    for plot in &report.plots {
        let path = dir.join(plot);
        let svg = std::fs::read_to_string(&path).map_err(|source| SimError::Io { path, source })?;
        let _ = writeln!(h, "<figure>\n<figcaption>{}</figcaption>\n{}</figure>", esc(plot), svg.trim());
    }
    if !report.notes.is_empty() {
        h.push_str("<h2>Set-up</h2>\n<ul>\n");
        for n in &report.notes {
            let _ = writeln!(h, "<li>{}</li>", esc(n));
        }
        h.push_str("</ul>\n");
    }
    h.push_str("</body>\n</html>\n");
    Ok(h)
}

/// Smallest clearance of each robot to each obstacle or robot (0: a contact).
fn clearance_table(h: &mut String, report: &SimReport) {
    h.push_str("<h2>Clearances</h2>\n<table id=\"clearances\">\n<tr><th class=\"name\">robot</th><th class=\"name\">to</th><th>smallest clearance (m)</th><th>result</th></tr>\n");
    for (id, r) in &report.robots {
        for (o, d) in &r.min_clearance_m {
            let shown = if d.is_finite() { format!("{d:.4}") } else { "never present".into() };
            let _ = writeln!(
                h,
                "<tr><td class=\"name\">{}</td><td class=\"name\">{}</td><td>{shown}</td>{}</tr>",
                esc(id),
                esc(o),
                verdict(*d > 0.0)
            );
        }
    }
    h.push_str("</table>\n");
}

/// Peaks of each robot against the limits, where the simulation has them.
fn limits_table(h: &mut String, report: &SimReport) {
    let l = report.limits.as_ref();
    let limit = |v: Option<f64>| v.map_or("none".to_string(), |v| format!("{v}"));
    let _ = writeln!(
        h,
        "<h2>Peaks and limits</h2>\n<table id=\"limits\">\n<tr><th class=\"name\">robot</th><th>speed (m/s)</th><th>acceleration (m/s²)</th><th>jerk (m/s³)</th><th>duration (s)</th></tr>\n<tr><td class=\"name\">limit</td><td>{}</td><td>{}</td><td>{}</td><td></td></tr>",
        limit(l.map(|l| l.speed)),
        limit(l.map(|l| l.acceleration)),
        limit(l.map(|l| l.jerk))
    );
    for (id, r) in &report.robots {
        let _ = writeln!(
            h,
            "<tr><td class=\"name\">{}</td><td>{:.3}</td><td>{:.3}</td><td>{:.1}</td><td>{:.3}</td></tr>",
            esc(id),
            r.peak_speed,
            r.peak_acceleration,
            r.peak_jerk,
            r.duration_s
        );
    }
    h.push_str("</table>\n");
}

/// The orientation of each pose robot: its goal angle, angular peaks (finite differences) against its profile,
/// and the clearance of its true shape.
fn pose_table(h: &mut String, report: &SimReport) {
    let poses: Vec<_> =
        report.robots.iter().filter_map(|(id, r)| r.pose.as_ref().map(|p| (id, r, p))).collect();
    if poses.is_empty() {
        return;
    }
    h.push_str(
        "<h2>Orientation</h2>\n<table id=\"orientation\">\n<tr><th class=\"name\">robot</th><th>goal error (°)</th>\
         <th>largest turn (°)</th><th>angular speed (rad/s)</th><th>angular acceleration (rad/s²)</th>\
         <th>angular jerk (rad/s³)</th><th>over the limits</th><th>clearance (m)</th><th class=\"name\">shape</th></tr>\n",
    );
    for (id, r, p) in poses {
        let limit = |v: Option<f64>| v.filter(|v| *v > 0.0).map_or(String::new(), |v| format!(" ≤ {v}"));
        let _ = writeln!(
            h,
            "<tr><td class=\"name\">{}</td><td>{:.4}</td><td>{:.1}</td><td>{:.3}{}</td><td>{:.2}{}</td><td>{:.0}{}</td>\
             <td>{}</td><td>{:.4}</td><td class=\"name\">{}</td></tr>",
            esc(id),
            p.final_orientation_error_deg,
            p.max_turn_from_start_deg,
            p.peak_angular_speed,
            limit(r.profile.map(|l| l.max_angular_speed)),
            p.peak_angular_acceleration,
            limit(r.profile.map(|l| l.max_angular_acceleration)),
            p.peak_angular_jerk,
            limit(r.profile.map(|l| l.max_angular_jerk)),
            p.angular_limit_violations,
            p.min_body_clearance_m,
            esc(&p.body)
        );
    }
    h.push_str("</table>\n");
}

/// Writes `dir/report.html` (the figures of `report` must be in `dir` already).
pub(crate) fn write_html(report: &SimReport, dir: &Path) -> Result<(), SimError> {
    let page = render_html(report, dir)?;
    let path = dir.join("report.html");
    std::fs::write(&path, page).map_err(|source| SimError::Io { path, source })
}
