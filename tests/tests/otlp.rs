//! Traces to OpenTelemetry (`--otlp-endpoint`): the spans of the server's gRPC requests reach an OTLP/gRPC
//! collector (one in-process, on loopback). Its own test binary: it installs the process's global subscriber.

use dmp_tests::{TestServer, within};
use opentelemetry_proto::tonic::collector::trace::v1::trace_service_server::{
    TraceService, TraceServiceServer,
};
use opentelemetry_proto::tonic::collector::trace::v1::{
    ExportTraceServiceRequest, ExportTraceServiceResponse,
};
use opentelemetry_proto::tonic::common::v1::KeyValue;
use opentelemetry_proto::tonic::common::v1::any_value::Value;
use tokio::sync::mpsc;
use tracing_subscriber::layer::SubscriberExt;

/// A collector that hands every export to the test.
struct Collector(mpsc::UnboundedSender<ExportTraceServiceRequest>);

#[tonic::async_trait]
impl TraceService for Collector {
    async fn export(
        &self,
        request: tonic::Request<ExportTraceServiceRequest>,
    ) -> Result<tonic::Response<ExportTraceServiceResponse>, tonic::Status> {
        let _ = self.0.send(request.into_inner());
        Ok(tonic::Response::new(ExportTraceServiceResponse { partial_success: None }))
    }
}

/// The string value of the attribute `key`.
fn attribute<'a>(attributes: &'a [KeyValue], key: &str) -> Option<&'a str> {
    attributes.iter().find(|a| a.key == key).and_then(|a| match a.value.as_ref()?.value.as_ref()? {
        Value::StringValue(s) => Some(s.as_str()),
        _ => None,
    })
}

#[tokio::test(flavor = "multi_thread")]
async fn the_spans_of_grpc_requests_reach_the_collector() {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let endpoint = format!("http://{}", listener.local_addr().unwrap());
    let (tx, mut exports) = mpsc::unbounded_channel();
    let collector = tokio::spawn(
        tonic::transport::Server::builder()
            .add_service(TraceServiceServer::new(Collector(tx)))
            .serve_with_incoming(tokio_stream::wrappers::TcpListenerStream::new(listener)),
    );
    let (layer, traces) = dmp_server::telemetry::otlp_layer(&endpoint).expect("the exporter builds");
    let subscriber =
        tracing_subscriber::registry().with(tracing_subscriber::EnvFilter::new("info")).with(layer);
    tracing::subscriber::set_global_default(subscriber).expect("the only subscriber of this test binary");

    let server = TestServer::grpc_only().await;
    let client = server.client().await;
    within("info", client.info()).await.unwrap();
    let flush = tokio::task::spawn_blocking(move || {
        traces.force_flush().expect("flushed");
        traces
    });
    let traces = within("flush", flush).await.unwrap();
    let path = "/dmp.v1.ServerService/GetInfo";
    within("the request's span", async {
        loop {
            let export = exports.recv().await.expect("the collector runs");
            for resource in &export.resource_spans {
                let service = resource.resource.as_ref().map(|r| attribute(&r.attributes, "service.name"));
                assert_eq!(service, Some(Some(dmp_server::telemetry::SERVICE_NAME)));
                let spans = resource.scope_spans.iter().flat_map(|s| &s.spans);
                if spans
                    .into_iter()
                    .any(|s| s.name == "grpc" && attribute(&s.attributes, "rpc") == Some(path))
                {
                    return;
                }
            }
        }
    })
    .await;
    server.stop().await;
    within("shutdown", tokio::task::spawn_blocking(move || traces.shutdown())).await.unwrap().unwrap();
    collector.abort();
}
