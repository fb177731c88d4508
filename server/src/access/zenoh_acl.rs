//! The Zenoh access control generated from the access file: default deny, and for each identity with a
//! certificate common name (Zenoh knows a peer by its TLS certificate; bearer tokens are gRPC's) only the keys of
//! its role and cells:
//!
//! | role | keys | messages |
//! | --- | --- | --- |
//! | perception | `dmp/<cell>/obstacles/**` of its cells | publish and delete obstacles, answer the server's catch-up queries (declaring its queryable on `dmp/*/obstacles/**`, replying only for its cells), see its subscribers |
//! | planner | `dmp/<cell>/obstacles/**` of its cells; `dmp/<cell>/**` read | the same, and subscribe to its cells |
//! | observer | `dmp/<cell>/**` of its cells | subscribe and query only |
//! | server | `dmp/<cell>/**` of its cells; the plant's keys `dmp/@servers/**`, `dmp/@cells/**`, `dmp/@primitives/**` | everything: robot states and primitives are taken only from servers |
//! | admin | `dmp/**` and the plant's keys | everything |
//!
//! Perception, planner and observer identities may also ask the plant which server serves a cell (query and be
//! answered on `dmp/@cells/**` and `dmp/@servers/**`). The plant's keys start with a verbatim chunk, which `dmp/**`
//! does not match: they are named apart.
//!
//! Robots stream over gRPC and get nothing on Zenoh. A peer without a certificate of the cell's CA cannot connect
//! to a `tls/` endpoint with mutual TLS; one that connects otherwise (a `tcp/` endpoint) matches no subject and is
//! denied everything.

use serde_json::{Value, json};

use super::file::Access;
use super::role::Role;

/// What a publisher sends: samples, and answers to queries.
const PUBLISH: &[&str] = &["put", "delete", "declare_queryable", "reply", "liveliness_token"];
/// What a reader sends: its interests.
const READ: &[&str] = &["declare_subscriber", "query", "declare_liveliness_subscriber", "liveliness_query"];
/// What a reader is sent.
const SAMPLES: &[&str] = &["put", "delete", "reply", "liveliness_token", "declare_queryable"];
/// Every message.
const ALL: &[&str] = &[
    "put",
    "delete",
    "declare_queryable",
    "reply",
    "liveliness_token",
    "declare_subscriber",
    "query",
    "declare_liveliness_subscriber",
    "liveliness_query",
];

/// The plant's keys: servers' tokens and announcements, cells' servers, replicated primitives.
const PLANT_KEYS: &[&str] = &["dmp/@servers/**", "dmp/@cells/**", "dmp/@primitives/**"];
/// The plant's directory: which server serves a cell.
const DIRECTORY_KEYS: &[&str] = &["dmp/@servers/**", "dmp/@cells/**"];

/// What an identity may send in (ingress) and be sent (egress), on which keys.
struct Grant {
    what: &'static str,
    ingress: (&'static [&'static str], Vec<String>),
    egress: (&'static [&'static str], Vec<String>),
}

