//! Who may do what: identities from the access file (`--access FILE`), recognised by a bearer token or a TLS
//! client certificate, each with a role and the cells and robots it acts on. Every gRPC request is authenticated
//! by one layer ([`crate::grpc::authentication`]) before any handler runs, and authorised by its handler with the [`Action`] it
//! performs; streams are authorised again whenever the file is reloaded (SIGHUP), and end with PERMISSION_DENIED
//! once it no longer allows them. Every change is logged on the tracing target `audit` with its identity, and so is
//! every refused attempt, rate-limited ([`audit`]).
//!
//! Without an access file the server is open: every caller is `anonymous` with the admin role (the server then
//! listens on loopback only, unless told `--insecure`).

pub(crate) mod audit;
pub(crate) mod credential;
pub(crate) mod exposure;
pub(crate) mod file;
pub mod init;
pub(crate) mod role;
pub(crate) mod zenoh_acl;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use tokio::sync::watch;
use tracing::{error, info};

pub(crate) use file::{Access, AccessError, Identity};
pub(crate) use role::{Action, Role};

use crate::config::SecurityConfig;
use crate::error::ServerError;
use credential::TokenDigest;

/// How a caller proved who it is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Credential {
    /// No access file: nothing to prove.
    Open,
    /// A bearer token (its digest).
    Token(TokenDigest),
    /// A verified TLS client certificate (its common name).
    CommonName(String),
}

/// The identity a request runs as.
#[derive(Debug, Clone)]
pub(crate) struct Caller {
    identity: Option<Arc<Identity>>,
    credential: Credential,
}

impl Caller {
    /// The caller of an open server (no access file): everything is allowed.
    pub(crate) fn open() -> Self {
        Self { identity: None, credential: Credential::Open }
    }

    /// Its name (`anonymous` on an open server).
    pub(crate) fn name(&self) -> &str {
        self.identity.as_ref().map_or("anonymous", |i| &i.name)
    }

    /// Its role (admin on an open server).
    pub(crate) fn role(&self) -> Role {
        self.identity.as_ref().map_or(Role::Admin, |i| i.role)
    }

    /// Whether it may do `action`; PERMISSION_DENIED naming the identity and the action if not. Not audited here:
    /// handlers also ask it to filter; a request refused with it is audited by the authentication layer.
    pub(crate) fn check(&self, action: &Action<'_>) -> Result<(), ServerError> {
        match &self.identity {
            None => Ok(()),
            Some(i) if role::allows(i.role, &i.scope, action) => Ok(()),
            Some(i) => Err(denied(i, action)),
        }
    }

    /// Whether its credential, under `access` (a reloaded file), still allows `action`: the identity may have
    /// gone, lost the credential, or changed role or scope.
    pub(crate) fn check_again(
        &self,
        access: Option<&Access>,
        action: &Action<'_>,
    ) -> Result<(), ServerError> {
        let again = match (&self.credential, access) {
            (Credential::Open, _) => return Ok(()),
            (_, None) => return Ok(()),
            (Credential::Token(d), Some(a)) => a.by_token(d),
            (Credential::CommonName(cn), Some(a)) => a.by_common_name(cn),
        };
        match again {
            Some(i) => {
                Caller { identity: Some(i.clone()), credential: self.credential.clone() }.check(action)
            }
            None => Err(ServerError::PermissionDenied(format!(
                "identity `{}` is no longer in the access file: it may not {}",
                self.name(),
                action.describe()
            ))),
        }
    }
}

fn denied(i: &Identity, action: &Action<'_>) -> ServerError {
    ServerError::PermissionDenied(format!("identity `{}` ({}) may not {}", i.name, i.role, action.describe()))
}

/// The access file in force, reloadable.
#[derive(Debug)]
pub(crate) struct AccessControl {
    path: Option<PathBuf>,
    current: watch::Sender<Option<Arc<Access>>>,
}

impl AccessControl {
    /// An open server: no access file.
    pub(crate) fn open() -> Self {
        Self { path: None, current: watch::Sender::new(None) }
    }

    /// The access file at `path`, checked.
    pub(crate) fn load(path: &Path) -> Result<Self, AccessError> {
        let access = Access::load(path)?;
        info!(file = %path.display(), identities = access.identities().len(), "access file loaded");
        Ok(Self { path: Some(path.to_owned()), current: watch::Sender::new(Some(Arc::new(access))) })
    }

