//! Traces to OpenTelemetry (`--otlp-endpoint`, off by default): the server's tracing spans (one per gRPC request,
//! `grpc` with its `rpc` path, and whatever is logged inside it) exported over OTLP/gRPC to a collector, in batches
//! from the SDK's own thread. Logging to stderr is unchanged.

use opentelemetry::trace::TracerProvider as _;
use opentelemetry_otlp::WithExportConfig;
use opentelemetry_sdk::Resource;
use opentelemetry_sdk::trace::SdkTracerProvider;
use tracing::Subscriber;
use tracing_subscriber::Layer;
use tracing_subscriber::registry::LookupSpan;

use crate::error::ServerError;

/// The service name the spans carry.
pub const SERVICE_NAME: &str = "dmp-server";

/// The tracing layer that exports spans to the OTLP/gRPC collector at `endpoint` (e.g. `http://collector:4317`),
/// and its provider, to shut down at exit (it flushes what is pending). Call it within a tokio runtime: the
/// exporter's channel lives on it.
pub fn otlp_layer<S>(endpoint: &str) -> Result<(impl Layer<S> + use<S>, SdkTracerProvider), ServerError>
where
    S: Subscriber + for<'a> LookupSpan<'a>,
{
    let exporter = opentelemetry_otlp::SpanExporter::builder()
        .with_tonic()
        .with_endpoint(endpoint)
        .build()
        .map_err(|e| ServerError::FailedPrecondition(format!("otlp_endpoint: {endpoint}: {e}")))?;
    let provider = SdkTracerProvider::builder()
        .with_batch_exporter(exporter)
        .with_resource(Resource::builder().with_service_name(SERVICE_NAME).build())
        .build();
    let layer = tracing_opentelemetry::layer().with_tracer(provider.tracer(SERVICE_NAME));
    Ok((layer, provider))
}
