//! Credentials: bearer tokens, kept only as SHA-256 digests and compared in constant time, and the common name of a
//! verified TLS client certificate.

use sha2::{Digest, Sha256};
use subtle::ConstantTimeEq;

/// The SHA-256 digest of a token.
pub(crate) type TokenDigest = [u8; 32];

/// The digest of `token`.
pub(crate) fn digest(token: &str) -> TokenDigest {
    Sha256::digest(token.as_bytes()).into()
}

/// The hex of a digest (what the access file's `token_sha256` holds).
pub(crate) fn digest_hex(token: &str) -> String {
    hex::encode(digest(token))
}

/// Parses the 64 hex digits of a `token_sha256`.
pub(crate) fn parse_digest(hex_digest: &str) -> Result<TokenDigest, String> {
    let mut out = [0u8; 32];
    hex::decode_to_slice(hex_digest.trim(), &mut out).map_err(|_| {
        "must be the 64 hex digits of a SHA-256 digest (`sha256sum` of the token)".to_string()
    })?;
    Ok(out)
}

/// The index of the digest in `digests` equal to `candidate`. Every digest is compared, each in constant time, so
/// that the time taken says nothing of which one matched or how much of one did.
pub(crate) fn find(
    digests: impl Iterator<Item = Option<TokenDigest>>,
    candidate: &TokenDigest,
) -> Option<usize> {
    let mut found = None;
    for (i, d) in digests.enumerate() {
        let Some(d) = d else { continue };
        if bool::from(d.ct_eq(candidate)) && found.is_none() {
            found = Some(i);
        }
    }
    found
}

/// The token of an `authorization` header value: `Bearer <token>` (the scheme in any case).
pub(crate) fn bearer(header: &str) -> Option<&str> {
    let (scheme, token) = header.split_once(' ')?;
    let token = token.trim();
    (scheme.eq_ignore_ascii_case("bearer") && !token.is_empty()).then_some(token)
}

/// The common name of a DER certificate's subject (the first one), if it has one.
pub(crate) fn common_name(der: &[u8]) -> Option<String> {
    let (_, cert) = x509_parser::parse_x509_certificate(der).ok()?;
    let cn = cert.subject().iter_common_name().next()?;
    cn.as_str().ok().map(str::to_owned)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_token_is_found_by_its_digest_only() {
        let digests = [Some(digest("alpha")), None, Some(digest("beta"))];
        assert_eq!(find(digests.iter().copied(), &digest("beta")), Some(2));
        assert_eq!(find(digests.iter().copied(), &digest("gamma")), None);
        assert_eq!(digest_hex("test"), "9f86d081884c7d659a2feaa0c55ad015a3bf4f1b2b0b822cd15d6c15b0f00a08");
        assert_eq!(parse_digest(&digest_hex("test")).unwrap(), digest("test"));
        assert!(parse_digest("9f86d08").is_err());
        assert!(parse_digest(&"zz".repeat(32)).is_err());
    }

    #[test]
    fn bearer_headers() {
        assert_eq!(bearer("Bearer abc"), Some("abc"));
        assert_eq!(bearer("bearer  abc "), Some("abc"));
        assert_eq!(bearer("Basic abc"), None);
        assert_eq!(bearer("Bearer "), None);
        assert_eq!(bearer("Bearer"), None);
    }

    #[test]
    fn the_common_name_of_a_certificate() {
        let mut params = rcgen::CertificateParams::new(vec!["localhost".into()]).unwrap();
        params.distinguished_name.push(rcgen::DnType::CommonName, "panda-1");
        let key = rcgen::KeyPair::generate().unwrap();
        let cert = params.self_signed(&key).unwrap();
        assert_eq!(common_name(cert.der()).as_deref(), Some("panda-1"));
        assert_eq!(common_name(b"not a certificate"), None);
    }
}
