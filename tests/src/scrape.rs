//! Scraping the server's Prometheus endpoint over HTTP, as Prometheus does, and reading the text format with a
//! parser of it.

use std::collections::HashSet;
use std::net::SocketAddr;

use http_body_util::{BodyExt, Empty};
use hyper::body::Bytes;
use hyper_util::rt::TokioIo;

use crate::within;

/// An HTTP reply: status, content type, body.
#[derive(Debug)]
pub struct Reply {
    /// The HTTP status code.
    pub status: u16,
    /// The `content-type` header (empty when absent).
    pub content_type: String,
    /// The body as text.
    pub body: String,
}

/// `GET path` from the HTTP server at `addr` (HTTP/1.1, one connection).
pub async fn get(addr: SocketAddr, path: &str) -> Reply {
    let stream = within("metrics connect", tokio::net::TcpStream::connect(addr)).await.expect("connects");
    let (mut sender, connection) =
        within("http handshake", hyper::client::conn::http1::handshake(TokioIo::new(stream)))
            .await
            .expect("HTTP/1.1 handshake");
    let driver = tokio::spawn(connection);
    let request = hyper::Request::get(path)
        .header(hyper::header::HOST, addr.to_string())
        .body(Empty::<Bytes>::new())
        .expect("a valid request");
    let response = within("http request", sender.send_request(request)).await.expect("a response");
    let status = response.status().as_u16();
    let content_type = response
        .headers()
        .get(hyper::header::CONTENT_TYPE)
        .map(|v| v.to_str().expect("an ASCII content type").to_owned())
        .unwrap_or_default();
    let body = within("http body", response.into_body().collect()).await.expect("a body").to_bytes();
    drop(sender);
    driver.abort();
    Reply { status, content_type, body: String::from_utf8(body.to_vec()).expect("a UTF-8 body") }
}

/// The metrics now: `GET /metrics`, checked (status 200, the OpenMetrics content type, `# EOF` last, a HELP and a
/// TYPE for every family of samples, no line the parser skipped) and parsed.
pub async fn scrape(addr: SocketAddr) -> prometheus_parse::Scrape {
    let reply = get(addr, "/metrics").await;
    assert_eq!(reply.status, 200, "{}", reply.body);
    assert!(reply.content_type.starts_with("application/openmetrics-text"), "{}", reply.content_type);
    let text = reply.body;
    assert_eq!(text.lines().last(), Some("# EOF"), "the OpenMetrics text ends with # EOF");
    let mut typed = HashSet::new();
    let mut helped = HashSet::new();
    for line in text.lines().filter(|l| l.starts_with('#') && *l != "# EOF") {
        let mut words = line.split_whitespace().skip(1);
        let (kind, name) = (words.next(), words.next().expect("a metric name after # HELP or # TYPE"));
        match kind {
            Some("TYPE") => assert!(typed.insert(name.to_owned()), "two TYPE lines for {name}"),
            Some("HELP") => assert!(helped.insert(name.to_owned()), "two HELP lines for {name}"),
            _ => panic!("unexpected comment line: {line}"),
        }
    }
    assert_eq!(typed, helped, "every family has a TYPE and a HELP");
    let parsed = prometheus_parse::Scrape::parse(text.lines().map(|l| Ok(l.to_owned()))).expect("parses");
    let samples = text.lines().filter(|l| !l.starts_with('#')).count();
    let parsed_lines: usize = parsed
        .samples
        .iter()
        .map(|s| match &s.value {
            prometheus_parse::Value::Histogram(buckets) => buckets.len(),
            _ => 1,
        })
        .sum();
    assert_eq!(parsed_lines, samples, "every sample line parses:\n{text}");
    for s in &parsed.samples {
        assert!(typed.contains(family(&s.metric)), "{} has no TYPE line", s.metric);
    }
    parsed
}

/// The family a sample belongs to: its name without the suffix the text format adds (`_total`, `_bucket`, `_sum`,
/// `_count`).
pub fn family(sample: &str) -> &str {
    ["_total", "_bucket", "_sum", "_count"].iter().find_map(|s| sample.strip_suffix(s)).unwrap_or(sample)
}

/// The value of the sample `name` whose labels are `labels` (None when there is none).
pub fn value(scrape: &prometheus_parse::Scrape, name: &str, labels: &[(&str, &str)]) -> Option<f64> {
    scrape
        .samples
        .iter()
        .find(|s| s.metric == name && labels.iter().all(|(k, v)| s.labels.get(k) == Some(*v)))
        .map(|s| match &s.value {
            prometheus_parse::Value::Counter(v)
            | prometheus_parse::Value::Gauge(v)
            | prometheus_parse::Value::Untyped(v) => *v,
            prometheus_parse::Value::Histogram(b) => b.iter().map(|c| c.count).fold(0.0, f64::max),
            prometheus_parse::Value::Summary(_) => f64::NAN,
        })
}

/// The families of a scrape (sample names without their suffixes).
pub fn families(scrape: &prometheus_parse::Scrape) -> HashSet<String> {
    scrape.samples.iter().map(|s| family(&s.metric).to_owned()).collect()
}
