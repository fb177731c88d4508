//! SVG figures of a scenario run, in the style of the paper's plots: the demonstration (dashed), the obstacle-free
//! DMP (dashed), the trajectory adapted by the avoidance (solid) and the obstacles' outlines.
//!
//! - Robots moving in 2-D: one panel `x1`-`x2` with an equal aspect ratio (an ellipse looks like an ellipse).
//! - Robots moving in 3-D: three panels, the projections on `x1`-`x2`, `x1`-`x3` and `x2`-`x3`, each with an equal
//!   aspect ratio; an obstacle is drawn as the convex hull of its projected surface samples.
//! - Anything else (1-D, more than 3-D): each coordinate against time, one panel per DMP dimension (at most
//!   [`MAX_TIME_PANELS`]); an obstacle shows as the band its extent along that coordinate sweeps.
//!
//! With several robots (each owning some dimensions of one DMP), every robot's path has its own colour in the shared
//! robot-space panel(s), the obstacles are drawn once, and each robot's footprint is outlined where it is at
//! [`PlotInput::obstacle_time`].
//!
//! Rendering uses plotters' SVG backend without its `ttf` feature: text is emitted as SVG `<text>` elements that the
//! viewer lays out (plotters only estimates their width for spacing), so no font library is needed. Text that fails to
//! draw is dropped rather than failing the figure.

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use dmp::{Agent, Obstacle, Shape, Trajectory};

/// Longest polyline drawn per curve: longer trajectories are decimated (every k-th row, plus the last).
pub const MAX_POINTS: usize = 2000;
/// Most panels of a plot against time; further dimensions are left out (the legend says so).
pub const MAX_TIME_PANELS: usize = 6;
/// Boundary samples of a 2-D outline (in order around the obstacle).
const OUTLINE_SAMPLES_2D: usize = 200;
/// Boundary samples of a 3-D (or higher) obstacle, before projection and convex hull / extent.
const OUTLINE_SAMPLES_ND: usize = 2000;

const FONT: &str = "sans-serif";
const TITLE_H: u32 = 40;
const LEGEND_W: u32 = 300;
const LEGEND_ROW: i32 = 24;
const PANEL_MARGIN: u32 = 12;
const X_LABEL_AREA: u32 = 44;
const Y_LABEL_AREA: u32 = 64;
const CAPTION_H: u32 = 28;
/// Smallest distance on screen, in pixels, between consecutive drawn points of a curve.
const MIN_PIXEL_STEP: i64 = 3;
/// Margin around the data in geometric panels, as a fraction of the larger data span.
const MARGIN_FRAC: f64 = 0.06;

const DEMO: RGBColor = RGBColor(110, 110, 110);
const FREE: RGBColor = RGBColor(31, 119, 180);
const ADAPTED: RGBColor = RGBColor(214, 39, 40);
const OBSTACLE_FILL: RGBColor = RGBColor(150, 150, 150);
const OBSTACLE_EDGE: RGBColor = RGBColor(50, 50, 50);
const GHOST: RGBColor = RGBColor(120, 120, 120);
const MARKER: RGBColor = RGBColor(0, 0, 0);
/// Robot colours (matplotlib's tab10 without its grey, which the demonstration uses).
const PALETTE: [RGBColor; 9] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// What to draw.
#[derive(Debug, Clone, Copy)]
pub struct PlotInput<'a> {
    /// Figure title.
    pub title: &'a str,
    /// The demonstration's positions, a row per sample, `d` columns (the full DMP dimension). Its times are not
    /// known here: in plots against time it is spread evenly over the obstacle-free rollout's time span.
    pub demonstration: &'a [Vec<f64>],
    /// The obstacle-free rollout; its first row is drawn as the start, its last row as the goal.
    pub free: &'a Trajectory,
    /// The rollout with avoidance.
    pub adapted: &'a Trajectory,
    /// Obstacles in robot space (each of a robot's dimension).
    pub obstacles: &'a [Obstacle],
    /// Robots sharing the DMP; empty for one robot owning every dimension.
    pub robots: &'a [Agent],
    /// Time at which moving obstacles (and robot footprints) are drawn; moving obstacles are also outlined faintly
    /// at the start and at the end of the run.
    pub obstacle_time: f64,
}

/// Why a figure could not be drawn.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// Something has the wrong number of dimensions.
    #[error("{what} has {found} dimensions, expected {expected}")]
    Dimension {
        /// What.
        what: String,
        /// Expected dimension.
        expected: usize,
        /// Its dimension.
        found: usize,
    },
    /// A trajectory without rows.
    #[error("the {0} trajectory is empty")]
    EmptyTrajectory(&'static str),
    /// An inconsistent robot.
    #[error("robots[{index}]: {reason}")]
    Robot {
        /// Index in [`PlotInput::robots`].
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// The backend failed.
    #[error("drawing the SVG failed: {0}")]
    Drawing(String),
}

/// Renders the figure as a standalone SVG document. Deterministic: the same input gives the same bytes.
pub fn render_svg(input: &PlotInput<'_>) -> Result<String, PlotError> {
    let d = validate(input)?;
    let groups = groups(input, d)?;
    let sub = groups[0].dims.len();
    for o in input.obstacles {
        if o.dim() != sub {
            return Err(PlotError::Dimension {
                what: format!("obstacle `{}`", o.id()),
                expected: sub,
                found: o.dim(),
            });
        }
    }
    let run = Run::new(input, groups);
    match sub {
        2 | 3 => render_geometric(input, &run),
        _ => render_time(input, &run, d),
    }
}

// ------------------------------------------------------------------------------------------------------------------
// Input checks and extraction.

fn validate(input: &PlotInput<'_>) -> Result<usize, PlotError> {
    if input.adapted.is_empty() {
        return Err(PlotError::EmptyTrajectory("adapted"));
    }
    let d = input.adapted.dim();
    if d == 0 {
        return Err(PlotError::Dimension { what: "the adapted trajectory".into(), expected: 1, found: 0 });
    }
    if input.free.dim() != d {
        return Err(PlotError::Dimension {
            what: "the obstacle-free trajectory".into(),
            expected: d,
            found: input.free.dim(),
        });
    }
    for (k, row) in input.demonstration.iter().enumerate() {
        if row.len() != d {
            return Err(PlotError::Dimension {
                what: format!("demonstration row {k}"),
                expected: d,
                found: row.len(),
            });
        }
    }
    Ok(d)
}

/// A robot: the DMP dimensions it owns and how it is drawn.
#[derive(Debug)]
struct Group<'a> {
    label: String,
    dims: Vec<usize>,
    color: RGBColor,
    footprint: Option<&'a Shape>,
}

