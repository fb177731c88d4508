"""A ROS 2 node's collision objects as rmw_zenoh puts them, from a stock eclipse-zenoh session and rosbags' CDR,
for the end-to-end test (`tests/tests/server/ros2_bridge.rs`).

    ros2_publish.py LOCATOR MSG_DIR DOMAIN

Waits until the server's subscriber matches, prints `ok: matched`, then for each line of stdin (`add`, `remove`,
`wrong-frame`) publishes that CollisionObject and prints `ok: <line>`.
"""

import json
import pathlib
import sys
import time

import numpy as np
import zenoh

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from ros2_payloads import store  # noqa: E402


def main():
    locator, msg_dir, domain = sys.argv[1], pathlib.Path(sys.argv[2]), sys.argv[3]
    ts = store(msg_dir)
    T = ts.types
    Header, Time = T["std_msgs/msg/Header"], T["builtin_interfaces/msg/Time"]
    Pose, Point, Quaternion = T["geometry_msgs/msg/Pose"], T["geometry_msgs/msg/Point"], T["geometry_msgs/msg/Quaternion"]
    Solid, Polygon = T["shape_msgs/msg/SolidPrimitive"], T["geometry_msgs/msg/Polygon"]
    CO, ObjectType = T["moveit_msgs/msg/CollisionObject"], T["object_recognition_msgs/msg/ObjectType"]

    def pose(x, y, z, q=(0.0, 0.0, 0.0, 1.0)):
        return Pose(position=Point(x=x, y=y, z=z), orientation=Quaternion(x=q[0], y=q[1], z=q[2], w=q[3]))

    def box(op, frame="world"):
        return CO(
            header=Header(stamp=Time(sec=int(time.time()), nanosec=0), frame_id=frame),
            # At (0.5, 0.25, 0.1), turned a quarter about z; the box 0.2 m further along the object's x.
            pose=pose(0.5, 0.25, 0.1, (0.0, 0.0, 2 ** -0.5, 2 ** -0.5)), id="crate", type=ObjectType(key="", db=""),
            primitives=[Solid(type=1, dimensions=np.array([0.2, 0.1, 0.3]), polygon=Polygon(points=[]))],
            primitive_poses=[pose(0.2, 0.0, 0.0)], meshes=[], mesh_poses=[], planes=[], plane_poses=[],
            subframe_names=[], subframe_poses=[], operation=op,
        )

    config = zenoh.Config()
    config.insert_json5("mode", json.dumps("client"))
    config.insert_json5("connect/endpoints", json.dumps([locator]))
    config.insert_json5("scouting/multicast/enabled", "false")
    session = zenoh.open(config)
    key = f"{domain}/collision_object/moveit_msgs::msg::dds_::CollisionObject_/RIHS01_" + "0" * 64
    publisher = session.declare_publisher(key)
    deadline = time.monotonic() + 30
    while not publisher.matching_status.matching:
        if time.monotonic() > deadline:
            sys.exit("no subscriber matched within 30 s")
        time.sleep(0.01)
    print("ok: matched", flush=True)
    messages = {"add": lambda: box(0), "remove": lambda: box(1), "wrong-frame": lambda: box(0, "camera_link")}
    for line in sys.stdin:
        cmd = line.strip()
        msg = messages[cmd]()
        publisher.put(bytes(ts.serialize_cdr(msg, msg.__msgtype__)))
        print(f"ok: {cmd}", flush=True)
    session.close()


if __name__ == "__main__":
    main()
