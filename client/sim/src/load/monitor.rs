//! The server's resource use over the run (`GetStats` once a second), and this process's CPU time.

use std::time::Duration;

use dmp_client::grpc::DmpClient;
use dmp_proto::v1;
use tokio::time::{Instant, MissedTickBehavior};

use super::Errors;

/// Longest wait for one GetStats.
const CALL_TIMEOUT: Duration = Duration::from_secs(2);
/// How often the server is sampled.
pub(crate) const PERIOD: Duration = Duration::from_secs(1);

/// What the monitor saw.
#[derive(Debug, Clone, Default)]
pub(crate) struct Watched {
    /// At the beginning of the measurement.
    pub(crate) begin: Option<v1::ServerStats>,
    /// At its end (before the stops).
    pub(crate) end: Option<v1::ServerStats>,
    /// Every sample, beginning and end included.
    pub(crate) samples: Vec<v1::ServerStats>,
    /// This process's CPU seconds at the beginning and the end (Linux only).
    pub(crate) own_cpu_s: Option<(f64, f64)>,
    /// Wall seconds between the two.
    pub(crate) own_wall_s: f64,
}

impl Watched {
    /// Server CPU over the measurement, percent of one core.
    pub(crate) fn cpu_percent(&self) -> Option<f64> {
        let (b, e) = (self.begin.as_ref()?, self.end.as_ref()?);
        let wall = e.uptime_s - b.uptime_s;
        (wall > 0.0).then(|| round1(100.0 * (e.cpu_seconds - b.cpu_seconds) / wall))
    }

    /// This process's CPU over the measurement, percent of one core.
    pub(crate) fn own_cpu_percent(&self) -> Option<f64> {
        let (b, e) = self.own_cpu_s?;
        (self.own_wall_s > 0.0).then(|| round1(100.0 * (e - b) / self.own_wall_s))
    }

    /// Resident memory of every sample, MiB.
    pub(crate) fn rss_mib(&self) -> Vec<f64> {
        self.samples.iter().map(|s| mib(s.rss_bytes)).collect()
    }
}

/// Bytes to MiB, one decimal.
pub(crate) fn mib(bytes: u64) -> f64 {
    round1(bytes as f64 / (1024.0 * 1024.0))
}

fn round1(x: f64) -> f64 {
    (x * 10.0).round() / 10.0
}

async fn sample(client: &DmpClient, errors: &Errors) -> Option<v1::ServerStats> {
    match tokio::time::timeout(CALL_TIMEOUT, client.stats()).await {
        Ok(Ok(s)) => Some(s),
        Ok(Err(e)) => {
            errors.add(format!("server stats: {e}"));
            None
        }
        Err(_) => {
            errors.add(format!("server stats: no answer within {CALL_TIMEOUT:?}"));
            None
        }
    }
}

/// Samples the server from `begin` to `end`, every [`PERIOD`].
pub(crate) async fn watch(client: &DmpClient, begin: Instant, end: Instant, errors: &Errors) -> Watched {
    let mut w = Watched::default();
    let mut tick = tokio::time::interval_at(begin, PERIOD);
    tick.set_missed_tick_behavior(MissedTickBehavior::Delay);
    tick.tick().await;
    let own_begin = process_cpu_seconds();
    let wall = Instant::now();
    w.begin = sample(client, errors).await;
    w.samples.extend(w.begin);
    loop {
        tokio::select! {
            _ = tick.tick() => w.samples.extend(sample(client, errors).await),
            _ = tokio::time::sleep_until(end) => break,
        }
    }
    w.own_wall_s = wall.elapsed().as_secs_f64();
    w.own_cpu_s = own_begin.zip(process_cpu_seconds());
    w.end = sample(client, errors).await;
    w.samples.extend(w.end);
    w
}

/// This process's CPU time (user and system), seconds: `/proc/self/stat` on Linux, `None` elsewhere.
pub(crate) fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (which may hold spaces) start with the state, field 3; utime and stime are
    // fields 14 and 15, in clock ticks of 1/100 s (USER_HZ).
    let rest = &stat[stat.rfind(')')? + 1..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| fields.get(i)?.parse::<u64>().ok();
    Some((ticks(11)? + ticks(12)?) as f64 / 100.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_percent_is_of_one_core() {
        let at = |uptime_s, cpu_seconds| v1::ServerStats { uptime_s, cpu_seconds, ..Default::default() };
        let w = Watched { begin: Some(at(10.0, 1.0)), end: Some(at(20.0, 16.0)), ..Default::default() };
        assert_eq!(w.cpu_percent(), Some(150.0));
        assert_eq!(Watched::default().cpu_percent(), None);
        assert_eq!(mib(300 * 1024 * 1024 + 1_000), 300.0);
        if cfg!(target_os = "linux") {
            assert!(process_cpu_seconds().is_some());
        }
    }
}
