//! Orientation DMPs (unit quaternions): unit outputs, goal reached, replay, time scaling, the double cover, the
//! angular velocity and acceleration against finite differences, and the refusals.

mod derivatives;
mod double_cover;
mod fixtures;
mod pose_runs;
mod refusals;
mod replay;
