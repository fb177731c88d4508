//! `std_msgs`: the header and colours.

use super::builtin_interfaces::Time;

/// `std_msgs/msg/Header`: a stamp and the frame the data is in.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Header {
    /// When the data was taken.
    pub stamp: Time,
    /// The frame.
    pub frame_id: String,
}

/// `std_msgs/msg/ColorRGBA`, each in [0, 1].
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct ColorRGBA {
    /// Red.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
    /// Opacity.
    pub a: f32,
}