fn groups<'a>(input: &PlotInput<'a>, d: usize) -> Result<Vec<Group<'a>>, PlotError> {
    if input.robots.is_empty() {
        return Ok(vec![Group {
            label: "robot".into(),
            dims: (0..d).collect(),
            color: ADAPTED,
            footprint: None,
        }]);
    }
    let sub = input.robots[0].dims.len();
    for (index, r) in input.robots.iter().enumerate() {
        if r.dims.is_empty() {
            return Err(PlotError::Robot { index, reason: "owns no dimension".into() });
        }
        if r.dims.len() != sub {
            return Err(PlotError::Robot {
                index,
                reason: format!("owns {} dimensions, robots[0] owns {sub}", r.dims.len()),
            });
        }
        if let Some(k) = r.dims.iter().find(|&&k| k >= d) {
            return Err(PlotError::Robot {
                index,
                reason: format!("dimension {k} is outside the DMP's {d}"),
            });
        }
    }
    Ok(input
        .robots
        .iter()
        .enumerate()
        .map(|(i, r)| Group {
            label: r.id.clone(),
            dims: r.dims.clone(),
            color: PALETTE[i % PALETTE.len()],
            footprint: r.footprint.as_ref(),
        })
        .collect())
}

/// Row indices kept when decimating `n` rows to at most about [`MAX_POINTS`]: every k-th row and the last one.
fn decimated(n: usize) -> Vec<usize> {
    if n <= MAX_POINTS {
        return (0..n).collect();
    }
    let stride = (n - 1).div_ceil(MAX_POINTS - 2);
    let mut idx: Vec<usize> = (0..n).step_by(stride).collect();
    if idx.last() != Some(&(n - 1)) {
        idx.push(n - 1);
    }
    idx
}

/// A decimated curve: times and full-dimensional positions.
#[derive(Debug, Default)]
struct Curve {
    t: Vec<f64>,
    x: Vec<Vec<f64>>,
}

impl Curve {
    fn of(tr: &Trajectory) -> Self {
        let idx = decimated(tr.len());
        Self {
            t: idx.iter().map(|&k| tr.t[k]).collect(),
            x: idx.iter().map(|&k| tr.position(k).to_vec()).collect(),
        }
    }

    /// The demonstration, its rows spread evenly over `[t0, t1]`.
    fn spread(rows: &[Vec<f64>], t0: f64, t1: f64) -> Self {
        let idx = decimated(rows.len());
        let n = rows.len().saturating_sub(1).max(1) as f64;
        Self {
            t: idx.iter().map(|&k| t0 + (t1 - t0) * k as f64 / n).collect(),
            x: idx.iter().map(|&k| rows[k].clone()).collect(),
        }
    }

    /// Positions restricted to `dims`, then projected on the local axes `(i, j)`.
    fn plane(&self, dims: &[usize], (i, j): (usize, usize)) -> Vec<P2> {
        self.x.iter().map(|p| (p[dims[i]], p[dims[j]])).collect()
    }

    /// Coordinate `k` against time.
    fn against_time(&self, k: usize) -> Vec<P2> {
        self.t.iter().zip(&self.x).map(|(t, p)| (*t, p[k])).collect()
    }
}

type P2 = (f64, f64);

fn finite(p: &P2) -> bool {
    p.0.is_finite() && p.1.is_finite()
}

/// Surface samples of `o` at time `t`, absolute positions.
fn surface(o: &Obstacle, t: f64, n: usize) -> Vec<Vec<f64>> {
    let d = o.dim();
    let mut c = vec![0.0; d];
    o.center_at(t, &mut c);
    o.boundary_offsets(n).chunks(d).map(|off| off.iter().zip(&c).map(|(a, b)| a + b).collect()).collect()
}

/// Everything extracted from the input, decimated.
#[derive(Debug)]
struct Run<'a> {
    groups: Vec<Group<'a>>,
    demo: Curve,
    free: Curve,
    adapted: Curve,
    start: Vec<f64>,
    goal: Vec<f64>,
    t0: f64,
    t1: f64,
    obstacle_time: f64,
    moving: bool,
}

impl<'a> Run<'a> {
    fn new(input: &PlotInput<'_>, groups: Vec<Group<'a>>) -> Self {
        let reference = if input.free.is_empty() { input.adapted } else { input.free };
        let t0 = reference.t[0];
        let t1 =
            input.free.t.last().copied().unwrap_or(t0).max(input.adapted.t.last().copied().unwrap_or(t0));
        let obstacle_time = if input.obstacle_time.is_finite() { input.obstacle_time } else { t0 };
        Self {
            groups,
            demo: Curve::spread(input.demonstration, t0, reference.t.last().copied().unwrap_or(t0)),
            free: Curve::of(input.free),
            adapted: Curve::of(input.adapted),
            start: reference.position(0).to_vec(),
            goal: reference.position(reference.len() - 1).to_vec(),
            t0,
            t1,
            obstacle_time,
            moving: input.obstacles.iter().any(|o| o.velocity().iter().any(|v| *v != 0.0)),
        }
    }

    fn single(&self) -> bool {
        self.groups.len() == 1
    }

    fn free_stroke(&self, g: &Group<'_>) -> Stroke {
        if self.single() {
            Stroke::dashed(FREE, 2, (10, 6))
        } else {
            Stroke { color: g.color.mix(0.7), width: 2, dash: Some((8, 5)) }
        }
    }

    fn adapted_stroke(&self, g: &Group<'_>) -> Stroke {
        Stroke::solid(if self.single() { ADAPTED } else { g.color }, 2)
    }

    /// Row of the adapted trajectory closest in time to `t`.
    fn adapted_row_at(&self, t: f64) -> usize {
        let k = self.adapted.t.partition_point(|s| *s < t);
        k.min(self.adapted.t.len() - 1)
    }
}

