//! The access file (`--access FILE`, TOML): the identities, their roles, their cells and robots, and how each is
//! recognised (a bearer token's SHA-256 digest, a TLS client certificate's common name).
//!
//! ```toml
//! [[identity]]
//! name = "panda-1"
//! role = "robot"
//! cells = ["cell-a"]
//! robots = ["panda-1"]
//! token_sha256 = "9f86d081884c7d659a2feaa0c55ad015a3bf4f1b2b0b822cd15d6c15b0f00a08"
//! cert_common_name = "panda-1"
//! ```

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::credential::{self, TokenDigest};
use super::role::{Role, Scope};

/// Why an access file was refused.
#[derive(Debug, Error)]
pub enum AccessError {
    /// The file could not be read.
    #[error("cannot read the access file {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// Not TOML of the expected shape.
    #[error("invalid access file: {0}")]
    Syntax(String),
    /// An identity breaks a rule.
    #[error("invalid access file: identity {index} (`{name}`): {field}: {reason}")]
    Identity {
        /// Its place in the file, from 1.
        index: usize,
        /// Its name.
        name: String,
        /// The field at fault.
        field: &'static str,
        /// The rule.
        reason: String,
    },
    /// The file as a whole breaks a rule.
    #[error("invalid access file: {0}")]
    File(String),
}

/// One `[[identity]]` as written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct IdentityEntry {
    /// Shown in logs and refusals.
    pub name: String,
    /// What it may do.
    pub role: Role,
    /// Its cells; `*` is every cell.
    #[serde(default)]
    pub cells: Vec<String>,
    /// Its robots (robots, and planners limited to some robots); empty is every robot of its cells.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub robots: Vec<String>,
    /// Hex SHA-256 digest of its bearer token.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub token_sha256: Option<String>,
    /// The common name of its TLS client certificate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cert_common_name: Option<String>,
}

/// The file as written.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct AccessFile {
    /// Every identity.
    #[serde(default)]
    pub identity: Vec<IdentityEntry>,
}

/// An identity, checked.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Identity {
    /// Its name.
    pub name: String,
    /// Its role.
    pub role: Role,
    /// Its cells and robots.
    pub scope: Scope,
    /// The digest of its token.
    pub token: Option<TokenDigest>,
    /// Its certificate's common name.
    pub cert_common_name: Option<String>,
}

/// The identities of an access file, checked.
#[derive(Debug, Clone, Default)]
pub(crate) struct Access {
    identities: Vec<Arc<Identity>>,
}

impl Access {
    /// Reads and checks the access file at `path`.
    pub(crate) fn load(path: &Path) -> Result<Self, AccessError> {
        let text = std::fs::read_to_string(path)
            .map_err(|source| AccessError::Read { path: path.to_owned(), source })?;
        Self::parse(&text)
    }

    /// Checks the text of an access file.
    pub(crate) fn parse(text: &str) -> Result<Self, AccessError> {
        // The message and the line, never the line's text: a secret written under a wrong key would be logged.
        let file: AccessFile = toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1);
            AccessError::Syntax(match line {
                Some(l) => format!("line {l}: {}", e.message()),
                None => e.message().to_owned(),
            })
        })?;
        Self::from_file(&file)
    }

    /// Checks an access file.
    pub(crate) fn from_file(file: &AccessFile) -> Result<Self, AccessError> {
        if file.identity.is_empty() {
            return Err(AccessError::File(
                "no `[[identity]]`: nobody could use the server (give at least an admin)".into(),
            ));
        }
        let mut names = HashSet::new();
        let mut tokens = HashSet::new();
        let mut common_names = HashSet::new();
        let mut identities = Vec::with_capacity(file.identity.len());
        for (i, entry) in file.identity.iter().enumerate() {
            let fail = |field: &'static str, reason: String| AccessError::Identity {
                index: i + 1,
                name: entry.name.clone(),
                field,
                reason,
            };
            let identity = check(entry).map_err(|(field, reason)| fail(field, reason))?;
            if !names.insert(identity.name.clone()) {
                return Err(fail("name", "is given to two identities".into()));
            }
            if let Some(t) = identity.token
                && !tokens.insert(t)
            {
                return Err(fail("token_sha256", "is the token of another identity".into()));
            }
            if let Some(cn) = &identity.cert_common_name
                && !common_names.insert(cn.clone())
            {
                return Err(fail("cert_common_name", "is the common name of another identity".into()));
            }
            identities.push(Arc::new(identity));
        }
        Ok(Self { identities })
    }

    /// Every identity.
    pub(crate) fn identities(&self) -> &[Arc<Identity>] {
        &self.identities
    }

    /// The identity whose token digest is `digest` (every digest compared in constant time).
    pub(crate) fn by_token(&self, digest: &TokenDigest) -> Option<&Arc<Identity>> {
        credential::find(self.identities.iter().map(|i| i.token), digest).map(|i| &self.identities[i])
    }

    /// The identity whose certificate's common name is `cn`.
    pub(crate) fn by_common_name(&self, cn: &str) -> Option<&Arc<Identity>> {
        self.identities.iter().find(|i| i.cert_common_name.as_deref() == Some(cn))
    }
}

