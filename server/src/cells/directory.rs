//! The plant's servers as this server knows them: filled from their liveliness tokens (`dmp/@servers/<id>`, with
//! history, so those declared before this server started count) and the answer of each one's queryable on the same
//! key (`dmp.v1.PlantServer`); a server whose token goes is forgotten. It names the server of a cell that this one
//! does not serve, and each change wakes the fail-over ([`crate::plant::failover`]).

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

use dmp_proto::v1;
use tokio::sync::watch;

/// The live servers of the plant, by id, and every cell's home. Cheap to clone; the locks are never held across
/// an await.
#[derive(Debug, Clone)]
pub struct Directory {
    servers: Arc<Mutex<BTreeMap<String, v1::PlantServer>>>,
    /// Each cell's home: the smallest id of the live servers that list it ([`Directory::insert`]), remembered after
    /// it is gone.
    homes: Arc<Mutex<BTreeMap<String, String>>>,
    /// Bumped at every change.
    changes: Arc<watch::Sender<u64>>,
}

impl Default for Directory {
    fn default() -> Self {
        Self { servers: Arc::default(), homes: Arc::default(), changes: Arc::new(watch::Sender::new(0)) }
    }
}

impl Directory {
    /// Records (or replaces) a live server, and settles the home of the cells it lists.
    pub(crate) fn insert(&self, server: v1::PlantServer) {
        {
            let mut homes = self.homes.lock().unwrap_or_else(|p| p.into_inner());
            // The cells whose server it knows gone: their home, unless this server knows it already.
            for (cell, home) in &server.homes_away {
                homes.entry(cell.clone()).or_insert_with(|| home.clone());
            }
        }
        let cells = server.cells.clone();
        self.lock().insert(server.server_id.clone(), server);
        self.settle(&cells);
        self.changes.send_modify(|n| *n += 1);
    }

    /// Sets the home of each of `cells` by the one rule every server applies to the same live set: the smallest id
    /// of the live servers that list it. A cell that none lists keeps the home it had (gone: the fail-over holds
    /// it), so that the order announcements arrive in never decides, and a claimant that leaves hands the cell to
    /// the other claimants at once.
    fn settle(&self, cells: &[String]) {
        let claimants: Vec<(String, Option<String>)> = {
            let servers = self.lock();
            cells
                .iter()
                .map(|c| {
                    let first = servers.values().find(|s| s.cells.contains(c)).map(|s| s.server_id.clone());
                    (c.clone(), first)
                })
                .collect()
        };
        let mut homes = self.homes.lock().unwrap_or_else(|p| p.into_inner());
        for (cell, first) in claimants {
            if let Some(home) = first {
                homes.insert(cell, home);
            }
        }
    }

    /// Every cell's home, as last announced.
    pub fn homes(&self) -> BTreeMap<String, String> {
        self.homes.lock().unwrap_or_else(|p| p.into_inner()).clone()
    }

    /// The cells whose home is not live, with their home (what a server tells one that joins, `homes_away`).
    pub(crate) fn homes_away(&self) -> std::collections::HashMap<String, String> {
        let live = self.server_ids();
        let homes = self.homes.lock().unwrap_or_else(|p| p.into_inner());
        homes.iter().filter(|(_, h)| !live.contains(h)).map(|(c, h)| (c.clone(), h.clone())).collect()
    }

    /// The home of `cell` and the server that holds it as the fail-over has it: its home while that is live, else
    /// the live server (`me` included, when given) of highest rendezvous weight ([`super::rendezvous::rendezvous`]).
    /// None for a cell no server ever announced, or no server live.
    pub(crate) fn holder_of(&self, cell: &str, me: Option<&str>) -> Option<(String, String)> {
        let home = self.homes.lock().unwrap_or_else(|p| p.into_inner()).get(cell).cloned()?;
        let mut live = self.server_ids();
        if live.contains(&home) {
            return Some((home.clone(), home));
        }
        if let Some(me) = me
            && !live.iter().any(|s| s == me)
        {
            live.push(me.to_owned());
        }
        let holder = super::rendezvous::rendezvous(cell, live.iter().map(String::as_str))?.to_owned();
        Some((home, holder))
    }

    /// Forgets a server (its token went); the cells it listed go to the other live servers that list them.
    pub(crate) fn remove(&self, server_id: &str) {
        let gone = self.lock().remove(server_id);
        if let Some(gone) = gone {
            self.settle(&gone.cells);
            self.changes.send_modify(|n| *n += 1);
        }
    }

    /// A receiver that sees every change from now on.
    pub(crate) fn changes(&self) -> watch::Receiver<u64> {
        self.changes.subscribe()
    }

