//! The messages, field for field and in the order of the `.msg` files in `ros2/msg/` (CDR has no field names: the
//! order is the format). Constants are associated constants of their message. Serde's field names are the ROS
//! names, so the JSON of a message (the golden test's) reads like `ros2 topic echo`.

pub mod builtin_interfaces;
pub mod geometry_msgs;
pub mod moveit_msgs;
pub mod nav2_dynamic_msgs;
pub mod shape_msgs;
pub mod std_msgs;
pub mod trajectory_msgs;
pub mod visualization_msgs;
