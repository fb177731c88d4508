"""ROS 2 payloads written and read by rosbags, an implementation independent of the server's, for the golden test
(`tests/tests/server/ros2_golden.rs`).

    ros2_payloads.py MSG_DIR defs      one line per type of MSG_DIR that rosbags ships: `ok <type>` when its fields
                                       (names, types, bounds, order) are rosbags' Humble and Jazzy ones
    ros2_payloads.py MSG_DIR hashes    `<type> <RIHS01 hash>` of the types the server publishes (Jazzy)
    ros2_payloads.py MSG_DIR encode    one JSON line per case: name, type, cdr (hex), value (as rosbags reads it back)
    ros2_payloads.py MSG_DIR decode    reads JSON lines {name, type, cdr} and writes {name, value}
    ros2_payloads.py MSG_DIR attachment SEQ TIME
                                       rmw_zenoh's attachment (int64, int64, 16 bytes 0..15 as a sequence) in
                                       eclipse-zenoh's zenoh-ext serialization, as hex

The types rosbags does not ship (moveit_msgs, object_recognition_msgs, nav2_dynamic_msgs) are registered from the
.msg files of MSG_DIR.
"""

import dataclasses
import json
import pathlib
import sys

import numpy as np
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

EXTRA = [
    "object_recognition_msgs/msg/ObjectType",
    "moveit_msgs/msg/CollisionObject",
    "nav2_dynamic_msgs/msg/Obstacle",
    "nav2_dynamic_msgs/msg/ObstacleArray",
]


def store(msg_dir, which=Stores.ROS2_JAZZY):
    ts = get_typestore(which)
    types = {}
    for name in EXTRA:
        types.update(get_types_from_msg((msg_dir / f"{name}.msg").read_text(), name))
    ts.register(types)
    return ts


def plain(ts, v):
    """A message as plain JSON values: its fields (as the store defines them, without constants), arrays as lists."""
    if dataclasses.is_dataclass(v):
        return {name: plain(ts, getattr(v, name)) for name, _ in ts.fielddefs[v.__msgtype__][1]}
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, (list, tuple)):
        return [plain(ts, x) for x in v]
    return v