fn fmt_num(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s };
    if s == "-0" { "0".into() } else { s }
}

// ------------------------------------------------------------------------------------------------------------------
// Drawing helpers.

type Area<'b> = DrawingArea<SVGBackend<'b>, Shift>;
type Chart<'c, 'b> = ChartContext<'c, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

fn drawing_err(e: impl std::fmt::Display) -> PlotError {
    PlotError::Drawing(e.to_string())
}

#[derive(Debug, Clone, Copy)]
struct Stroke {
    color: RGBAColor,
    width: u32,
    dash: Option<(u32, u32)>,
}

impl Stroke {
    fn solid(color: RGBColor, width: u32) -> Self {
        Self { color: color.to_rgba(), width, dash: None }
    }

    fn dashed(color: RGBColor, width: u32, dash: (u32, u32)) -> Self {
        Self { color: color.to_rgba(), width, dash: Some(dash) }
    }

    fn style(&self) -> ShapeStyle {
        ShapeStyle { color: self.color, filled: false, stroke_width: self.width }
    }
}

/// Draws `pts` as polylines, broken where a point is not finite.
fn draw_curve(chart: &mut Chart<'_, '_>, pts: &[P2], stroke: Stroke) -> Result<(), PlotError> {
    for seg in pts.split(|p| !finite(p)).filter(|s| s.len() >= 2) {
        let seg = thinned(chart, seg);
        match stroke.dash {
            None => chart.draw_series(LineSeries::new(seg, stroke.style())).map(|_| ()),
            Some((on, off)) => {
                chart.draw_series(DashedLineSeries::new(seg, on, off, stroke.style())).map(|_| ())
            }
        }
        .map_err(drawing_err)?;
    }
    Ok(())
}

/// The points of `seg` at least [`MIN_PIXEL_STEP`] pixels apart on screen (and the last one): the backend rounds to
/// whole pixels, and denser points only draw a jagged line.
fn thinned(chart: &Chart<'_, '_>, seg: &[P2]) -> Vec<P2> {
    let mut out = Vec::with_capacity(seg.len());
    let mut last: Option<(i32, i32)> = None;
    for (k, p) in seg.iter().enumerate() {
        let q = chart.backend_coord(p);
        let far = last.is_none_or(|l| {
            let (dx, dy) = ((q.0 - l.0) as i64, (q.1 - l.1) as i64);
            dx * dx + dy * dy >= MIN_PIXEL_STEP * MIN_PIXEL_STEP
        });
        if far || k + 1 == seg.len() {
            out.push(*p);
            last = Some(q);
        }
    }
    out
}

/// A filled polygon with an outline (closed); non-finite vertices are dropped.
fn draw_patch(
    chart: &mut Chart<'_, '_>,
    poly: &[P2],
    fill: RGBAColor,
    edge: Option<Stroke>,
) -> Result<(), PlotError> {
    let poly: Vec<P2> = poly.iter().copied().filter(finite).collect();
    if poly.len() < 3 {
        return Ok(());
    }
    chart.draw_series(std::iter::once(Polygon::new(poly.clone(), fill.filled()))).map_err(drawing_err)?;
    if let Some(edge) = edge {
        draw_curve(chart, &closed(poly), edge)?;
    }
    Ok(())
}

fn closed(mut poly: Vec<P2>) -> Vec<P2> {
    if let Some(&first) = poly.first() {
        poly.push(first);
    }
    poly
}

/// Text that may fail to draw is dropped: a figure without a label beats no figure.
fn put_text(area: &Area<'_>, text: &str, pos: (i32, i32), size: u32, h: HPos) {
    let style = TextStyle::from((FONT, size).into_font()).color(&BLACK).pos(Pos::new(h, VPos::Center));
    let _ = area.draw(&Text::new(text.to_string(), pos, style));
}

/// Axes, grid, tick labels and axis names; without the text if the text cannot be drawn.
fn draw_mesh(
    chart: &mut Chart<'_, '_>,
    x_desc: &str,
    y_desc: &str,
    x_labels: usize,
    y_labels: usize,
) -> Result<(), PlotError> {
    let labelled = chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_labels(x_labels)
        .y_labels(y_labels)
        .max_light_lines(4)
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 18))
        .light_line_style(RGBColor(242, 242, 242))
        .bold_line_style(RGBColor(218, 218, 218))
        .axis_style(RGBColor(60, 60, 60))
        .draw();
    if labelled.is_ok() {
        return Ok(());
    }
    chart
        .configure_mesh()
        .x_labels(0)
        .y_labels(0)
        .light_line_style(RGBColor(242, 242, 242))
        .axis_style(RGBColor(60, 60, 60))
        .draw()
        .map_err(drawing_err)
}

/// A data range `lo..hi` with nonzero width.
fn padded(lo: f64, hi: f64, frac: f64) -> (f64, f64) {
    if !(lo.is_finite() && hi.is_finite()) || lo > hi {
        return (-1.0, 1.0);
    }
    let span = hi - lo;
    let pad = if span > 0.0 { frac * span } else { 0.1 * lo.abs().max(1.0) };
    (lo - pad, hi + pad)
}

#[derive(Debug, Clone, Copy)]
struct Bounds {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
}

impl Bounds {
    fn new() -> Self {
        Self { x0: f64::INFINITY, x1: f64::NEG_INFINITY, y0: f64::INFINITY, y1: f64::NEG_INFINITY }
    }

    fn add(&mut self, p: P2) {
        if finite(&p) {
            self.x0 = self.x0.min(p.0);
            self.x1 = self.x1.max(p.0);
            self.y0 = self.y0.min(p.1);
            self.y1 = self.y1.max(p.1);
        }
    }

    fn add_all(&mut self, pts: &[P2]) {
        pts.iter().for_each(|p| self.add(*p));
    }

    fn is_empty(&self) -> bool {
        self.x0 > self.x1
    }