    /// The live servers known, by id.
    pub(crate) fn servers(&self) -> Vec<v1::PlantServer> {
        self.lock().values().cloned().collect()
    }

    /// The live server `server_id`, if known.
    pub(crate) fn get(&self, server_id: &str) -> Option<v1::PlantServer> {
        self.lock().get(server_id).cloned()
    }

    /// The live server serving `cell` (the smallest id when several say they do); None when none is known.
    pub(crate) fn owner_of(&self, cell: &str) -> Option<v1::PlantServer> {
        self.lock().values().find(|s| s.cells.iter().any(|c| c == cell)).cloned()
    }

    /// The ids of the live servers known, in order.
    pub fn server_ids(&self) -> Vec<String> {
        self.lock().keys().cloned().collect()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, BTreeMap<String, v1::PlantServer>> {
        self.servers.lock().unwrap_or_else(|p| p.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn server(id: &str, cells: &[&str]) -> v1::PlantServer {
        v1::PlantServer {
            server_id: id.into(),
            grpc_address: format!("http://{id}:1"),
            cells: cells.iter().map(|c| c.to_string()).collect(),
            ..Default::default()
        }
    }

    #[test]
    fn a_cell_is_owned_by_the_smallest_live_server_serving_it() {
        let d = Directory::default();
        assert!(d.owner_of("a").is_none());
        d.insert(server("s2", &["a", "b"]));
        d.insert(server("s1", &["a"]));
        assert_eq!(d.owner_of("a").unwrap().server_id, "s1");
        assert_eq!(d.owner_of("b").unwrap().server_id, "s2");
        d.remove("s1");
        assert_eq!(d.owner_of("a").unwrap().server_id, "s2");
        assert_eq!(d.server_ids(), ["s2"]);
    }

    #[test]
    fn competing_claims_resolve_alike_in_any_order_and_converge_when_a_claimant_leaves() {
        let (x, y) = (Directory::default(), Directory::default());
        // A fake server `0` claims cell a: two directories hearing the claims in opposite orders agree.
        x.insert(server("s1", &["a"]));
        x.insert(server("0", &["a"]));
        y.insert(server("0", &["a"]));
        y.insert(server("s1", &["a"]));
        y.insert(server("s2", &["b"]));
        x.insert(server("s2", &["b"]));
        assert_eq!(x.homes(), y.homes());
        // It leaves: a goes back to s1 at once, and nobody takes it over (no split brain).
        x.remove("0");
        y.remove("0");
        for d in [&x, &y] {
            assert_eq!(d.homes().get("a").map(String::as_str), Some("s1"));
            assert_eq!(d.holder_of("a", Some("s2")), Some(("s1".into(), "s1".into())));
        }
    }

    #[test]
    fn a_cell_is_held_by_its_home_while_it_lives_then_by_the_rendezvous_pick() {
        let d = Directory::default();
        assert_eq!(d.holder_of("a", Some("s3")), None, "a cell nobody announced");
        d.insert(server("s1", &["a"]));
        d.insert(server("s2", &["b"]));
        assert_eq!(d.holder_of("a", Some("s3")), Some(("s1".into(), "s1".into())));
        d.remove("s1");
        assert_eq!(d.homes().get("a").map(String::as_str), Some("s1"), "remembered after it is gone");
        let pick = super::super::rendezvous::rendezvous("a", ["s2", "s3"]).unwrap();
        assert_eq!(d.holder_of("a", Some("s3")), Some(("s1".into(), pick.into())));
        assert_eq!(
            d.holder_of("a", None),
            Some(("s1".into(), "s2".into())),
            "s2 is the only live one it knows"
        );
    }

    #[test]
    fn a_server_joining_while_a_home_is_away_learns_it_from_the_taker() {
        let d = Directory::default();
        let mut taker = server("s2", &["b"]);
        taker.homes_away.insert("a".into(), "s1".into());
        d.insert(taker);
        assert_eq!(d.homes().get("a").map(String::as_str), Some("s1"));
        assert_eq!(d.homes_away().get("a").map(String::as_str), Some("s1"), "and tells the next one");
        assert!(!d.homes_away().contains_key("b"), "s2 is live");
        let pick = super::super::rendezvous::rendezvous("a", ["s2", "s4"]).unwrap();
        assert_eq!(d.holder_of("a", Some("s4")), Some(("s1".into(), pick.into())));
        // The home's own announcement wins over what a taker said.
        d.insert(server("s9", &["a"]));
        assert_eq!(d.homes().get("a").map(String::as_str), Some("s9"));
    }
}
