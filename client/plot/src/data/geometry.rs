//! Geometry in a panel's data coordinates: points, clipping a polygon to a rectangle, convex hull.

/// A point in a panel's data coordinates.
pub(crate) type P2 = (f64, f64);

/// Both coordinates are finite.
pub(crate) fn finite(p: &P2) -> bool {
    p.0.is_finite() && p.1.is_finite()
}

/// The part of the polygon `poly` inside the rectangle `((x0, x1), (y0, y1))` (Sutherland-Hodgman).
pub(crate) fn clip_polygon(poly: &[P2], ((x0, x1), (y0, y1)): ((f64, f64), (f64, f64))) -> Vec<P2> {
    let (x0, x1) = (x0.min(x1), x0.max(x1));
    let (y0, y1) = (y0.min(y1), y0.max(y1));
    let mut out: Vec<P2> = poly.to_vec();
    let edges: [(usize, f64, bool); 4] = [(0, x0, true), (0, x1, false), (1, y0, true), (1, y1, false)];
    for (axis, bound, keep_above) in edges {
        let inside = |p: &P2| {
            let v = if axis == 0 { p.0 } else { p.1 };
            if keep_above { v >= bound } else { v <= bound }
        };
        let cross = |a: &P2, b: &P2| {
            let (va, vb) = if axis == 0 { (a.0, b.0) } else { (a.1, b.1) };
            let s = (bound - va) / (vb - va);
            (a.0 + s * (b.0 - a.0), a.1 + s * (b.1 - a.1))
        };
        let input = std::mem::take(&mut out);
        for (k, b) in input.iter().enumerate() {
            let a = &input[(k + input.len() - 1) % input.len()];
            match (inside(a), inside(b)) {
                (true, true) => out.push(*b),
                (true, false) => out.push(cross(a, b)),
                (false, true) => {
                    out.push(cross(a, b));
                    out.push(*b);
                }
                (false, false) => {}
            }
        }
    }
    out
}

/// Convex hull (Andrew's monotone chain), counter-clockwise, without repeating the first vertex.
pub(crate) fn convex_hull(mut p: Vec<P2>) -> Vec<P2> {
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