    /// The bounds grown by a margin of [`MARGIN_FRAC`] of the larger span on every side: `(x range, y range)`.
    fn with_margin(&self) -> ((f64, f64), (f64, f64)) {
        if self.is_empty() {
            return ((-1.0, 1.0), (-1.0, 1.0));
        }
        let span = (self.x1 - self.x0).max(self.y1 - self.y0);
        let scale = self.x0.abs().max(self.x1.abs()).max(self.y0.abs()).max(self.y1.abs()).max(1e-9);
        let m = if span > 0.0 { MARGIN_FRAC * span } else { 0.1 * scale };
        ((self.x0 - m, self.x1 + m), (self.y0 - m, self.y1 + m))
    }
}

/// Grows the narrower of the two ranges (about its centre) so that one data unit has the same length in pixels on
/// both axes of a `px_w` x `px_h` plotting area.
fn fit_equal_aspect(x: (f64, f64), y: (f64, f64), px_w: f64, px_h: f64) -> ((f64, f64), (f64, f64)) {
    let (mut xs, mut ys) = (x.1 - x.0, y.1 - y.0);
    let (cx, cy) = (0.5 * (x.0 + x.1), 0.5 * (y.0 + y.1));
    let r = px_w.max(1.0) / px_h.max(1.0);
    if xs / ys < r {
        xs = ys * r;
    } else {
        ys = xs / r;
    }
    ((cx - 0.5 * xs, cx + 0.5 * xs), (cy - 0.5 * ys, cy + 0.5 * ys))
}

/// Convex hull (Andrew's monotone chain), counter-clockwise, without repeating the first vertex.
fn convex_hull(mut p: Vec<P2>) -> Vec<P2> {
    p.retain(finite);
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: P2, a: P2, b: P2| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0);
    let mut hull: Vec<P2> = Vec::with_capacity(p.len() + 1);
    for q in p.iter() {
        while hull.len() >= 2 && cross(hull[hull.len() - 2], hull[hull.len() - 1], *q) <= 0.0 {
            hull.pop();
        }
        hull.push(*q);
    }
    let lower = hull.len() + 1;
    for q in p.iter().rev().skip(1) {
        while hull.len() >= lower && cross(hull[hull.len() - 2], hull[hull.len() - 1], *q) <= 0.0 {
            hull.pop();
        }
        hull.push(*q);
    }
    hull.pop();
    hull
}

// ------------------------------------------------------------------------------------------------------------------
// Legend.

#[derive(Debug, Clone, Copy)]
enum Mark {
    Line(Stroke),
    Patch(RGBAColor, Stroke),
    Dot,
    Cross,
}

#[derive(Debug, Clone)]
struct Entry {
    mark: Mark,
    text: String,
}

impl Entry {
    fn new(mark: Mark, text: impl Into<String>) -> Self {
        let text: String = text.into();
        let text = if text.chars().count() > 30 {
            format!("{}…", text.chars().take(29).collect::<String>())
        } else {
            text
        };
        Self { mark, text }
    }
}

fn legend_height(entries: &[Entry], notes: &[String]) -> u32 {
    (24 + LEGEND_ROW * (entries.len() + notes.len()) as i32 + 12) as u32
}

fn draw_legend(area: &Area<'_>, entries: &[Entry], notes: &[String]) -> Result<(), PlotError> {
    let area = area.margin(8, 8, 8, 8);
    let (w, _) = area.dim_in_pixel();
    let h = LEGEND_ROW * (entries.len() + notes.len()) as i32 + 16;
    area.draw(&Rectangle::new(
        [(0, 0), (w as i32 - 1, h)],
        ShapeStyle::from(RGBColor(200, 200, 200)).stroke_width(1),
    ))
    .map_err(drawing_err)?;
    for (k, e) in entries.iter().enumerate() {
        let y = 8 + LEGEND_ROW / 2 + LEGEND_ROW * k as i32;
        let (x0, x1) = (12, 52);
        match e.mark {
            Mark::Line(s) => match s.dash {
                None => area.draw(&PathElement::new(vec![(x0, y), (x1, y)], s.style())),
                Some((on, off)) => {
                    area.draw(&DashedPathElement::new(vec![(x0, y), (x1, y)], on, off, s.style()))
                }
            },
            Mark::Patch(fill, edge) => area
                .draw(&Rectangle::new([(x0 + 4, y - 7), (x1 - 4, y + 7)], fill.filled()))
                .and_then(|_| match edge.dash {
                    None => area.draw(&Rectangle::new([(x0 + 4, y - 7), (x1 - 4, y + 7)], edge.style())),
                    Some((on, off)) => area.draw(&DashedPathElement::new(
                        vec![
                            (x0 + 4, y - 7),
                            (x1 - 4, y - 7),
                            (x1 - 4, y + 7),
                            (x0 + 4, y + 7),
                            (x0 + 4, y - 7),
                        ],
                        on,
                        off,
                        edge.style(),
                    )),
                }),
            Mark::Dot => area.draw(&Circle::new(((x0 + x1) / 2, y), 4, MARKER.filled())),
            Mark::Cross => area.draw(&Cross::new(((x0 + x1) / 2, y), 5, MARKER.stroke_width(2))),
        }
        .map_err(drawing_err)?;
        put_text(&area, &e.text, (x1 + 10, y), 16, HPos::Left);
    }
    for (k, note) in notes.iter().enumerate() {
        let y = 8 + LEGEND_ROW / 2 + LEGEND_ROW * (entries.len() + k) as i32;
        put_text(&area, note, (12, y), 15, HPos::Left);
    }
    Ok(())
}

/// The figure: title band on top, panels in a row or a column, legend on the right.
fn figure(
    title: &str,
    panels: &[(u32, u32)],
    vertical: bool,
    legend: (&[Entry], &[String]),
    mut draw_panel: impl FnMut(usize, &Area<'_>) -> Result<(), PlotError>,
) -> Result<String, PlotError> {
    let (pw, ph) = if vertical {
        (panels.iter().map(|p| p.0).max().unwrap_or(0), panels.iter().map(|p| p.1).sum::<u32>())
    } else {
        (panels.iter().map(|p| p.0).sum::<u32>(), panels.iter().map(|p| p.1).max().unwrap_or(0))
    };
    let size = (pw + LEGEND_W, TITLE_H + ph.max(legend_height(legend.0, legend.1)));
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, size).into_drawing_area();
        root.fill(&WHITE).map_err(drawing_err)?;
        let (top, rest) = root.split_vertically(TITLE_H);
        let (tw, _) = top.dim_in_pixel();
        put_text(&top, title, (tw as i32 / 2, TITLE_H as i32 / 2 + 2), 24, HPos::Center);
        let (panel_area, legend_area) = rest.split_horizontally(pw);
        let mut offset = 0;
        for (k, &(w, h)) in panels.iter().enumerate() {
            let area = if vertical {
                panel_area.clone().shrink((0, offset), (w, h))
            } else {
                panel_area.clone().shrink((offset, 0), (w, h))
            };
            offset += if vertical { h } else { w };
            draw_panel(k, &area)?;
        }
        draw_legend(&legend_area, legend.0, legend.1)?;
        root.present().map_err(drawing_err)?;
    }
    Ok(buf)
}

