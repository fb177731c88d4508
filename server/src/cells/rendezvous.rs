//! Who serves a cell whose home server is gone: rendezvous (highest-random-weight) hashing over the plant's live
//! servers. Every server computes it alike from the same live set, so each cell goes to one server once their
//! directories agree, and a server coming or going moves only the cells it wins or held.
//!
//! # Formula
//! `weight(cell, server)` = the first 8 bytes (big-endian) of SHA-256(`cell` ‖ 0 ‖ `server`); the cell goes to the
//! live server of highest weight, ties to the smaller id (Thaler and Ravishankar, 1998).

use sha2::{Digest, Sha256};

/// The rendezvous weight of `server` for `cell`.
pub fn weight(cell: &str, server: &str) -> u64 {
    let digest = Sha256::new().chain_update(cell).chain_update([0]).chain_update(server).finalize();
    let mut first = [0u8; 8];
    first.copy_from_slice(&digest[..8]);
    u64::from_be_bytes(first)
}

/// The server of `live` that serves `cell` while its home is gone: the highest weight, ties to the smaller id.
pub fn rendezvous<'a>(cell: &str, live: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    live.into_iter().max_by(|a, b| weight(cell, a).cmp(&weight(cell, b)).then_with(|| b.cmp(a)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rendezvous_is_stable_and_moves_only_the_cells_of_the_server_gone() {
        let all = ["s1", "s2", "s3", "s4"];
        let cells: Vec<String> = (0..200).map(|i| format!("cell-{i}")).collect();
        let pick = |live: &[&'static str]| -> Vec<&'static str> {
            cells.iter().map(|c| rendezvous(c, live.iter().copied()).unwrap()).collect()
        };
        let before = pick(&all);
        // The same on every call and in any order of the live set (no per-process random state).
        assert_eq!(before, pick(&["s4", "s2", "s3", "s1"]));
        assert_eq!(weight("a", "s1"), weight("a", "s1"));
        assert_ne!(weight("a", "s1"), weight("a", "s2"));
        // Spread over every server.
        for s in all {
            let n = before.iter().filter(|p| **p == s).count();
            assert!(n > 20, "{s} wins {n} of 200");
        }
        // Without s2: only s2's cells move.
        let after = pick(&["s1", "s3", "s4"]);
        for (b, a) in before.iter().zip(&after) {
            if *b != "s2" {
                assert_eq!(b, a);
            } else {
                assert_ne!(*a, "s2");
            }
        }
        assert_eq!(rendezvous("a", std::iter::empty()), None);
    }
}