    /// The access control `security` configures: its access file, checked, or an open server without one.
    pub(crate) fn from_config(security: &SecurityConfig) -> Result<Self, ServerError> {
        match &security.access {
            Some(path) => Self::load(path).map_err(|e| ServerError::FailedPrecondition(e.to_string())),
            None => Ok(Self::open()),
        }
    }

    /// Whether an access file is in force.
    pub(crate) fn enabled(&self) -> bool {
        self.path.is_some()
    }

    /// Follows the reloads: the identities in force now, and every change.
    pub(crate) fn reloads(&self) -> watch::Receiver<Option<Arc<Access>>> {
        self.current.subscribe()
    }

    /// The identities in force (None on an open server).
    pub(crate) fn current(&self) -> Option<Arc<Access>> {
        self.current.borrow().clone()
    }

    /// Reads the file again. A file that is refused changes nothing (the error says why); streams the new file
    /// no longer allows end with PERMISSION_DENIED.
    pub(crate) fn reload(&self) -> Result<usize, AccessError> {
        let Some(path) = &self.path else { return Ok(0) };
        match Access::load(path) {
            Ok(access) => {
                let n = access.identities().len();
                self.current.send_replace(Some(Arc::new(access)));
                info!(target: "audit", file = %path.display(), identities = n, "access file reloaded");
                Ok(n)
            }
            Err(e) => {
                error!(error = %e, "access file not reloaded: the previous one stays in force");
                Err(e)
            }
        }
    }

    /// The caller presenting `token` (the value of a bearer token), or else the verified certificate of common
    /// name `common_name`. UNAUTHENTICATED when neither names an identity (the token itself is never repeated).
    pub(crate) fn authenticate(
        &self,
        token: Option<&str>,
        common_name: Option<&str>,
    ) -> Result<Caller, ServerError> {
        self.identify(token, common_name).inspect_err(|e| audit::refused(UNAUTHENTICATED, "authenticate", e))
    }

    fn identify(&self, token: Option<&str>, common_name: Option<&str>) -> Result<Caller, ServerError> {
        let Some(access) = self.current() else { return Ok(Caller::open()) };
        if let Some(token) = token {
            let d = credential::digest(token);
            return match access.by_token(&d) {
                Some(i) => Ok(Caller { identity: Some(i.clone()), credential: Credential::Token(d) }),
                None => Err(ServerError::Unauthenticated("the bearer token matches no identity".into())),
            };
        }
        if let Some(cn) = common_name {
            return match access.by_common_name(cn) {
                Some(i) => {
                    Ok(Caller { identity: Some(i.clone()), credential: Credential::CommonName(cn.into()) })
                }
                None => Err(ServerError::Unauthenticated(format!(
                    "the client certificate's common name `{cn}` matches no identity"
                ))),
            };
        }
        Err(ServerError::Unauthenticated(
            "no credentials: send `authorization: Bearer <token>` or a TLS client certificate".into(),
        ))
    }
}

/// The identity the audit log names a caller that proved none by.
pub(crate) const UNAUTHENTICATED: &str = "unauthenticated";

/// What a long request (a stream, a watch) was allowed to do, checked again at every reload of the access file.
pub(crate) struct Grant {
    caller: Caller,
    reloads: watch::Receiver<Option<Arc<Access>>>,
    recheck: Recheck,
}

/// How a grant is checked again at a reload.
type Recheck = Box<dyn Fn(&Caller, Option<&Access>) -> Result<(), ServerError> + Send + Sync>;

impl std::fmt::Debug for Grant {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Grant").field("caller", &self.caller.name()).finish_non_exhaustive()
    }
}

impl Grant {
    /// Completes with PERMISSION_DENIED once a reload no longer allows the request; never on an open server.
    pub(crate) async fn revoked(&mut self) -> ServerError {
        loop {
            if self.reloads.changed().await.is_err() {
                return std::future::pending().await;
            }
            if let Err(e) = self.check_now() {
                return e;
            }
        }
    }

    /// Checks again if the file was reloaded since the last check (for loops that do not wait); a refusal ends
    /// the request, audited.
    pub(crate) fn check_now(&mut self) -> Result<(), ServerError> {
        let access = self.reloads.borrow_and_update().clone();
        (self.recheck)(&self.caller, access.as_deref())
            .inspect_err(|e| audit::refused(self.caller.name(), "stream", e))
    }
}