/// `area` below a caption (the caption is dropped if its text cannot be drawn).
fn captioned<'b>(area: &Area<'b>, caption: Option<&str>) -> Area<'b> {
    match caption {
        None => area.clone(),
        Some(c) => area.titled(c, (FONT, 19)).unwrap_or_else(|_| area.split_vertically(CAPTION_H).1),
    }
}

/// Chart on `area`, built twice: once to measure the plotting area, once with the ranges `fit` gives for its
/// size in pixels.
fn chart_on<'c, 'b>(
    area: &'c Area<'b>,
    fit: impl FnOnce(f64, f64) -> ((f64, f64), (f64, f64)),
) -> Result<Chart<'c, 'b>, PlotError> {
    let mut builder = ChartBuilder::on(area);
    builder.margin(PANEL_MARGIN).x_label_area_size(X_LABEL_AREA).y_label_area_size(Y_LABEL_AREA);
    // Building draws nothing (no caption here), so the builder can be used twice.
    let (pw, ph) =
        builder.build_cartesian_2d(0.0..1.0, 0.0..1.0).map_err(drawing_err)?.plotting_area().dim_in_pixel();
    let (x, y) = fit(pw.saturating_sub(1) as f64, ph.saturating_sub(1) as f64);
    builder.build_cartesian_2d(x.0..x.1, y.0..y.1).map_err(drawing_err)
}

// ------------------------------------------------------------------------------------------------------------------
// Robot space (2-D and 3-D).

/// Outlines of one obstacle, as surface samples in robot space.
#[derive(Debug)]
struct Outlines {
    now: Vec<Vec<f64>>,
    ghosts: Vec<Vec<Vec<f64>>>,
    path: Option<(Vec<f64>, Vec<f64>)>,
}

fn outlines(input: &PlotInput<'_>, run: &Run<'_>, n: usize) -> Vec<Outlines> {
    input
        .obstacles
        .iter()
        .map(|o| {
            let moving = o.velocity().iter().any(|v| *v != 0.0);
            let (mut c0, mut c1) = (vec![0.0; o.dim()], vec![0.0; o.dim()]);
            o.center_at(run.t0, &mut c0);
            o.center_at(run.t1, &mut c1);
            Outlines {
                now: surface(o, run.obstacle_time, n),
                ghosts: if moving { vec![surface(o, run.t0, n), surface(o, run.t1, n)] } else { Vec::new() },
                path: moving.then_some((c0, c1)),
            }
        })
        .collect()
}

/// Footprint outline of each robot at the obstacle time (robots without one: empty).
fn footprints(run: &Run<'_>, n: usize) -> Vec<Vec<Vec<f64>>> {
    let row = run.adapted_row_at(run.obstacle_time);
    run.groups
        .iter()
        .map(|g| match g.footprint {
            Some(shape) if run.groups.len() > 1 => {
                let center: Vec<f64> = g.dims.iter().map(|&k| run.adapted.x[row][k]).collect();
                if center.iter().all(|v| v.is_finite()) {
                    Obstacle::new(&g.label, shape.clone(), center, None, None)
                        .map(|o| surface(&o, 0.0, n))
                        .unwrap_or_default()
                } else {
                    Vec::new()
                }
            }
            _ => Vec::new(),
        })
        .collect()
}

/// Projected outline on local axes `(i, j)`: in 2-D the samples go around in order; in 3-D their convex hull.
fn project_outline(pts: &[Vec<f64>], (i, j): (usize, usize), ordered: bool) -> Vec<P2> {
    let p: Vec<P2> = pts.iter().map(|p| (p[i], p[j])).filter(finite).collect();
    if ordered { p } else { convex_hull(p) }
}

