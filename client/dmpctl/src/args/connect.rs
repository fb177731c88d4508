//! The flags that reach a secured server: TLS (`--tls-ca`, and `--tls-cert` with `--tls-key` for mutual TLS) and a
//! bearer token (`DMP_TOKEN`, `--token-file`, or `--token`, which is warned about: it shows in `ps`).

use std::path::PathBuf;

use clap::Args;
use dmp_client::ClientError;
use dmp_client::connect::{ConnectOptions, TlsOptions};

/// The environment variable holding the bearer token.
pub(crate) const TOKEN_ENV: &str = "DMP_TOKEN";

/// See the module.
#[derive(Clone, Default, Args)]
pub(crate) struct ConnectArgs {
    /// The CA that signed the server's certificate (PEM): connect over TLS (`https://`).
    #[arg(long, global = true, value_name = "FILE", env = "DMP_TLS_CA")]
    pub(crate) tls_ca: Option<PathBuf>,
    /// This client's certificate (PEM), for mutual TLS; its common name names an identity.
    #[arg(long, global = true, value_name = "FILE", requires = "tls_key")]
    pub(crate) tls_cert: Option<PathBuf>,
    /// This client's private key (PEM).
    #[arg(long, global = true, value_name = "FILE", requires = "tls_cert")]
    pub(crate) tls_key: Option<PathBuf>,
    /// A file holding the bearer token (as `dmp-server access init` writes them).
    #[arg(long, global = true, value_name = "FILE", conflicts_with = "token")]
    pub(crate) token_file: Option<PathBuf>,
    /// The bearer token. Prefer `DMP_TOKEN` or `--token-file`: a token on the command line shows in `ps`.
    #[arg(long, global = true, value_name = "TOKEN")]
    pub(crate) token: Option<String>,
}

impl std::fmt::Debug for ConnectArgs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ConnectArgs")
            .field("tls_ca", &self.tls_ca)
            .field("tls_cert", &self.tls_cert)
            .field("tls_key", &self.tls_key)
            .field("token_file", &self.token_file)
            .field("token", &self.token.as_ref().map(|_| "<hidden>"))
            .finish()
    }
}

impl ConnectArgs {
    /// The options to connect with; `token_from_env` is the value of `DMP_TOKEN`. Warnings go to `warn`.
    pub(crate) fn options(
        &self,
        token_from_env: Option<String>,
        mut warn: impl FnMut(&str),
    ) -> Result<ConnectOptions, ClientError> {
        let token = match (&self.token, &self.token_file) {
            (Some(t), _) => {
                warn(
                    "a token given with --token shows in the process list: prefer DMP_TOKEN or --token-file",
                );
                Some(t.clone())
            }
            (None, Some(path)) => Some(
                std::fs::read_to_string(path)
                    .map_err(|e| {
                        ClientError::argument("token-file", format!("cannot read {}: {e}", path.display()))
                    })?
                    .trim()
                    .to_owned(),
            ),
            (None, None) => token_from_env.filter(|t| !t.trim().is_empty()),
        };
        if token.as_deref().is_some_and(|t| t.trim().is_empty()) {
            return Err(ClientError::argument("token", "is empty"));
        }
        let tls = match &self.tls_ca {
            Some(ca) => Some(TlsOptions::from_files(ca, self.tls_cert.as_deref(), self.tls_key.as_deref())?),
            None if self.tls_cert.is_some() => {
                return Err(ClientError::argument(
                    "tls-cert",
                    "needs --tls-ca (the CA of the server's certificate)",
                ));
            }
            None => None,
        };
        Ok(ConnectOptions { token, tls, ..Default::default() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_token_comes_from_the_flag_with_a_warning_else_the_file_else_the_environment() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("t");
        std::fs::write(&file, "from-file\n").unwrap();
        let mut warnings = Vec::new();
        let flag = ConnectArgs { token: Some("from-flag".into()), ..Default::default() };
        let o = flag.options(Some("env".into()), |w| warnings.push(w.to_owned())).unwrap();
        assert_eq!(o.token.as_deref(), Some("from-flag"));
        assert_eq!(warnings.len(), 1);
        let from_file = ConnectArgs { token_file: Some(file), ..Default::default() };
        assert_eq!(
            from_file.options(Some("env".into()), |_| {}).unwrap().token.as_deref(),
            Some("from-file")
        );
        let none = ConnectArgs::default();
        assert_eq!(none.options(Some("env".into()), |_| {}).unwrap().token.as_deref(), Some("env"));
        assert_eq!(none.options(None, |_| {}).unwrap().token, None);
        let e = ConnectArgs { token_file: Some(dir.path().join("missing")), ..Default::default() }
            .options(None, |_| {})
            .unwrap_err()
            .to_string();
        assert!(e.contains("token-file"), "{e}");
    }
}
