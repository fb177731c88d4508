//! The safety margin around a true shape on a panel's plane: its outline grown by the margin (the projection of the
//! shape grown by a ball is its projection grown by a disc), exact for a convex outline, the convex hull's otherwise.

use super::geometry::{P2, convex_hull, finite};

/// Points on the disc's rim added to each vertex.
const RIM: usize = 48;

/// The outline `poly` grown by `margin` (the convex hull of its vertices, each swept around a disc of that radius);
/// empty for an empty outline or a margin that is not positive.
pub(crate) fn grown(poly: &[P2], margin: f64) -> Vec<P2> {
    if !(margin.is_finite() && margin > 0.0) || poly.is_empty() {
        return Vec::new();
    }
    let hull = convex_hull(poly.to_vec());
    let rim: Vec<P2> = (0..RIM)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / RIM as f64;
            (margin * a.cos(), margin * a.sin())
        })
        .collect();
    convex_hull(
        hull.iter().filter(|p| finite(p)).flat_map(|p| rim.iter().map(|r| (p.0 + r.0, p.1 + r.1))).collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_square_grown_is_a_rounded_square_as_far_out_as_the_margin() {
        let square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
        let g = grown(&square, 0.1);
        let (x0, x1) = g.iter().fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
        assert!((x0 + 0.1).abs() < 1e-12 && (x1 - 1.1).abs() < 1e-12, "{x0} {x1}");
        // Every vertex is the margin away from the square.
        for p in &g {
            let dx = (-p.0).max(p.0 - 1.0).max(0.0);
            let dy = (-p.1).max(p.1 - 1.0).max(0.0);
            assert!(((dx * dx + dy * dy).sqrt() - 0.1).abs() < 1e-9, "{p:?}");
        }
        assert!(grown(&square, 0.0).is_empty());
    }
}
