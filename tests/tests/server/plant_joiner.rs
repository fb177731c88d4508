//! A server that joins a plant while a cell's server is away: it learns the cell's home from the taker's
//! announcement and takes part in the fail-over's choice like the others, so that the cell is never left without
//! a server when the newcomer wins it.

use dmp_server::cells::rendezvous::{rendezvous, weight};
use dmp_tests::within;

use crate::plant::{Loopback, loopback, plant_server, shut_down, three_servers, until_all_known};
use crate::until;

#[tokio::test(flavor = "multi_thread")]
async fn a_server_joining_during_an_outage_takes_the_cell_it_wins() {
    let Loopback { zenohd, endpoint, dirs } = loopback(4).await;
    let (s1, s2, s3) = three_servers(&endpoint, &dirs).await;
    within("s1 down", s1.shutdown()).await.unwrap();
    let taker = match rendezvous("a", ["s2", "s3"]).unwrap() {
        "s2" => &s2,
        _ => &s3,
    };
    until("the taker serves cell a", || taker.cells().serves("a")).await;

    // A newcomer whose id outweighs both survivors for cell a: it never heard s1, yet it must take cell a.
    let id = (4..)
        .map(|k| format!("s{k}"))
        .find(|id| ["s2", "s3"].iter().all(|s| weight("a", id) > weight("a", s)))
        .unwrap();
    let s4 = plant_server(dirs[3].path(), &endpoint, &id, &["d"], &[]).await;
    until_all_known(&[&s2, &s3, &s4]).await;
    until("the newcomer serves cell a", || s4.cells().serves("a")).await;
    until("the taker let it go", || !taker.cells().serves("a")).await;
    assert_eq!(s4.cells().directory().homes().get("a").map(String::as_str), Some("s1"));
    let found = within(
        "resolve a",
        dmp_client::discovery::resolve_cell_via(&endpoint, None, "a", std::time::Duration::from_secs(5)),
    )
    .await
    .unwrap();
    assert_eq!(found.server_id, id);

    // s1 comes back: the newcomer gives cell a back to it.
    let s1 = plant_server(dirs[0].path(), &endpoint, "s1", &["a"], &[]).await;
    until("the newcomer gave cell a back", || !s4.cells().serves("a")).await;
    shut_down([s1, s2, s3, s4], zenohd).await;
}