def cases(ts):
    T = lambda name: ts.types[name]  # noqa: E731
    Time, Header = T("builtin_interfaces/msg/Time"), T("std_msgs/msg/Header")
    Point, Quaternion = T("geometry_msgs/msg/Point"), T("geometry_msgs/msg/Quaternion")
    Pose, Vector3 = T("geometry_msgs/msg/Pose"), T("geometry_msgs/msg/Vector3")
    Point32, Polygon = T("geometry_msgs/msg/Point32"), T("geometry_msgs/msg/Polygon")
    Solid, Mesh = T("shape_msgs/msg/SolidPrimitive"), T("shape_msgs/msg/Mesh")
    Triangle, Plane = T("shape_msgs/msg/MeshTriangle"), T("shape_msgs/msg/Plane")
    ObjectType, CO = T("object_recognition_msgs/msg/ObjectType"), T("moveit_msgs/msg/CollisionObject")
    Duration = T("builtin_interfaces/msg/Duration")

    def header(frame="world"):
        return Header(stamp=Time(sec=1764100000, nanosec=250000000), frame_id=frame)

    def pose(x, y, z, q=(0.0, 0.0, 0.0, 1.0)):
        return Pose(position=Point(x=x, y=y, z=z), orientation=Quaternion(x=q[0], y=q[1], z=q[2], w=q[3]))

    def solid(kind, dims, polygon=()):
        return Solid(type=kind, dimensions=np.array(dims, dtype=np.float64),
                     polygon=Polygon(points=[Point32(x=x, y=y, z=0.0) for x, y in polygon]))

    def co(oid, op, prims=(), meshes=(), planes=(), frame="world"):
        return CO(
            header=header(frame), pose=pose(0.5, -0.25, 0.125, (0.0, 0.0, 0.6, 0.8)), id=oid,
            type=ObjectType(key="mug", db="{}"),
            primitives=[p for p, _ in prims], primitive_poses=[q for _, q in prims],
            meshes=[m for m, _ in meshes], mesh_poses=[q for _, q in meshes],
            planes=[p for p, _ in planes], plane_poses=[q for _, q in planes],
            subframe_names=["tip"], subframe_poses=[pose(0.0, 0.0, 0.1)], operation=op,
        )

    mesh = Mesh(triangles=[Triangle(vertex_indices=np.array([0, 1, 2], dtype=np.uint32))],
                vertices=[Point(x=0.0, y=0.0, z=0.0), Point(x=0.1, y=0.0, z=0.0), Point(x=0.0, y=0.2, z=0.05)])
    yield "co-add-every-primitive", co("every", 0, prims=[
        (solid(1, [0.1, 0.2, 0.3]), pose(0.1, 0.0, 0.0)),
        (solid(2, [0.05]), pose(0.0, 0.2, 0.0)),
        (solid(3, [0.4, 0.05]), pose(0.0, 0.0, 0.3, (0.0, 0.6, 0.0, 0.8))),
        (solid(4, [0.2, 0.1]), pose(-0.1, 0.0, 0.0)),
        (solid(5, [0.1], [(0.0, 0.0), (0.5, 0.0), (0.0, 0.25)]), pose(0.0, -0.2, 0.0)),
    ], meshes=[(mesh, pose(0.0, 0.0, 0.5))], planes=[(Plane(coef=np.array([0.0, 0.0, 1.0, -0.5])), pose(0, 0, 0))])
    yield "co-remove", co("every", 1)
    yield "co-append", co("every", 2, prims=[(solid(1, [0.5, 0.5, 0.5]), pose(1.0, 0.0, 0.0))])
    yield "co-move", co("every", 3)

    Obstacle, ObstacleArray = T("nav2_dynamic_msgs/msg/Obstacle"), T("nav2_dynamic_msgs/msg/ObstacleArray")
    UUID = T("unique_identifier_msgs/msg/UUID")
    yield "obstacle-array", ObstacleArray(header=header("map"), obstacles=[
        Obstacle(uuid=UUID(uuid=np.arange(16, dtype=np.uint8)), score=0.75, position=Point(x=1.5, y=2.0, z=0.0),
                 velocity=Vector3(x=0.5, y=-0.25, z=0.0), size=Vector3(x=0.5, y=0.5, z=1.75)),
        Obstacle(uuid=UUID(uuid=np.full(16, 255, dtype=np.uint8)), score=0.5, position=Point(x=-1.0, y=0.0, z=0.0),
                 velocity=Vector3(x=0.0, y=0.0, z=0.0), size=Vector3(x=0.25, y=0.25, z=0.25)),
    ])

    Transform, Twist = T("geometry_msgs/msg/Transform"), T("geometry_msgs/msg/Twist")
    Traj, TrajPoint = T("trajectory_msgs/msg/MultiDOFJointTrajectory"), T("trajectory_msgs/msg/MultiDOFJointTrajectoryPoint")
    yield "multi-dof-trajectory", Traj(header=header(), joint_names=["panda-1"], points=[
        TrajPoint(transforms=[Transform(translation=Vector3(x=0.1 * k, y=0.2, z=0.3),
                                        rotation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0))],
                  velocities=[Twist(linear=Vector3(x=0.5, y=0.0, z=-0.125), angular=Vector3(x=0.0, y=0.0, z=0.0))],
                  accelerations=[Twist(linear=Vector3(x=0.0, y=1.0, z=0.0), angular=Vector3(x=0.0, y=0.0, z=0.0))],
                  time_from_start=Duration(sec=k, nanosec=1000000 * k))
        for k in range(3)
    ])

    Marker, MarkerArray = T("visualization_msgs/msg/Marker"), T("visualization_msgs/msg/MarkerArray")
    Color, Image = T("std_msgs/msg/ColorRGBA"), T("sensor_msgs/msg/CompressedImage")
    UV, MeshFile = T("visualization_msgs/msg/UVCoordinate"), T("visualization_msgs/msg/MeshFile")

    def marker(i, kind, points=()):
        return Marker(header=header(), ns="obstacles", id=i, type=kind, action=0, pose=pose(0.5, 0.25, 0.0),
                      scale=Vector3(x=0.1, y=0.2, z=0.3), color=Color(r=1.0, g=0.5, b=0.25, a=0.75),
                      lifetime=Duration(sec=0, nanosec=0), frame_locked=False,
                      points=[Point(x=x, y=y, z=z) for x, y, z in points],
                      colors=[Color(r=0.0, g=0.0, b=1.0, a=1.0) for _ in points], texture_resource="",
                      texture=Image(header=header(), format="", data=np.array([], dtype=np.uint8)),
                      uv_coordinates=[UV(u=0.5, v=0.5) for _ in points][:1], text="box",
                      mesh_resource="", mesh_file=MeshFile(filename="", data=np.array([1, 2, 3], dtype=np.uint8)),
                      mesh_use_embedded_materials=True)
    yield "marker-array", MarkerArray(markers=[marker(0, 1), marker(1, 4, [(0.0, 0.0, 0.0), (1.0, 0.5, 0.25)])])


def main():
    msg_dir, mode = pathlib.Path(sys.argv[1]), sys.argv[2]
    ts = store(msg_dir)
    if mode == "defs":
        humble = store(msg_dir, Stores.ROS2_HUMBLE)
        for path in sorted(msg_dir.glob("*/msg/*.msg")):
            name = f"{path.parent.parent.name}/msg/{path.stem}"
            if any(name == e for e in EXTRA):
                continue
            mine = get_types_from_msg(path.read_text(), name)[name]
            for which, s in (("jazzy", ts), ("humble", humble)):
                theirs = s.fielddefs[name]
                print(("ok " if mine[1] == theirs[1] else f"MISMATCH {which} {mine} {theirs} ") + name)
    elif mode == "hashes":
        for name in ["trajectory_msgs/msg/MultiDOFJointTrajectory", "visualization_msgs/msg/MarkerArray"]:
            print(name, ts.hash_rihs01(name))
    elif mode == "encode":
        for name, msg in cases(ts):
            cdr = ts.serialize_cdr(msg, msg.__msgtype__)
            value = plain(ts, ts.deserialize_cdr(cdr, msg.__msgtype__))
            print(json.dumps({"name": name, "type": msg.__msgtype__, "cdr": bytes(cdr).hex(), "value": value}))
    elif mode == "decode":
        for line in sys.stdin:
            case = json.loads(line)
            value = plain(ts, ts.deserialize_cdr(bytes.fromhex(case["cdr"]), case["type"]))
            print(json.dumps({"name": case["name"], "value": value}), flush=True)
    elif mode == "attachment":
        import zenoh.ext as ze

        seq, stamp = int(sys.argv[3]), int(sys.argv[4])
        print(ze.z_serialize((ze.Int64(seq), ze.Int64(stamp), [ze.UInt8(i) for i in range(16)])).to_bytes().hex())
    else:
        sys.exit(f"unknown mode {mode}")


if __name__ == "__main__":
    main()
