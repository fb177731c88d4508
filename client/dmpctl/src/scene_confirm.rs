//! `scene put --via zenoh` confirmed: a Zenoh put has no answer, so the command watches the server's scene (gRPC
//! `WatchScene`) and waits, at most `--wait-s`, until every obstacle it published shows there as published. One
//! that does not is named, with the likely causes: the server refuses a payload it cannot apply (a centre beyond
//! its workspace, a value out of range) and logs why, and Zenoh's access control drops a put of an identity that may
//! not publish in that cell, silently.

use std::time::Duration;

use dmp_client::grpc::{DmpClient, SceneStream};
use dmp_proto::obstacle_json::JsonObstacle;
use dmp_proto::v1;
use tokio_stream::StreamExt;

use crate::error::DmpctlError;

/// The default of `--wait-s`.
pub(crate) const DEFAULT_WAIT_S: f64 = 2.0;

/// A watch of the server's scene opened before publishing, so that no change is missed.
pub(crate) struct Confirmation {
    client: DmpClient,
    events: SceneStream,
    wait: Duration,
}

impl std::fmt::Debug for Confirmation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Confirmation").field("wait", &self.wait).finish_non_exhaustive()
    }
}

impl Confirmation {
    /// Opens the watch on `client`'s cell; errors say that the put cannot be confirmed and how to skip it.
    pub(crate) async fn open(client: DmpClient, wait: Duration) -> Result<Self, DmpctlError> {
        let events = client.watch_scene().await.map_err(|e| {
            DmpctlError::NotApplied(format!(
                "cannot watch the server's scene to confirm the put ({e}); nothing was published \
                 (--wait-s 0 publishes without confirming)"
            ))
        })?;
        Ok(Self { client, events, wait })
    }

    /// Waits until every one of `published` shows in the scene as published; the scene version it did, or an error
    /// naming those that did not and why they may not have.
    pub(crate) async fn wait(mut self, published: &[JsonObstacle]) -> Result<u64, DmpctlError> {
        let expected: Vec<v1::Obstacle> = published.iter().map(JsonObstacle::to_proto).collect();
        let mut missing: Vec<&v1::Obstacle> = expected.iter().collect();
        let deadline = tokio::time::Instant::now() + self.wait;
        let mut version = 0;
        while !missing.is_empty() {
            let snapshot = match tokio::time::timeout_at(deadline, self.events.next()).await {
                Ok(Some(Ok(s))) => s,
                Ok(Some(Err(e))) => {
                    return Err(DmpctlError::NotApplied(format!(
                        "the watch of the server's scene failed: {e}"
                    )));
                }
                Ok(None) => {
                    return Err(DmpctlError::NotApplied("the server closed the watch of its scene".into()));
                }
                Err(_) => break,
            };
            version = snapshot.scene_version;
            missing.retain(|o| !snapshot.obstacles.iter().any(|s| shows(s, o)));
        }
        if missing.is_empty() {
            return Ok(version);
        }
        let info = self.client.info().await.ok();
        let lines: Vec<String> = missing.iter().map(|o| why_missing(o, info.as_ref(), self.wait)).collect();
        Err(DmpctlError::NotApplied(lines.join("\n")))
    }
}

/// Whether `seen` (in the server's scene) is `published`: the same id, shape and velocity, and the same centre
/// unless it moves (the scene gives centres as of now). Semi-axes may be inflated by the margin.
fn shows(seen: &v1::Obstacle, published: &v1::Obstacle) -> bool {
    let close = |a: &[f64], b: &[f64]| {
        a.len() == b.len()
            && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1.0))
    };
    let axes = |o: &v1::Obstacle| match &o.shape {
        Some(v1::obstacle::Shape::Superquadric(s)) => s.semi_axes.clone(),
        Some(v1::obstacle::Shape::Nested(n)) => n.semi_axes.clone(),
        _ => Vec::new(),
    };
    let (a, b) = (axes(seen), axes(published));
    let inflated: Vec<f64> = b.iter().map(|x| x + published.margin).collect();
    seen.id == published.id
        && (close(&a, &b) || close(&a, &inflated))
        && close(&seen.velocity, &published.velocity)
        && (!published.velocity.is_empty() || close(&seen.center, &published.center))
}

/// Why `o` may not show: a centre beyond the server's workspace when it is, else the likely causes.
fn why_missing(o: &v1::Obstacle, info: Option<&v1::ServerInfo>, wait: Duration) -> String {
    let mut line = format!(
        "`{}` was published but did not show in the server's scene within {} s: the server refused it",
        o.id,
        wait.as_secs_f64()
    );
    let workspace = info.and_then(|i| i.limits.as_ref()).map(|l| l.workspace_m).filter(|w| *w > 0.0);
    if let Some(w) = workspace
        && let Some((axis, c)) = o.center.iter().enumerate().find(|(_, c)| c.abs() > w)
    {
        line.push_str(&format!(
            ": center[{axis}] = {c} is outside the server's workspace (|x| <= {w} m, limits.workspace_m)"
        ));
        return line;
    }
    let identity = info.map(|i| i.identity.as_str()).filter(|i| !i.is_empty());
    line.push_str(&format!(
        ", or it never reached it. Likely causes: this identity{} may not publish obstacles in this cell (Zenoh's \
         access control drops the put without a word); a value out of the server's range (its log names the field, \
         `zenoh payload refused`); the server listens on another Zenoh endpoint or cell (--zenoh-connect, --cell); \
         or it takes longer than --wait-s",
        identity.map(|i| format!(" (`{i}`)")).unwrap_or_default()
    ));
    line
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ball(center: Vec<f64>, r: f64) -> v1::Obstacle {
        v1::Obstacle {
            id: "ball".into(),
            shape: Some(v1::obstacle::Shape::Superquadric(v1::Superquadric {
                semi_axes: vec![r; center.len()],
                exponents: vec![],
            })),
            center,
            ..Default::default()
        }
    }

    #[test]
    fn an_obstacle_shows_when_id_shape_and_centre_agree() {
        let published = ball(vec![0.5, 0.5], 0.1);
        assert!(shows(&ball(vec![0.5, 0.5], 0.1), &published));
        assert!(!shows(&ball(vec![0.5, 0.6], 0.1), &published), "another centre: an older version");
        assert!(!shows(&ball(vec![0.5, 0.5], 0.2), &published));
        let mut inflated = published.clone();
        inflated.margin = 0.05;
        assert!(shows(&ball(vec![0.5, 0.5], 0.15), &inflated), "semi-axes inflated by the margin");
        let mut moving = published.clone();
        moving.velocity = vec![1.0, 0.0];
        let mut seen = ball(vec![0.7, 0.5], 0.1);
        seen.velocity = vec![1.0, 0.0];
        assert!(shows(&seen, &moving), "a moving obstacle's centre has moved on");
    }

    #[test]
    fn a_centre_beyond_the_workspace_is_named() {
        let info = v1::ServerInfo {
            limits: Some(v1::ServerLimits { workspace_m: 100.0, ..Default::default() }),
            ..Default::default()
        };
        let line = why_missing(&ball(vec![0.0, 1e9], 0.1), Some(&info), Duration::from_secs(2));
        assert!(line.contains("center[1] = 1000000000 is outside the server's workspace"), "{line}");
        let line = why_missing(&ball(vec![0.0, 1.0], 0.1), Some(&info), Duration::from_secs(2));
        assert!(line.contains("may not publish obstacles in this cell"), "{line}");
    }
}