/// The `access_control` block of a Zenoh configuration for `access`.
pub(crate) fn access_control(access: &Access) -> Value {
    let (mut rules, mut subjects, mut policies) = (Vec::new(), Vec::new(), Vec::new());
    for identity in access.identities() {
        let Some(cn) = &identity.cert_common_name else { continue };
        let keys = |suffix: &str| -> Vec<String> {
            identity.scope.cells.iter().map(|c| format!("dmp/{c}/{suffix}")).collect()
        };
        // The server declares its subscriber and sends its catch-up queries on every cell's obstacles
        // (`dmp/*/obstacles/*`): a node must be told of them to publish (and to answer), whatever its cells. An
        // access rule covers a message only when its keys include the message's key.
        let obstacles = || Grant {
            what: "obstacles",
            ingress: (PUBLISH, keys("obstacles/**")),
            egress: (READ, vec!["dmp/*/obstacles/**".into()]),
        };
        // A node serving its latest obstacles declares one queryable on every cell's (`dmp/*/obstacles/**`, the
        // expression the server asks): the declaration is allowed for every cell, its replies only for its cells
        // (a reply is checked on its own key, by `obstacles`).
        let catch_up = || Grant {
            what: "catch-up",
            ingress: (&["declare_queryable"], vec!["dmp/*/obstacles/**".into()]),
            egress: (&["query"], vec!["dmp/*/obstacles/**".into()]),
        };
        let read = || Grant { what: "read", ingress: (READ, keys("**")), egress: (SAMPLES, keys("**")) };
        let all =
            |keys: Vec<String>| Grant { what: "all", ingress: (ALL, keys.clone()), egress: (ALL, keys) };
        let owned = |k: &[&str]| k.iter().map(|k| k.to_string()).collect::<Vec<_>>();
        let plant =
            || Grant { what: "plant", ingress: (ALL, owned(PLANT_KEYS)), egress: (ALL, owned(PLANT_KEYS)) };
        let directory = || Grant {
            what: "directory",
            ingress: (READ, owned(DIRECTORY_KEYS)),
            egress: (SAMPLES, owned(DIRECTORY_KEYS)),
        };
        let grants: Vec<Grant> = match identity.role {
            Role::Admin => vec![all(vec!["dmp/**".to_owned()]), plant()],
            // A server of some cells publishes and reads those cells only; `*` gives `dmp/*/**`. Every server
            // takes part in the plant: only servers publish primitives.
            Role::Server => vec![all(keys("**")), plant()],
            Role::Perception => vec![obstacles(), catch_up(), directory()],
            Role::Planner => vec![obstacles(), catch_up(), read(), directory()],
            Role::Observer => vec![read(), directory()],
            Role::Robot => Vec::new(),
        };
        if grants.is_empty() {
            continue;
        }
        let subject = format!("cn:{}", identity.name);
        subjects.push(json!({ "id": subject, "cert_common_names": [cn] }));
        let mut ids = Vec::new();
        for g in grants {
            for (flow, (messages, key_exprs)) in [("ingress", g.ingress), ("egress", g.egress)] {
                let id = format!("{}:{}:{flow}", identity.name, g.what);
                rules.push(json!({
                    "id": id, "permission": "allow", "flows": [flow], "messages": messages, "key_exprs": key_exprs,
                }));
                ids.push(id);
            }
        }
        policies
            .push(json!({ "id": format!("policy:{}", identity.name), "rules": ids, "subjects": [subject] }));
    }
    json!({
        "enabled": true,
        "default_permission": "deny",
        "rules": rules,
        "subjects": subjects,
        "policies": policies,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perception_gets_only_its_cells_obstacles_and_robots_nothing() {
        let text = "\
[[identity]]\nname = \"eyes\"\nrole = \"perception\"\ncells = [\"a\"]\ncert_common_name = \"eyes\"\n\
[[identity]]\nname = \"panda\"\nrole = \"robot\"\ncells = [\"a\"]\nrobots = [\"panda\"]\ncert_common_name = \"panda\"\n\
[[identity]]\nname = \"peer\"\nrole = \"server\"\ncells = [\"*\"]\ncert_common_name = \"peer\"\n";
        let acl = access_control(&Access::parse(text).unwrap());
        assert_eq!(acl["default_permission"], "deny");
        let rules = acl["rules"].as_array().unwrap();
        let rule = |id: &str| rules.iter().find(|r| r["id"] == id).unwrap();
        assert_eq!(rule("eyes:obstacles:ingress")["key_exprs"], json!(["dmp/a/obstacles/**"]));
        assert_eq!(rule("eyes:obstacles:ingress")["messages"], json!(PUBLISH));
        assert_eq!(rule("eyes:obstacles:egress")["messages"], json!(READ));
        assert_eq!(rules.iter().filter(|r| r["id"].as_str().unwrap().starts_with("eyes:")).count(), 6);
        assert_eq!(rule("eyes:catch-up:ingress")["messages"], json!(["declare_queryable"]));
        assert_eq!(rule("eyes:catch-up:ingress")["key_exprs"], json!(["dmp/*/obstacles/**"]));
        assert_eq!(rule("eyes:directory:ingress")["messages"], json!(READ));
        assert!(!rule("eyes:directory:ingress")["key_exprs"].to_string().contains("@primitives"));
        // Only servers (and the admin) may publish primitives.
        assert_eq!(rule("peer:plant:ingress")["key_exprs"], json!(PLANT_KEYS));
        assert_eq!(rule("peer:plant:ingress")["messages"], json!(ALL));
        assert!(!rules.iter().any(|r| r["id"].as_str().unwrap().starts_with("panda")));
        assert_eq!(acl["subjects"].as_array().unwrap().len(), 2);
        // Zenoh reads it.
        let mut config = zenoh::Config::default();
        config.insert_json5("access_control", &acl.to_string()).unwrap();
    }
}
