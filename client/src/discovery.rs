//! Finding the server of a cell in a plant of servers, through Zenoh (feature `zenoh`): each server answers on
//! `dmp/@cells/<cell>` for the cells it serves with its `dmp.v1.PlantServer` (id, gRPC address, cells, and the cells
//! it serves for a server gone, `taken`). When several answer (while a cell goes back to its server after a
//! fail-over), the cell's own server is taken, then the smallest server id.

use std::path::Path;
use std::time::Duration;

use dmp_proto::keys::{cell_server_key, check_name};
use dmp_proto::zenoh_session::{SessionOptions, session_config};
use dmp_proto::{codec, v1};
use zenoh::Session;
use zenoh::query::{ConsolidationMode, QueryTarget};

use crate::error::ClientError;

/// How long [`resolve_cell`] waits for the servers' answers by default.
pub const RESOLVE_TIMEOUT: Duration = Duration::from_secs(3);

/// The server of `cell`, asked on `session`; an error naming the cell when no server answers within `timeout`.
pub async fn resolve_cell(
    session: &Session,
    cell: &str,
    timeout: Duration,
) -> Result<v1::PlantServer, ClientError> {
    check_name("cell", cell)?;
    let replies = session
        .get(cell_server_key(cell))
        .target(QueryTarget::All)
        .consolidation(ConsolidationMode::None)
        .timeout(timeout)
        .await
        .map_err(|e| ClientError::Zenoh(format!("asking for the server of cell `{cell}`: {e}")))?;
    // The best answer so far, and whether the cell is its own (not taken over).
    let mut best: Option<(bool, v1::PlantServer)> = None;
    while let Ok(reply) = replies.recv_async().await {
        let Ok(sample) = reply.result() else { continue };
        let Ok(server) = codec::decode::<v1::PlantServer>(&sample.payload().to_bytes()) else { continue };
        let own = server.cells.iter().any(|c| c == cell);
        if !(own || server.taken.iter().any(|c| c == cell)) || server.grpc_address.is_empty() {
            continue;
        }
        let better = match &best {
            None => true,
            Some((best_own, b)) => {
                (own, std::cmp::Reverse(&server.server_id)) > (*best_own, std::cmp::Reverse(&b.server_id))
            }
        };
        if better {
            best = Some((own, server));
        }
    }
    let best = best.map(|(_, s)| s);
    best.ok_or_else(|| {
        ClientError::argument("cell", format!("no server of the plant answered that it serves cell `{cell}`"))
    })
}

/// Opens a Zenoh session (a client of the routers at `connect`, or from the stock configuration `config_file`,
/// whose endpoints `connect` replaces when given), finds the server of `cell` ([`resolve_cell`]) and closes it.
pub async fn resolve_cell_via(
    connect: &[String],
    config_file: Option<&Path>,
    cell: &str,
    timeout: Duration,
) -> Result<v1::PlantServer, ClientError> {
    let mut found = resolve_cells_via(connect, config_file, &[cell.to_owned()], timeout).await?;
    Ok(found.remove(0))
}

/// [`resolve_cell_via`] for several cells on one session, in order; the first cell no server serves fails it.
pub async fn resolve_cells_via(
    connect: &[String],
    config_file: Option<&Path>,
    cells: &[String],
    timeout: Duration,
) -> Result<Vec<v1::PlantServer>, ClientError> {
    let options = SessionOptions {
        mode: "client".into(),
        listen: Some(Vec::new()),
        connect: connect.to_vec(),
        multicast_scouting: connect.is_empty() && config_file.is_none(),
        config_file: config_file.map(Path::to_path_buf),
        tls: None,
        access_control: None,
    };
    let config = session_config(&options)?;
    let session =
        zenoh::open(config).await.map_err(|e| ClientError::Zenoh(format!("opening the session: {e}")))?;
    let mut found = Ok(Vec::with_capacity(cells.len()));
    for cell in cells {
        match resolve_cell(&session, cell, timeout).await {
            Ok(s) => found.as_mut().map(|f| f.push(s)).unwrap_or(()),
            Err(e) => {
                found = Err(e);
                break;
            }
        }
    }
    if let Err(e) = session.close().await {
        return Err(ClientError::Zenoh(format!("closing the session: {e}")));
    }
    found
}