impl AccessControl {
    /// The grant of `caller` for a long request, checked now against the file in force and again at every
    /// reload with `recheck` (which calls [`Caller::check_again`] with the request's action).
    pub(crate) fn grant(
        &self,
        caller: Caller,
        recheck: impl Fn(&Caller, Option<&Access>) -> Result<(), ServerError> + Send + Sync + 'static,
    ) -> Result<Grant, ServerError> {
        let mut reloads = self.current.subscribe();
        // Checked against what is in force now: a reload between the request's authentication and here counts.
        let access = reloads.borrow_and_update().clone();
        recheck(&caller, access.as_deref()).inspect_err(|e| audit::refused(caller.name(), "stream", e))?;
        Ok(Grant { caller, reloads, recheck: Box::new(recheck) })
    }

    /// `caller` as the file in force now knows it: the request was authenticated when its headers arrived, and a
    /// reload may have come before its handler runs. UNAUTHENTICATED when its credential is gone.
    pub(crate) fn refresh(&self, caller: &Caller) -> Result<Caller, ServerError> {
        let Some(access) = self.current() else { return Ok(caller.clone()) };
        let identity = match &caller.credential {
            Credential::Open => return Ok(caller.clone()),
            Credential::Token(d) => access.by_token(d),
            Credential::CommonName(cn) => access.by_common_name(cn),
        };
        match identity {
            Some(i) => Ok(Caller { identity: Some(i.clone()), credential: caller.credential.clone() }),
            None => {
                let e = ServerError::Unauthenticated(
                    "the credential is no longer in the access file (it was reloaded)".into(),
                );
                audit::refused(caller.name(), "authenticate", &e);
                Err(e)
            }
        }
    }
}

/// Logs a change on the tracing target `audit`, with the identity that made it.
#[macro_export]
macro_rules! audit {
    ($caller:expr, $action:expr $(, $($fields:tt)*)?) => {
        ::tracing::info!(target: "audit", identity = %$caller.name(), role = %$caller.role(), action = $action
            $(, $($fields)*)?)
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    fn access_file(dir: &Path, robots: &str) -> PathBuf {
        let path = dir.join("access.toml");
        let text = format!(
            "[[identity]]\nname = \"panda-1\"\nrole = \"robot\"\ncells = [\"a\"]\nrobots = [{robots}]\n\
             token_sha256 = \"{}\"\n",
            credential::digest_hex("t1")
        );
        std::fs::write(&path, text).unwrap();
        path
    }

    #[test]
    fn callers_are_recognised_and_checked_again_after_a_reload() {
        let dir = tempfile::tempdir().unwrap();
        let path = access_file(dir.path(), "\"panda-1\"");
        let control = AccessControl::load(&path).unwrap();
        let caller = control.authenticate(Some("t1"), None).unwrap();
        assert_eq!((caller.name(), caller.role()), ("panda-1", Role::Robot));
        let own = Action::Execute { cell: "a", robots: &["panda-1"] };
        caller.check(&own).unwrap();
        let e = caller.check(&Action::Execute { cell: "a", robots: &["panda-2"] }).unwrap_err().to_string();
        assert_eq!(e, "identity `panda-1` (robot) may not execute robot `panda-2` in cell `a`");
        let e = control.authenticate(Some("t2"), Some("panda-1")).unwrap_err().to_string();
        assert!(e.contains("matches no identity") && !e.contains("t2"), "{e}");
        assert!(control.authenticate(None, None).is_err());
        // The file changes: the robot is another one now.
        access_file(dir.path(), "\"panda-9\"");
        control.reload().unwrap();
        // A request authenticated before the reload, handled after it: its caller is seen as the file says now,
        // and a stream it starts is refused at once.
        let now = control.refresh(&caller).unwrap();
        assert!(now.check(&own).is_err());
        let recheck = |c: &Caller, a: Option<&Access>| {
            c.check_again(a, &Action::Execute { cell: "a", robots: &["panda-1"] })
        };
        assert!(control.grant(caller.clone(), recheck).is_err());
        let e = caller.check_again(control.current().as_deref(), &own).unwrap_err();
        assert!(matches!(e, ServerError::PermissionDenied(_)), "{e}");
        // A broken file keeps the one in force.
        std::fs::write(&path, "[[identity]]\nname = 3\n").unwrap();
        assert!(control.reload().is_err());
        assert_eq!(control.current().unwrap().identities()[0].scope.robots, ["panda-9"]);
    }

    #[test]
    fn an_open_server_lets_everyone_do_everything() {
        let control = AccessControl::open();
        let caller = control.authenticate(None, None).unwrap();
        assert_eq!(caller.name(), "anonymous");
        caller.check(&Action::DeletePrimitive { robot: "r" }).unwrap();
    }
}
