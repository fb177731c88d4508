//! A robot's state on the wire (`dmp/<cell>/robots/<robot-id>/state`), checked and its footprint made the engine's.

use dmp::Isopotential;

use crate::WireError;
use crate::check::check_vector;
use crate::keys::check_name;
use crate::shape::superquadric_to_shape;
use crate::v1;

/// Checks a robot state (a named robot, finite stamp, position and velocity of one dimension, a footprint of that
/// dimension) and returns its footprint in the engine's form.
pub fn check_robot_state(s: &v1::RobotState) -> Result<Option<dmp::Shape>, WireError> {
    check_name("robot_id", &s.robot_id)?;
    if !s.stamp_unix_s.is_finite() {
        return Err(WireError::new("stamp_unix_s", "must be a finite number"));
    }
    let dim = s.position.len();
    if dim == 0 {
        return Err(WireError::new("position", "must not be empty"));
    }
    check_vector("position", &s.position, dim)?;
    if !s.velocity.is_empty() {
        check_vector("velocity", &s.velocity, dim)?;
    }
    let Some(f) = &s.footprint else { return Ok(None) };
    let shape = superquadric_to_shape(f).map_err(|e| e.within("footprint"))?;
    if shape.dim() != dim {
        return Err(WireError::new(
            "footprint.semi_axes",
            format!("must have {dim} entries (the position's dimension), found {}", shape.dim()),
        ));
    }
    Ok(Some(shape))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(id: &str, x: f64) -> v1::RobotState {
        v1::RobotState {
            robot_id: id.into(),
            stamp_unix_s: 1.7e9,
            position: vec![x, 0.0, 0.0],
            velocity: vec![0.0; 3],
            footprint: Some(v1::Superquadric { semi_axes: vec![0.2; 3], exponents: vec![] }),
            ..Default::default()
        }
    }

    #[test]
    fn robot_states_are_checked() {
        assert!(check_robot_state(&state("r1", 0.0)).unwrap().is_some());
        let mut s = state("r1", f64::NAN);
        assert!(check_robot_state(&s).unwrap_err().to_string().starts_with("position[0]"));
        s = state("r1", 0.0);
        s.velocity = vec![0.0; 2];
        assert!(check_robot_state(&s).unwrap_err().to_string().starts_with("velocity"));
        s = state("r1", 0.0);
        s.footprint = Some(v1::Superquadric { semi_axes: vec![0.2; 2], exponents: vec![] });
        assert!(check_robot_state(&s).unwrap_err().to_string().starts_with("footprint.semi_axes"));
        s.footprint = Some(v1::Superquadric { semi_axes: vec![0.2, 0.0, 0.2], exponents: vec![] });
        assert!(check_robot_state(&s).unwrap_err().to_string().starts_with("footprint."));
        assert!(check_robot_state(&state("a/b", 0.0)).is_err());
    }
}
