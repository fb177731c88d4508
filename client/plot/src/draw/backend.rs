//! A plotters backend writing SVG with sub-pixel coordinates and named groups.
//!
//! plotters hands every backend whole-number coordinates. This backend declares a canvas [`SCALE`] times larger
//! than the figure and divides every coordinate by [`SCALE`] when it writes it, so that the SVG carries positions
//! to 1/[`SCALE`] of a pixel (a curve is smooth, not a staircase). Everything sized in pixels by the figure code
//! (fonts, strokes, margins) is therefore given in device units: pixels times [`SCALE`] ([`px`]).
//!
//! The figure code wraps what it draws in `<g class="...">` groups ([`Doc::group`]), so that a reader (or a test)
//! finds the obstacles' true shapes, the isopotentials, the contacts and the events by class.

use std::cell::{Cell, RefCell};
use std::fmt::Write as _;
use std::rc::Rc;

use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingBackend, DrawingErrorKind, FontStyle,
    FontTransform,
};

/// Device units per pixel of the figure.
pub(crate) const SCALE: u32 = 8;

thread_local! {
    /// The dash pattern of the lines being drawn (device units), set by [`dashed`]: one polyline with a
    /// `stroke-dasharray` instead of an element per dash.
    static DASH: Cell<Option<(u32, u32)>> = const { Cell::new(None) };
}

/// Runs `f` with lines drawn dashed `(on, off)` (device units). Figures are drawn on one thread, start to end.
pub(crate) fn dashed<T>(dash: (u32, u32), f: impl FnOnce() -> T) -> T {
    let before = DASH.with(|d| d.replace(Some(dash)));
    let out = f();
    DASH.with(|d| d.set(before));
    out
}

fn dasharray() -> String {
    DASH.with(Cell::get).map_or(String::new(), |(on, off)| {
        format!(" stroke-dasharray=\"{} {}\"", num(on as i32), num(off as i32))
    })
}

/// `v` pixels in device units.
pub(crate) const fn px(v: u32) -> u32 {
    v * SCALE
}

/// The SVG being written, shared by the backend and the figure code (which opens and closes groups).
#[derive(Debug, Default)]
pub(crate) struct Doc {
    body: String,
    open: usize,
}

/// A handle on the document.
pub(crate) type SharedDoc = Rc<RefCell<Doc>>;

impl Doc {
    pub(crate) fn shared() -> SharedDoc {
        Rc::new(RefCell::new(Doc::default()))
    }

    /// Opens `<g>` with these attributes (`class`, `id`, ...); [`Doc::end`] closes it.
    pub(crate) fn begin(doc: &SharedDoc, attrs: &[(&str, &str)]) {
        let mut d = doc.borrow_mut();
        d.body.push_str("<g");
        for (k, v) in attrs {
            let _ = write!(d.body, " {k}=\"{}\"", escape(v));
        }
        d.body.push_str(">\n");
        d.open += 1;
    }

    /// Closes the innermost group.
    pub(crate) fn end(doc: &SharedDoc) {
        let mut d = doc.borrow_mut();
        if d.open > 0 {
            d.body.push_str("</g>\n");
            d.open -= 1;
        }
    }

    /// Runs `f` inside `<g class="class">`.
    pub(crate) fn group<T>(doc: &SharedDoc, class: &str, f: impl FnOnce() -> T) -> T {
        Doc::begin(doc, &[("class", class)]);
        let out = f();
        Doc::end(doc);
        out
    }

    /// The complete document, `size` in device units.
    pub(crate) fn finish(doc: &SharedDoc, size: (u32, u32)) -> String {
        let mut d = doc.borrow_mut();
        while d.open > 0 {
            d.body.push_str("</g>\n");
            d.open -= 1;
        }
        let (w, h) = (num(size.0 as i32), num(size.1 as i32));
        format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\">\n{}</svg>\n",
            d.body
        )
    }
}

fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '&' => out.push_str("&amp;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// A device coordinate in pixels: exact (a multiple of 1/8 has a short decimal form).
fn num(v: i32) -> String {
    format!("{}", f64::from(v) / f64::from(SCALE))
}

fn color(c: BackendColor) -> String {
    format!("#{:02X}{:02X}{:02X}", c.rgb.0, c.rgb.1, c.rgb.2)
}

fn points(path: impl IntoIterator<Item = BackendCoord>) -> String {
    let mut s = String::new();
    for (x, y) in path {
        let _ = write!(s, "{},{} ", num(x), num(y));
    }
    s.pop();
    s
}

/// The backend: a canvas of `size` device units writing into a [`Doc`].
#[derive(Debug)]
pub(crate) struct FineSvg {
    doc: SharedDoc,
    size: (u32, u32),
}

impl FineSvg {
    pub(crate) fn new(doc: SharedDoc, size: (u32, u32)) -> Self {
        Self { doc, size }
    }

    fn push(&self, element: String) {
        let mut d = self.doc.borrow_mut();
        d.body.push_str(&element);
        d.body.push('\n');
    }
}

type Res = Result<(), DrawingErrorKind<std::io::Error>>;

impl DrawingBackend for FineSvg {
    type ErrorType = std::io::Error;

    fn get_size(&self) -> (u32, u32) {
        self.size
    }

    fn ensure_prepared(&mut self) -> Res {
        Ok(())
    }

    fn present(&mut self) -> Res {
        Ok(())
    }

    fn draw_pixel(&mut self, p: BackendCoord, c: BackendColor) -> Res {
        if c.alpha > 0.0 {
            self.push(format!(
                "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"{}\" opacity=\"{}\"/>",
                num(p.0),
                num(p.1),
                num(1),
                num(1),
                color(c),
                c.alpha
            ));
        }
        Ok(())
    }

    fn draw_line<S: BackendStyle>(&mut self, from: BackendCoord, to: BackendCoord, style: &S) -> Res {
        let c = style.color();
        if c.alpha > 0.0 {
            self.push(format!(
                "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"{}\" stroke-width=\"{}\" opacity=\"{}\"/>",
                num(from.0),
                num(from.1),
                num(to.0),
                num(to.1),
                color(c),
                num(style.stroke_width() as i32),
                c.alpha
            ));
        }
        Ok(())
    }

    fn draw_rect<S: BackendStyle>(
        &mut self,
        ul: BackendCoord,
        br: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Res {
        let c = style.color();
        if c.alpha > 0.0 {
            let paint = if fill {
                format!("fill=\"{}\" stroke=\"none\"", color(c))
            } else {
                format!(
                    "fill=\"none\" stroke=\"{}\" stroke-width=\"{}\"",
                    color(c),
                    num(style.stroke_width().max(1) as i32)
                )
            };
            self.push(format!(
                "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" {paint} opacity=\"{}\"/>",
                num(ul.0),
                num(ul.1),
                num(br.0 - ul.0),
                num(br.1 - ul.1),
                c.alpha
            ));
        }
        Ok(())
    }

    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Res {
        let c = style.color();
        if c.alpha > 0.0 {
            self.push(format!(
                "<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"{}\" stroke-linejoin=\"round\"{} opacity=\"{}\" points=\"{}\"/>",
                color(c),
                num(style.stroke_width() as i32),
                dasharray(),
                c.alpha,
                points(path)
            ));
        }
        Ok(())
    }

    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Res {
        let c = style.color();
        if c.alpha > 0.0 {
            self.push(format!(
                "<polygon fill=\"{}\" opacity=\"{}\" points=\"{}\"/>",
                color(c),
                c.alpha,
                points(path)
            ));
        }
        Ok(())
    }

    fn draw_circle<S: BackendStyle>(&mut self, center: BackendCoord, r: u32, style: &S, fill: bool) -> Res {
        let c = style.color();
        if c.alpha > 0.0 {
            let paint = if fill {
                format!("fill=\"{}\" stroke=\"none\"", color(c))
            } else {
                format!(
                    "fill=\"none\" stroke=\"{}\" stroke-width=\"{}\"",
                    color(c),
                    num(style.stroke_width() as i32)
                )
            };
            self.push(format!(
                "<circle cx=\"{}\" cy=\"{}\" r=\"{}\" {paint} opacity=\"{}\"/>",
                num(center.0),
                num(center.1),
                num(r as i32),
                c.alpha
            ));
        }
        Ok(())
    }

    fn draw_text<T: BackendTextStyle>(&mut self, text: &str, style: &T, pos: BackendCoord) -> Res {
        let c = style.color();
        if c.alpha == 0.0 {
            return Ok(());
        }
        let anchor = match style.anchor().h_pos {
            HPos::Left => "start",
            HPos::Right => "end",
            HPos::Center => "middle",
        };
        let dy = match style.anchor().v_pos {
            VPos::Top => "0.76em",
            VPos::Center => "0.5ex",
            VPos::Bottom => "-0.5ex",
        };
        let (x, y) = (num(pos.0), num(pos.1));
        let mut attrs = format!(
            "x=\"{x}\" y=\"{y}\" dy=\"{dy}\" text-anchor=\"{anchor}\" font-family=\"{}\" font-size=\"{}\" fill=\"{}\"",
            escape(style.family().as_str()),
            style.size() / 1.24 / f64::from(SCALE),
            color(c)
        );
        if c.alpha < 1.0 {
            let _ = write!(attrs, " opacity=\"{}\"", c.alpha);
        }
        match style.style() {
            FontStyle::Normal => {}
            FontStyle::Bold => attrs.push_str(" font-weight=\"bold\""),
            other => {
                let _ = write!(attrs, " font-style=\"{}\"", other.as_str());
            }
        }
        let angle = match style.transform() {
            FontTransform::Rotate90 => Some(90),
            FontTransform::Rotate180 => Some(180),
            FontTransform::Rotate270 => Some(270),
            FontTransform::None => None,
        };
        if let Some(a) = angle {
            let _ = write!(attrs, " transform=\"rotate({a}, {x}, {y})\"");
        }
        self.push(format!("<text {attrs}>{}</text>", escape(text)));
        Ok(())
    }

    fn estimate_text_size<T: BackendTextStyle>(
        &self,
        text: &str,
        style: &T,
    ) -> Result<(u32, u32), DrawingErrorKind<std::io::Error>> {
        let ((x0, y0), (x1, y1)) =
            style.layout_box(text).map_err(|e| DrawingErrorKind::FontError(Box::new(e)))?;
        Ok(((x1 - x0).max(0) as u32, (y1 - y0).max(0) as u32))
    }
}