fn render_geometric(input: &PlotInput<'_>, run: &Run<'_>) -> Result<String, PlotError> {
    let sub = run.groups[0].dims.len();
    let ordered = sub == 2;
    let n = if ordered { OUTLINE_SAMPLES_2D } else { OUTLINE_SAMPLES_ND };
    let obstacles = outlines(input, run, n);
    let prints = footprints(run, n);
    let planes: Vec<(usize, usize)> = if sub == 2 { vec![(0, 1)] } else { vec![(0, 1), (0, 2), (1, 2)] };

    // Per plane: everything projected, and the bounds.
    struct Plane {
        axes: (usize, usize),
        demo: Vec<Vec<P2>>,
        free: Vec<Vec<P2>>,
        adapted: Vec<Vec<P2>>,
        starts: Vec<P2>,
        goals: Vec<P2>,
        now: Vec<Vec<P2>>,
        ghosts: Vec<Vec<P2>>,
        paths: Vec<[P2; 2]>,
        prints: Vec<Vec<P2>>,
        ranges: ((f64, f64), (f64, f64)),
    }
    let planes: Vec<Plane> = planes
        .into_iter()
        .map(|axes| {
            let local = |p: &[f64], dims: &[usize]| (p[dims[axes.0]], p[dims[axes.1]]);
            let mut pl = Plane {
                axes,
                demo: run.groups.iter().map(|g| run.demo.plane(&g.dims, axes)).collect(),
                free: run.groups.iter().map(|g| run.free.plane(&g.dims, axes)).collect(),
                adapted: run.groups.iter().map(|g| run.adapted.plane(&g.dims, axes)).collect(),
                starts: run.groups.iter().map(|g| local(&run.start, &g.dims)).collect(),
                goals: run.groups.iter().map(|g| local(&run.goal, &g.dims)).collect(),
                now: obstacles.iter().map(|o| project_outline(&o.now, axes, ordered)).collect(),
                ghosts: obstacles
                    .iter()
                    .flat_map(|o| o.ghosts.iter().map(|g| project_outline(g, axes, ordered)))
                    .collect(),
                paths: obstacles
                    .iter()
                    .filter_map(|o| {
                        o.path.as_ref().map(|(a, b)| [(a[axes.0], a[axes.1]), (b[axes.0], b[axes.1])])
                    })
                    .collect(),
                prints: prints.iter().map(|f| project_outline(f, axes, ordered)).collect(),
                ranges: ((0.0, 1.0), (0.0, 1.0)),
            };
            let mut b = Bounds::new();
            for set in [&pl.demo, &pl.free, &pl.adapted, &pl.now, &pl.ghosts, &pl.prints] {
                set.iter().for_each(|c| b.add_all(c));
            }
            b.add_all(&pl.starts);
            b.add_all(&pl.goals);
            pl.ranges = b.with_margin();
            pl
        })
        .collect();

    // Panel sizes: plotting areas shaped like the data (within limits), then the ranges are fitted exactly.
    let panels: Vec<(u32, u32)> = planes
        .iter()
        .map(|pl| {
            let ((x0, x1), (y0, y1)) = pl.ranges;
            let (w, h) = if sub == 2 {
                let a = ((x1 - x0) / (y1 - y0)).clamp(0.4, 2.5);
                if a >= 1.0 { (620.0, 620.0 / a) } else { (620.0 * a, 620.0) }
            } else {
                let a = ((x1 - x0) / (y1 - y0)).clamp(0.6, 1.8);
                (380.0 * a, 380.0)
            };
            let caption = if sub == 2 { 0 } else { CAPTION_H };
            (
                w.round() as u32 + 2 * PANEL_MARGIN + Y_LABEL_AREA,
                h.round() as u32 + 2 * PANEL_MARGIN + X_LABEL_AREA + caption,
            )
        })
        .collect();

    let mut entries = Vec::new();
    if !input.demonstration.is_empty() {
        entries.push(Entry::new(Mark::Line(demo_stroke()), "demonstration"));
    }
    if run.single() {
        entries.push(Entry::new(Mark::Line(run.free_stroke(&run.groups[0])), "DMP without obstacles"));
        entries.push(Entry::new(Mark::Line(run.adapted_stroke(&run.groups[0])), "DMP with avoidance"));
    } else {
        for g in &run.groups {
            entries.push(Entry::new(Mark::Line(run.adapted_stroke(g)), g.label.clone()));
            entries.push(Entry::new(Mark::Line(run.free_stroke(g)), format!("{}, no obstacles", g.label)));
        }
    }
    if !input.obstacles.is_empty() {
        let text = if run.moving {
            format!("obstacle at t = {}", fmt_num(run.obstacle_time))
        } else {
            "obstacle".into()
        };
        entries.push(Entry::new(Mark::Patch(obstacle_fill(), Stroke::solid(OBSTACLE_EDGE, 1)), text));
        if run.moving {
            entries.push(Entry::new(
                Mark::Patch(TRANSPARENT.to_rgba(), ghost_stroke()),
                format!("at t = {} and t = {}", fmt_num(run.t0), fmt_num(run.t1)),
            ));
        }
    }
    if prints.iter().any(|p| !p.is_empty()) {
        entries.push(Entry::new(
            Mark::Patch(TRANSPARENT.to_rgba(), Stroke::solid(MARKER, 1)),
            format!("footprints at t = {}", fmt_num(run.obstacle_time)),
        ));
    }
    entries.push(Entry::new(Mark::Dot, "start"));
    entries.push(Entry::new(Mark::Cross, "goal"));

    figure(input.title, &panels, false, (&entries, &[]), |k, area| {
        let pl = &planes[k];
        let names = (format!("x{}", pl.axes.0 + 1), format!("x{}", pl.axes.1 + 1));
        let caption = (sub == 3).then(|| format!("{} - {}", names.0, names.1));
        let area = captioned(area, caption.as_deref());
        let mut chart = chart_on(&area, |pw, ph| fit_equal_aspect(pl.ranges.0, pl.ranges.1, pw, ph))?;
        draw_mesh(&mut chart, &names.0, &names.1, 8, 8)?;
        for poly in &pl.now {
            draw_patch(&mut chart, poly, obstacle_fill(), Some(Stroke::solid(OBSTACLE_EDGE, 1)))?;
        }
        for poly in &pl.ghosts {
            draw_curve(&mut chart, &closed(poly.clone()), ghost_stroke())?;
        }
        for path in &pl.paths {
            draw_curve(&mut chart, path, Stroke { color: GHOST.mix(0.6), width: 1, dash: Some((2, 3)) })?;
        }
        for (gi, g) in run.groups.iter().enumerate() {
            if let Some(print) = pl.prints.get(gi).filter(|p| p.len() >= 3) {
                draw_curve(
                    &mut chart,
                    &closed(print.clone()),
                    Stroke { color: g.color.mix(0.9), width: 1, dash: None },
                )?;
            }
        }
        for (gi, g) in run.groups.iter().enumerate() {
            draw_curve(&mut chart, &pl.demo[gi], demo_stroke())?;
            draw_curve(&mut chart, &pl.free[gi], run.free_stroke(g))?;
        }
        for (gi, g) in run.groups.iter().enumerate() {
            draw_curve(&mut chart, &pl.adapted[gi], run.adapted_stroke(g))?;
        }
        for s in pl.starts.iter().filter(|p| finite(p)) {
            chart.draw_series(std::iter::once(Circle::new(*s, 4, MARKER.filled()))).map_err(drawing_err)?;
        }
        for g in pl.goals.iter().filter(|p| finite(p)) {
            chart
                .draw_series(std::iter::once(Cross::new(*g, 5, MARKER.stroke_width(2))))
                .map_err(drawing_err)?;
        }
        Ok(())
    })
}

fn demo_stroke() -> Stroke {
    Stroke::dashed(DEMO, 2, (4, 4))
}

fn ghost_stroke() -> Stroke {
    Stroke { color: GHOST.mix(0.8), width: 1, dash: Some((4, 4)) }
}

fn obstacle_fill() -> RGBAColor {
    OBSTACLE_FILL.mix(0.45)
}

