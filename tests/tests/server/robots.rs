//! `PrimitiveService.ListRobots`: every robot that has primitives, with its count and latest update, and only
//! those the caller may read.

use dmp_tests::within;

use crate::access::{as_identity, secured};
use crate::line;

#[tokio::test(flavor = "multi_thread")]
async fn robots_are_listed_as_far_as_the_caller_may_read_them() {
    let set = tempfile::tempdir().unwrap();
    let (server, tokens) = secured(set.path()).await;
    let admin = as_identity(&server, Some(&tokens["admin"])).await;
    let p = line(vec![0.0, 0.0], vec![1.0, 0.0], 1.0);
    for (robot, name) in
        [("panda-1", "a"), ("panda-1", "b"), ("panda-1", "b"), ("panda-2", "a"), ("other", "a")]
    {
        within("put", admin.put_primitive(robot, name, &p)).await.unwrap();
    }
    // Deleted: a robot without primitives is not listed.
    within("put", admin.put_primitive("gone", "a", &p)).await.unwrap();
    within("delete", admin.delete("gone", "a")).await.unwrap();

    let listed = |token: &'static str| {
        let (server, tokens) = (&server, &tokens);
        async move {
            let client = as_identity(server, Some(&tokens[token])).await;
            let robots = within("list robots", client.list_robots()).await.unwrap();
            robots.into_iter().map(|r| (r.robot_id, r.primitives, r.updated_unix_ms)).collect::<Vec<_>>()
        }
    };
    let all = listed("admin").await;
    let ids: Vec<(&str, u64)> = all.iter().map(|(r, n, _)| (r.as_str(), *n)).collect();
    // Sorted by id; names counted once however many versions they have.
    assert_eq!(ids, [("other", 1), ("panda-1", 2), ("panda-2", 1)]);
    assert!(all.iter().all(|(_, _, t)| *t > 1_700_000_000_000), "{all:?}");
    let without_other: Vec<_> = all.iter().filter(|(r, ..)| r != "other").cloned().collect();
    // The planner and the observer have the robots `access init` gave them; a robot its own; perception none.
    assert_eq!(listed("planner").await, without_other);
    assert_eq!(listed("observer").await, without_other);
    assert_eq!(listed("panda-2").await, [all[2].clone()]);
    assert!(listed("perception").await.is_empty());
    server.stop().await;
}