/// Checks one identity: `Err((field, reason))`.
fn check(e: &IdentityEntry) -> Result<Identity, (&'static str, String)> {
    let name_rule =
        |field: &'static str, s: &str| dmp_proto::keys::check_name(field, s).map_err(|err| (field, err.rule));
    name_rule("name", &e.name)?;
    for cell in &e.cells {
        if cell != "*" {
            name_rule("cells", cell)?;
        }
    }
    for robot in &e.robots {
        // A prefix (`sim.*`) names every robot id that starts with it.
        match robot.strip_suffix(super::role::PREFIX_WILDCARD) {
            Some(prefix) if !prefix.is_empty() => name_rule("robots", prefix)?,
            Some(_) => {
                return Err((
                    "robots",
                    "`*` alone: leave `robots` empty for every robot of its cells".into(),
                ));
            }
            None => name_rule("robots", robot)?,
        }
    }
    if e.cells.is_empty() && e.role != Role::Admin {
        return Err(("cells", "is empty: list its cells, or `*` for every cell".into()));
    }
    match e.role {
        Role::Robot if e.robots.is_empty() => {
            return Err(("robots", "is empty: a robot identity acts only as the robot ids listed".into()));
        }
        Role::Perception if !e.robots.is_empty() => {
            return Err(("robots", "a perception identity acts on cells, not robots: remove it".into()));
        }
        _ => {}
    }
    let token = e
        .token_sha256
        .as_deref()
        .map(credential::parse_digest)
        .transpose()
        .map_err(|r| ("token_sha256", r))?;
    let cert_common_name = match e.cert_common_name.as_deref() {
        Some(cn) if cn.trim().is_empty() => return Err(("cert_common_name", "is empty".into())),
        other => other.map(str::to_owned),
    };
    if token.is_none() && cert_common_name.is_none() {
        return Err((
            "token_sha256",
            "neither it nor `cert_common_name` is given: nothing recognises it".into(),
        ));
    }
    Ok(Identity {
        name: e.name.clone(),
        role: e.role,
        scope: Scope { cells: e.cells.clone(), robots: e.robots.clone() },
        token,
        cert_common_name,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::access::credential::{digest, digest_hex};

    fn file(extra: &str) -> String {
        format!(
            "[[identity]]\nname = \"panda-1\"\nrole = \"robot\"\ncells = [\"cell-a\"]\nrobots = [\"panda-1\"]\n\
             token_sha256 = \"{}\"\n{extra}",
            digest_hex("secret-1")
        )
    }

    #[test]
    fn identities_are_found_by_token_and_by_common_name() {
        let text = format!(
            "{}\n[[identity]]\nname = \"eyes\"\nrole = \"perception\"\ncells = [\"*\"]\ncert_common_name = \"cam\"\n",
            file("")
        );
        let access = Access::parse(&text).unwrap();
        assert_eq!(access.by_token(&digest("secret-1")).unwrap().name, "panda-1");
        assert!(access.by_token(&digest("secret-2")).is_none());
        assert_eq!(access.by_common_name("cam").unwrap().role, Role::Perception);
        assert!(access.by_common_name("panda-1").is_none());
    }

    #[test]
    fn each_refusal_names_the_identity_and_the_field() {
        let refused = |text: &str, needle: &str| {
            let e = Access::parse(text).unwrap_err().to_string();
            assert!(e.contains(needle), "{e} should mention {needle}");
        };
        refused(&file("colour = \"red\""), "line 7: unknown field `colour`");
        let leaked =
            Access::parse("[[identity]]\nname = \"x\"\ntoken = \"s3cret\"\n").unwrap_err().to_string();
        assert!(!leaked.contains("s3cret"), "{leaked}");
        refused(&file("").replace("robot\"", "pilot\""), "unknown variant `pilot`");
        refused(&file("").replace("robots = [\"panda-1\"]", "robots = []"), "identity 1 (`panda-1`): robots");
        refused(&file("").replace(&digest_hex("secret-1"), "9f86d08"), "token_sha256: must be the 64 hex");
        refused(&file("").replace("cells = [\"cell-a\"]", "cells = [\"a/b\"]"), "cells: has `/`");
        refused(&format!("{}\n{}", file(""), file("")), "identity 2 (`panda-1`): name: is given to two");
        refused("", "no `[[identity]]`");
        let anonymous = "[[identity]]\nname = \"x\"\nrole = \"admin\"\n";
        refused(anonymous, "nothing recognises it");
    }
}