// ------------------------------------------------------------------------------------------------------------------
// Coordinates against time.

fn render_time(input: &PlotInput<'_>, run: &Run<'_>, d: usize) -> Result<String, PlotError> {
    let shown = d.min(MAX_TIME_PANELS);
    // Extent of every obstacle along each local axis, as offsets from its centre.
    let extents: Vec<Vec<(f64, f64)>> = input
        .obstacles
        .iter()
        .map(|o| {
            if o.rotation().is_none() {
                // Axis-aligned: the extent along axis i is exactly the semi-axis.
                return o.shape().semi_axes().iter().map(|a| (-a, *a)).collect();
            }
            let off = o.boundary_offsets(OUTLINE_SAMPLES_ND);
            (0..o.dim())
                .map(|i| {
                    off.iter()
                        .skip(i)
                        .step_by(o.dim())
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(*v), hi.max(*v)))
                })
                .collect()
        })
        .collect();
    let (tx0, tx1) = if run.t1 > run.t0 { (run.t0, run.t1) } else { (run.t0 - 0.5, run.t0 + 0.5) };

    struct Panel {
        j: usize,
        owner: Option<usize>,
        bands: Vec<Vec<P2>>,
        y: (f64, f64),
    }
    let panels_data: Vec<Panel> = (0..shown)
        .map(|j| {
            let owner = run.groups.iter().position(|g| g.dims.contains(&j));
            let bands: Vec<Vec<P2>> = match owner {
                Some(gi) => {
                    let i = run.groups[gi].dims.iter().position(|&k| k == j).unwrap_or(0);
                    input
                        .obstacles
                        .iter()
                        .zip(&extents)
                        .map(|(o, ext)| {
                            let (lo, hi) = ext[i];
                            let c = |t: f64| o.center()[i] + o.velocity()[i] * t;
                            vec![
                                (tx0, c(tx0) + lo),
                                (tx1, c(tx1) + lo),
                                (tx1, c(tx1) + hi),
                                (tx0, c(tx0) + hi),
                            ]
                        })
                        .collect()
                }
                None => Vec::new(),
            };
            let mut b = Bounds::new();
            for c in [&run.demo, &run.free, &run.adapted] {
                b.add_all(&c.against_time(j));
            }
            bands.iter().for_each(|p| b.add_all(p));
            let y = if b.is_empty() { (-1.0, 1.0) } else { padded(b.y0, b.y1, 0.08) };
            Panel { j, owner, bands, y }
        })
        .collect();

    let panels = vec![(840 + 2 * PANEL_MARGIN + Y_LABEL_AREA, 150 + 2 * PANEL_MARGIN + X_LABEL_AREA); shown];
    let mut entries = Vec::new();
    if !input.demonstration.is_empty() {
        entries.push(Entry::new(Mark::Line(demo_stroke()), "demonstration (time rescaled)"));
    }
    if run.single() {
        entries.push(Entry::new(Mark::Line(run.free_stroke(&run.groups[0])), "DMP without obstacles"));
        entries.push(Entry::new(Mark::Line(run.adapted_stroke(&run.groups[0])), "DMP with avoidance"));
    } else {
        for g in &run.groups {
            entries.push(Entry::new(Mark::Line(run.adapted_stroke(g)), g.label.clone()));
            entries.push(Entry::new(Mark::Line(run.free_stroke(g)), format!("{}, no obstacles", g.label)));
        }
    }
    if !input.obstacles.is_empty() {
        entries
            .push(Entry::new(Mark::Patch(band_fill(), Stroke::solid(OBSTACLE_EDGE, 1)), "obstacle extent"));
    }
    let mut notes = Vec::new();
    if d > shown {
        notes.push(format!("showing {shown} of {d} coordinates"));
    }

    figure(input.title, &panels, true, (&entries, &notes), |k, area| {
        let p = &panels_data[k];
        let mut chart = chart_on(area, |_, _| ((tx0, tx1), p.y))?;
        let y_desc = match p.owner {
            Some(gi) if !run.single() => format!("x{} ({})", p.j + 1, run.groups[gi].label),
            _ => format!("x{}", p.j + 1),
        };
        draw_mesh(&mut chart, "t", &y_desc, 10, 5)?;
        for band in &p.bands {
            draw_patch(
                &mut chart,
                band,
                band_fill(),
                Some(Stroke { color: OBSTACLE_EDGE.mix(0.5), width: 1, dash: None }),
            )?;
        }
        let g = p.owner.map(|gi| &run.groups[gi]).unwrap_or(&run.groups[0]);
        draw_curve(&mut chart, &run.demo.against_time(p.j), demo_stroke())?;
        draw_curve(&mut chart, &run.free.against_time(p.j), run.free_stroke(g))?;
        draw_curve(&mut chart, &run.adapted.against_time(p.j), run.adapted_stroke(g))?;
        Ok(())
    })
}

fn band_fill() -> RGBAColor {
    OBSTACLE_FILL.mix(0.3)
}

// ------------------------------------------------------------------------------------------------------------------

#[cfg(test)]
mod tests {
    use super::*;
    use dmp::Superquadric;

