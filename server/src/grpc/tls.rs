//! gRPC over TLS (rustls, no OpenSSL): the server's certificate and key, and the CA of client certificates for
//! mutual TLS. Clients without a certificate may still present a bearer token; a certificate that is presented must
//! be signed by that CA.

use std::path::Path;
use std::time::Duration;

use tonic::transport::{Certificate, Identity, ServerTlsConfig};

use crate::config::SecurityConfig;
use crate::error::ServerError;

/// A TLS handshake that has not completed by then is dropped (it holds no other connection up).
const HANDSHAKE_TIMEOUT: Duration = Duration::from_secs(10);

/// The TLS configuration of `security`; None without a certificate.
pub(crate) fn server_tls(security: &SecurityConfig) -> Result<Option<ServerTlsConfig>, ServerError> {
    let (cert, key) = match (&security.tls_cert, &security.tls_key) {
        (Some(cert), Some(key)) => (cert, key),
        (None, None) if security.tls_client_ca.is_none() => return Ok(None),
        _ => {
            return Err(ServerError::FailedPrecondition(
                "security: tls_cert and tls_key go together, and tls_client_ca needs them".into(),
            ));
        }
    };
    install_crypto_provider();
    let identity = Identity::from_pem(read("security.tls_cert", cert)?, read("security.tls_key", key)?);
    let mut tls = ServerTlsConfig::new().identity(identity).timeout(HANDSHAKE_TIMEOUT);
    if let Some(ca) = &security.tls_client_ca {
        tls = tls
            .client_ca_root(Certificate::from_pem(read("security.tls_client_ca", ca)?))
            .client_auth_optional(true);
    }
    Ok(Some(tls))
}

/// rustls' process-wide cryptography: ring (the one this build links). Installing it twice is harmless.
pub(crate) fn install_crypto_provider() {
    let _ = rustls::crypto::ring::default_provider().install_default();
}

fn read(field: &str, path: &Path) -> Result<Vec<u8>, ServerError> {
    let bytes = std::fs::read(path).map_err(|e| {
        ServerError::FailedPrecondition(format!("{field}: cannot read {}: {e}", path.display()))
    })?;
    if !bytes.windows(11).any(|w| w == b"-----BEGIN ") {
        return Err(ServerError::FailedPrecondition(format!("{field}: {} is not PEM", path.display())));
    }
    Ok(bytes)
}
