//! `builtin_interfaces`: time and duration.

/// `builtin_interfaces/msg/Time`: seconds and nanoseconds since the epoch.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Time {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds, in [0, 1e9).
    pub nanosec: u32,
}

/// `builtin_interfaces/msg/Duration`.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Duration {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds, in [0, 1e9).
    pub nanosec: u32,
}

impl Time {
    /// The time of `unix_s` seconds since the epoch (floored to the nanosecond).
    pub fn from_unix_s(unix_s: f64) -> Self {
        let (sec, nanosec) = split_seconds(unix_s);
        Self { sec, nanosec }
    }
}

impl Duration {
    /// The duration of `s` seconds (floored to the nanosecond).
    pub fn from_s(s: f64) -> Self {
        let (sec, nanosec) = split_seconds(s);
        Self { sec, nanosec }
    }

    /// In seconds.
    pub fn as_s(&self) -> f64 {
        f64::from(self.sec) + f64::from(self.nanosec) * 1e-9
    }
}

/// Whole seconds (floored, saturating at i32) and nanoseconds in [0, 1e9).
fn split_seconds(s: f64) -> (i32, u32) {
    let ns = (s * 1e9).floor();
    let sec = (ns / 1e9).floor();
    let nanosec = (ns - sec * 1e9).clamp(0.0, 999_999_999.0) as u32;
    (sec.clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32, nanosec)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seconds_split_into_sec_and_nanosec() {
        assert_eq!(Duration::from_s(1.5), Duration { sec: 1, nanosec: 500_000_000 });
        assert_eq!(Duration::from_s(-1.7), Duration { sec: -2, nanosec: 300_000_000 });
        assert!((Duration::from_s(2.25).as_s() - 2.25).abs() < 1e-9);
    }
}
