//! Scenario specifications to engine objects: what every reader of the format needs (with or without learning).

use super::model::ObstacleSpec;
use crate::error::{InvalidInput, Result};
use crate::isopotential::{NestedSuperquadric, Shape, Superquadric};
use crate::obstacle::Obstacle;

impl ObstacleSpec {
    /// The engine's obstacle (per-axis exponents default to 1; `nested` selects the paper's 3-D form); errors name
    /// the field within the obstacle.
    pub fn to_obstacle(&self) -> Result<Obstacle> {
        let o = self;
        let shape = match o.nested {
            Some(n) => {
                if o.exponents.is_some() {
                    return Err(
                        InvalidInput::new("nested", "give either `exponents` or `nested`, not both").into()
                    );
                }
                let a: [f64; 3] = o.semi_axes.as_slice().try_into().map_err(|_| {
                    InvalidInput::new(
                        "semi_axes",
                        format!("the nested form is 3-D: needs 3 semi-axes, found {}", o.semi_axes.len()),
                    )
                })?;
                Shape::Nested(NestedSuperquadric::new(a, n.n, n.m)?)
            }
            None => superquadric(&o.semi_axes, o.exponents.as_deref())?,
        };
        Obstacle::new(o.id.clone(), shape, o.center.clone(), o.rotation.clone(), o.velocity.clone())
    }
}

pub(crate) fn superquadric(semi_axes: &[f64], exponents: Option<&[f64]>) -> Result<Shape> {
    let n = exponents.map(<[f64]>::to_vec).unwrap_or_else(|| vec![1.0; semi_axes.len()]);
    Ok(Shape::Superquadric(Superquadric::new(semi_axes.to_vec(), n)?))
}
