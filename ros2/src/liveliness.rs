//! The liveliness tokens through which ROS 2's graph (`ros2 node list`, `ros2 topic list -v`) learns of nodes and
//! publishers on rmw_zenoh, and the GIDs derived from them. As read in ros2/rmw_zenoh's
//! `rmw_zenoh_cpp/src/detail/liveliness_utils.cpp` (commit `3411fdec149fe0c932f24d4d79ef908eb81d7482`):
//!
//! `@ros2_lv/<domain>/<zenoh id>/<node id>/<entity id>/<NN|MP|MS|SS|SC>/<enclave>/<namespace>/<node name>` for a
//! node, followed for a publisher by `/<topic>/<type>/<type hash>/<qos>`. Names are mangled (`/` becomes `%`; the
//! root namespace and enclave `/` are `%`). The QoS chunk leaves empty every value equal to the default's. An
//! entity's GID is the XXH3-128 hash of its token's key, its low 64 bits then its high 64 bits, little-endian.

use crate::keys::{RosType, topic_chunks};

/// The admin space of every token.
pub(crate) const ADMIN_SPACE: &str = "@ros2_lv";

/// The QoS chunk of an entity with the default QoS (reliable, volatile, keep last, default depth, no deadline,
/// lifespan or liveliness lease).
pub(crate) const DEFAULT_QOS: &str = "::,:,:,:,,";

/// A name with its `/` as `%` (rmw_zenoh's `mangle_name`).
pub(crate) fn mangle(name: &str) -> String {
    name.replace('/', "%")
}

/// A node: where its tokens live.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Node {
    /// The ROS domain.
    pub domain: u32,
    /// The Zenoh session's id, as Zenoh prints it.
    pub zid: String,
    /// The node's id in its session.
    pub node_id: u32,
    /// The node's namespace, e.g. `/`.
    pub namespace: String,
    /// The node's name.
    pub name: String,
}

impl Node {
    fn prefix(&self, entity_id: u32, kind: &str) -> String {
        format!(
            "{ADMIN_SPACE}/{}/{}/{}/{entity_id}/{kind}/%/{}/{}",
            self.domain,
            self.zid,
            self.node_id,
            mangle(&self.namespace),
            mangle(&self.name)
        )
    }

    /// The node's own token (its entity id is its node id).
    pub fn token(&self) -> String {
        self.prefix(self.node_id, "NN")
    }

    /// The token of the node's publisher `entity_id` of `ty` on `topic`, with the default QoS.
    pub fn publisher_token(&self, entity_id: u32, topic: &str, ty: &RosType) -> String {
        format!(
            "{}/{}/{}/{}/{DEFAULT_QOS}",
            self.prefix(entity_id, "MP"),
            mangle(&format!("/{}", topic_chunks(topic))),
            ty.dds_name(),
            ty.hash
        )
    }
}

/// The GID of the entity whose token's key is `token`.
pub fn gid(token: &str) -> [u8; 16] {
    let h = xxhash_rust::xxh3::xxh3_128(token.as_bytes());
    let mut out = [0u8; 16];
    out[..8].copy_from_slice(&(h as u64).to_le_bytes());
    out[8..].copy_from_slice(&((h >> 64) as u64).to_le_bytes());
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::keys::MARKER_ARRAY;

    #[test]
    fn tokens_are_rmw_zenohs() {
        let n = Node {
            domain: 7,
            zid: "abc".into(),
            node_id: 0,
            namespace: "/".into(),
            name: "dmp_server".into(),
        };
        assert_eq!(n.token(), "@ros2_lv/7/abc/0/0/NN/%/%/dmp_server");
        assert_eq!(
            n.publisher_token(3, "/dmp/cell_a/markers", &MARKER_ARRAY),
            format!(
                "@ros2_lv/7/abc/0/3/MP/%/%/dmp_server/%dmp%cell_a%markers/visualization_msgs::msg::dds_::MarkerArray_/{}/::,:,:,:,,",
                MARKER_ARRAY.hash
            )
        );
    }

    #[test]
    fn gids_are_xxh3_128() {
        // XXH3-128 of the empty input is 99aa06d3014798d8 6001c324468d497f (high, low).
        let g = gid("");
        assert_eq!(u64::from_le_bytes(g[..8].try_into().unwrap()), 0x6001c324468d497f);
        assert_eq!(u64::from_le_bytes(g[8..].try_into().unwrap()), 0x99aa06d3014798d8);
    }
}
