//! Whether a server dialled as `http://` speaks TLS: plaintext HTTP/2 against a TLS server fails with words such
//! as "broken pipe" or "connection reset", which do not say that the URL should have been `https://`. The probe
//! sends a TLS ClientHello and reads the first bytes of the answer: a TLS server answers with a TLS record (a
//! ServerHello or an alert), a plaintext one with HTTP.

use std::time::Duration;

/// How long the probe waits to connect, and then for the answer.
pub const PROBE_TIMEOUT: Duration = Duration::from_secs(1);

/// A TLS 1.3 ClientHello a TLS server answers with its ServerHello: three cipher suites, and the extensions TLS 1.3
/// needs (supported versions, the x25519 group with a key share, signature algorithms). Its random and key are
/// fixed: nothing comes of the handshake but its first answer.
fn client_hello() -> Vec<u8> {
    fn u16be(n: usize) -> [u8; 2] {
        (n as u16).to_be_bytes()
    }
    fn extension(kind: u16, data: &[u8]) -> Vec<u8> {
        [&kind.to_be_bytes()[..], &u16be(data.len()), data].concat()
    }
    // x25519's base point as the key share: a valid public key.
    let mut share = vec![0x00, 0x1d, 0x00, 0x20, 9];
    share.resize(4 + 32, 0);
    let extensions = [
        extension(0x002b, &[2, 0x03, 0x04]),
        extension(0x000a, &[0x00, 0x02, 0x00, 0x1d]),
        extension(0x0033, &[&u16be(share.len())[..], &share].concat()),
        // ecdsa_secp256r1_sha256, rsa_pss_rsae_sha256, rsa_pkcs1_sha256.
        extension(0x000d, &[0x00, 0x06, 0x04, 0x03, 0x08, 0x04, 0x04, 0x01]),
    ]
    .concat();
    let suites = [0x13, 0x01, 0x13, 0x02, 0x13, 0x03];
    let body = [
        &[0x03, 0x03][..],
        &[0u8; 32],
        &[0],
        &u16be(suites.len()),
        &suites,
        &[1, 0],
        &u16be(extensions.len()),
        &extensions,
    ]
    .concat();
    let handshake = [&[1u8][..], &(body.len() as u32).to_be_bytes()[1..], &body].concat();
    [&[0x16, 0x03, 0x01][..], &u16be(handshake.len()), &handshake].concat()
}

/// Whether the server at `url` (`http://HOST:PORT` or `HOST:PORT`) answers a ClientHello with a TLS record. False
/// when it cannot be told (no connection, no answer within [`PROBE_TIMEOUT`]).
pub async fn speaks_tls(url: &str) -> bool {
    let authority = url.split("://").last().unwrap_or(url).split('/').next().unwrap_or_default();
    let probe = async {
        let tcp = tokio::time::timeout(PROBE_TIMEOUT, tokio::net::TcpStream::connect(authority))
            .await
            .ok()?
            .ok()?;
        // `try_write` and `try_read` need only tokio's `net`.
        let hello = client_hello();
        let mut sent = 0;
        while sent < hello.len() {
            tcp.writable().await.ok()?;
            match tcp.try_write(&hello[sent..]) {
                Ok(n) => sent += n,
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
                Err(_) => return None,
            }
        }
        let mut first = [0u8; 2];
        let mut read = 0;
        while read < first.len() {
            tcp.readable().await.ok()?;
            match tcp.try_read(&mut first[read..]) {
                Ok(0) => return None,
                Ok(n) => read += n,
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
                Err(_) => return None,
            }
        }
        // A handshake (22) or alert (21) record of a TLS 1.x version.
        Some(matches!(first, [0x15 | 0x16, 0x03]))
    };
    tokio::time::timeout(PROBE_TIMEOUT * 2, probe).await.ok().flatten().unwrap_or(false)
}

/// The hint for a call to `url` that failed at the transport: use `https://` when it is `http://` and the server
/// speaks TLS; `None` otherwise.
pub async fn https_hint(url: &str) -> Option<String> {
    let rest = url.strip_prefix("http://")?;
    speaks_tls(url).await.then(|| {
        format!(
            "the server at {url} speaks TLS: use https://{rest} (with --tls-ca, the CA that signed its certificate)"
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_client_hello_is_one_consistent_record() {
        let hello = client_hello();
        assert_eq!(hello.len(), 125);
        assert_eq!(usize::from(u16::from_be_bytes([hello[3], hello[4]])), hello.len() - 5);
        assert_eq!(u32::from_be_bytes([0, hello[6], hello[7], hello[8]]) as usize, hello.len() - 9);
    }

    #[tokio::test]
    async fn a_plaintext_listener_is_not_taken_for_tls() {
        use std::io::{Read, Write};
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap();
        std::thread::spawn(move || {
            let (mut s, _) = listener.accept().unwrap();
            let mut buf = [0u8; 64];
            let _ = s.read(&mut buf);
            let _ = s.write_all(b"HTTP/1.1 400 Bad Request\r\n\r\n");
        });
        assert!(!speaks_tls(&format!("http://{addr}")).await);
        assert_eq!(https_hint("http://127.0.0.1:9").await, None, "nothing listens: cannot be told");
    }
}
