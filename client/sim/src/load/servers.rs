//! The servers the load streams to: `--server` alone, or with `--via-zenoh-discovery` the server of each of the
//! load's cells, found through Zenoh (`dmp_client::discovery::resolve_cell`), and the connections to each.
//!
//! Connections: `--connections` shared out over the servers in proportion to their cells (at least one each);
//! a cell's robots share one connection, the cells of a server taking its connections in turn.

use dmp_client::connect::ConnectOptions;
use dmp_client::discovery::{RESOLVE_TIMEOUT, resolve_cells_via};
use dmp_client::grpc::DmpClient;

use super::DEFAULT_ZENOH;
use crate::error::SimError;

/// One server of the load.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Target {
    /// Its plant id (empty for `--server`).
    pub(crate) server_id: String,
    /// Its gRPC address.
    pub(crate) url: String,
    /// The indices of the load's cells it serves.
    pub(crate) cells: Vec<usize>,
}

/// The servers of the load, and which serves each cell.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Servers {
    /// In the order their first cell comes.
    pub(crate) targets: Vec<Target>,
    /// For each cell, the index of its server in `targets`.
    pub(crate) of_cell: Vec<usize>,
}

impl Servers {
    /// Every cell on `url`.
    pub(crate) fn one(url: &str, cells: usize) -> Self {
        let target = Target { server_id: String::new(), url: url.to_owned(), cells: (0..cells).collect() };
        Self { targets: vec![target], of_cell: vec![0; cells] }
    }

    /// Groups the cells by the server each was found on (`found[c]`: its id and gRPC address).
    pub(crate) fn grouped(found: &[(String, String)]) -> Self {
        let mut targets: Vec<Target> = Vec::new();
        let mut of_cell = Vec::with_capacity(found.len());
        for (c, (id, url)) in found.iter().enumerate() {
            let t = match targets.iter().position(|t| &t.server_id == id) {
                Some(t) => t,
                None => {
                    targets.push(Target { server_id: id.clone(), url: url.clone(), cells: Vec::new() });
                    targets.len() - 1
                }
            };
            targets[t].cells.push(c);
            of_cell.push(t);
        }
        Self { targets, of_cell }
    }

    /// How many of `connections` each server gets: in proportion to its cells, at least one.
    pub(crate) fn connections(&self, connections: usize) -> Vec<usize> {
        let cells = self.of_cell.len().max(1);
        self.targets.iter().map(|t| (connections * t.cells.len()).div_ceil(cells).max(1)).collect()
    }

    /// Connects to every server and gives each cell its connection (`clients[c]` for cell `c`).
    pub(crate) async fn connect(
        &self,
        connections: usize,
        options: &ConnectOptions,
    ) -> Result<Vec<DmpClient>, SimError> {
        let mut of_cell: Vec<Option<DmpClient>> = vec![None; self.of_cell.len()];
        for (t, n) in self.targets.iter().zip(self.connections(connections)) {
            let mut clients = Vec::with_capacity(n);
            for _ in 0..n {
                clients.push(DmpClient::connect_with(&t.url, options).await?);
            }
            for (k, &c) in t.cells.iter().enumerate() {
                of_cell[c] = Some(clients[k % n].clone());
            }
        }
        Ok(of_cell.into_iter().flatten().collect())
    }
}

/// The servers of the load's `cells`: `server` for all, or with `via_zenoh` each cell's server asked through
/// Zenoh (a client of `zenoh_connect`, default [`DEFAULT_ZENOH`]); an error names a cell no server serves.
pub(crate) async fn find(
    cells: &[String],
    server: &str,
    via_zenoh: bool,
    zenoh_connect: &[String],
) -> Result<Servers, SimError> {
    if !via_zenoh {
        return Ok(Servers::one(server, cells.len()));
    }
    let connect =
        if zenoh_connect.is_empty() { vec![DEFAULT_ZENOH.to_string()] } else { zenoh_connect.to_vec() };
    let found = resolve_cells_via(&connect, None, cells, RESOLVE_TIMEOUT).await?;
    let found: Vec<(String, String)> = found.into_iter().map(|s| (s.server_id, s.grpc_address)).collect();
    Ok(Servers::grouped(&found))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_are_grouped_by_server_and_connections_shared_in_proportion() {
        let found: Vec<(String, String)> =
            [("s2", "u2"), ("s1", "u1"), ("s2", "u2"), ("s3", "u3"), ("s2", "u2")]
                .iter()
                .map(|(a, b)| (a.to_string(), b.to_string()))
                .collect();
        let s = Servers::grouped(&found);
        let ids: Vec<&str> = s.targets.iter().map(|t| t.server_id.as_str()).collect();
        assert_eq!(ids, ["s2", "s1", "s3"]);
        assert_eq!(s.targets[0].cells, [0, 2, 4]);
        assert_eq!(s.of_cell, [0, 1, 0, 2, 0]);
        assert_eq!(s.connections(8), [5, 2, 2]);
        assert_eq!(s.connections(1), [1, 1, 1]);
        let one = Servers::one("http://x", 3);
        assert_eq!((one.of_cell.clone(), one.connections(2)), (vec![0, 0, 0], vec![2]));
    }
}