    fn ellipse(id: &str, center: Vec<f64>, axes: Vec<f64>, velocity: Option<Vec<f64>>) -> Obstacle {
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
    fn traj(d: usize, rows: usize, f: impl Fn(f64) -> Vec<f64>) -> Trajectory {
        let mut tr = Trajectory::with_capacity(d, rows);
        let zero = vec![0.0; d];
        for k in 0..rows {
            let s = k as f64 / (rows - 1) as f64;
            tr.push(s, &f(s), &zero, &zero);
        }
        tr
    }

    fn bump(s: f64) -> f64 {
        (std::f64::consts::PI * s).sin()
    }

    /// A small well-formedness check of plotters' output: every tag closed in order, attribute values quoted.
    fn assert_well_formed(svg: &str) {
        let svg = svg.trim();
        assert!(svg.starts_with("<svg") || svg.starts_with("<?xml"), "{}", &svg[..svg.len().min(80)]);
        assert!(svg.ends_with("</svg>"));
        let mut stack: Vec<String> = Vec::new();
        let mut rest = svg;
        while let Some(start) = rest.find('<') {
            let end = start + rest[start..].find('>').expect("unterminated tag");
            let tag = &rest[start + 1..end];
            assert_eq!(tag.matches('"').count() % 2, 0, "unbalanced quotes in <{tag}>");
            if let Some(name) = tag.strip_prefix('/') {
                assert_eq!(stack.pop().as_deref(), Some(name.trim()), "mismatched </{name}>");
            } else if !tag.starts_with('?') && !tag.ends_with('/') {
                stack.push(tag.split_whitespace().next().unwrap().to_string());
            }
            rest = &rest[end + 1..];
        }
        assert!(stack.is_empty(), "unclosed: {stack:?}");
    }

    fn texts(svg: &str) -> Vec<String> {
        svg.split("<text")
            .skip(1)
            .map(|t| t[t.find('>').unwrap() + 1..t.find("</text>").unwrap()].trim().to_string())
            .collect()
    }

    fn count_text(svg: &str, s: &str) -> usize {
        texts(svg).iter().filter(|t| t.as_str() == s).count()
    }

    /// Vertices of every `<polygon>`, in pixels.
    fn polygons(svg: &str) -> Vec<Vec<(f64, f64)>> {
        svg.split("<polygon")
            .skip(1)
            .map(|p| {
                let pts = &p[p.find("points=\"").unwrap() + 8..];
                pts[..pts.find('"').unwrap()]
                    .split_whitespace()
                    .map(|xy| {
                        let (x, y) = xy.split_once(',').unwrap();
                        (x.parse().unwrap(), y.parse().unwrap())
                    })
                    .collect()
            })
            .collect()
    }

    /// With `DMP_PLOT_DUMP=dir` set, tests write their figures there (to look at them).
    fn dump(name: &str, svg: &str) {
        if let Some(dir) = std::env::var_os("DMP_PLOT_DUMP") {
            std::fs::write(std::path::Path::new(&dir).join(format!("{name}.svg")), svg).unwrap();
        }
    }

    fn check_common(svg: &str) {
        assert_well_formed(svg);
        assert!(!svg.contains("NaN") && !svg.contains("inf"), "non-finite number in the SVG");
        assert!(svg.contains("<text"), "no text at all");
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
            free: &c.free,
            adapted: &c.adapted,
            obstacles: &c.obstacles,
            robots: &[],
            obstacle_time: 0.0,
        }
    }

    #[test]
    fn plot_2d_one_ellipse() {
        let c = case_2d();
        let svg = render_svg(&input_2d(&c)).unwrap();
        dump("plot_2d_one_ellipse", &svg);
        check_common(&svg);
        for label in
            ["2-D: one ellipse", "x1", "x2", "demonstration", "DMP without obstacles", "DMP with avoidance"]
        {
            assert_eq!(count_text(&svg, label), 1, "text {label:?}");
        }
        assert!(svg.contains("#D62728") && svg.contains("#1F77B4"), "adapted / free colours");
        // One obstacle in one panel; its outline has the ellipse's 3:1 shape on screen (equal aspect ratio).
        let polys = polygons(&svg);
        assert_eq!(polys.len(), 1);
        let xs = polys[0].iter().map(|p| p.0);
        let ys = polys[0].iter().map(|p| p.1);
        let w = xs.clone().fold(f64::MIN, f64::max) - xs.fold(f64::MAX, f64::min);
        let h = ys.clone().fold(f64::MIN, f64::max) - ys.fold(f64::MAX, f64::min);
        assert!((w / h - 3.0).abs() < 0.1, "ellipse drawn {w} x {h} px");
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
            free: &free,
            adapted: &adapted,
            obstacles: &obstacles,
            robots: &[],
            obstacle_time: 0.0,
        };
        let svg = render_svg(&input).unwrap();
        dump("plot_3d_three_projections", &svg);
        check_common(&svg);
        for caption in ["x1 - x2", "x1 - x3", "x2 - x3"] {
            assert_eq!(count_text(&svg, caption), 1, "panel {caption:?}");
        }
        for axis in ["x1", "x2", "x3"] {
            assert_eq!(count_text(&svg, axis), 2, "axis name {axis:?}");
        }
        // The ellipsoid in each projection, with the right proportions.
        let polys = polygons(&svg);
        assert_eq!(polys.len(), 3);
        for (poly, ratio) in polys.iter().zip([2.0, 0.2 / 0.15, 0.1 / 0.15]) {
            let w = poly.iter().map(|p| p.0).fold(f64::MIN, f64::max)
                - poly.iter().map(|p| p.0).fold(f64::MAX, f64::min);
            let h = poly.iter().map(|p| p.1).fold(f64::MIN, f64::max)
                - poly.iter().map(|p| p.1).fold(f64::MAX, f64::min);
            assert!((w / h - ratio).abs() < 0.1 * ratio, "{w} x {h} px, expected ratio {ratio}");
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
            free: &free,
            adapted: &adapted,
            obstacles: &obstacles,
            robots: &robots,
            obstacle_time: 0.5,
        };
        let svg = render_svg(&input).unwrap();
        dump("plot_three_robots", &svg);
        check_common(&svg);
        for r in &robots {
            assert_eq!(count_text(&svg, &r.id), 1, "legend entry {}", r.id);
        }
        for colour in ["#1F77B4", "#FF7F0E", "#2CA02C"] {
            assert!(svg.contains(&format!("stroke=\"{colour}\"")), "robot colour {colour}");
        }
        assert_eq!(count_text(&svg, "x1"), 1);
        // The obstacle is filled once (at t = 0.5); its start and end positions are dashed outlines only.
        assert_eq!(polygons(&svg).len(), 1);
        assert_eq!(count_text(&svg, "obstacle at t = 0.5"), 1);
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
            free: &free,
            adapted: &adapted,
            obstacles: &obstacles,
            robots: &[],
            obstacle_time: 0.0,
        };
        let svg = render_svg(&input).unwrap();
        dump("plot_against_time_above_3d", &svg);
        check_common(&svg);
        assert_eq!(count_text(&svg, "t"), MAX_TIME_PANELS);
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
            free: &free,
            adapted: &adapted,
            obstacles: &obstacles,
            robots: &[],
            obstacle_time: f64::NAN,
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
    }
}
