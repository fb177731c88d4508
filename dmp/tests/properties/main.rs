//! Properties of the `dmp` engine, through its public API only: RK4 order, replay of a demonstration, time
//! scaling, spatial generalisation, save and load, changing the motion mid-run, guard rails (never NaN,
//! contacts and stalls reported), several robots on one phase, and orientation DMPs on unit quaternions.
//!
//! Measured numbers are printed with `eprintln!` (`cargo test -p dmp --test properties -- --nocapture`).

mod arrival;
mod bar_through_gap;
mod bar_through_gap_scenarios;
mod changing_the_motion;
mod fixtures;
mod guard_rails;
mod limits;
mod orientation;
mod replay;
mod rk4_convergence;
mod save_and_load;
mod several_robots;
mod time_scaling_and_generalisation;
