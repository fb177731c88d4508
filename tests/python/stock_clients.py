"""Stock Python clients against a secured dmp-server: grpcio as a robot, eclipse-zenoh as a perception node.

Run by `tests/tests/server/python_clients.rs`, which starts the server (TLS, an access file made by
`access init`), stores the robot's primitive and checks on the server what the Zenoh puts changed. Only the
stock libraries are used: the stubs are generated here from `proto/` with grpc_tools (no system protoc), TLS is
grpcio's `ssl_channel_credentials`, the token goes in the `authorization` metadata, and the Zenoh session is opened
from the perception config that `access init` wrote.

Usage: stock_clients.py PROTO_DIR SET_DIR GRPC_ADDR ZENOH_LOCATOR CELL ROBOT OTHER_ROBOT
Prints one line per check; exits non-zero (with the reason) at the first that fails.
"""

import importlib
import json
import pathlib
import sys
import tempfile
import time

import grpc
import zenoh
from grpc_tools import protoc


def stubs(proto_dir: pathlib.Path, out: pathlib.Path):
    """Generates the Python stubs of every .proto under proto_dir/dmp/v1 into out and imports them."""
    files = sorted(str(p.relative_to(proto_dir)) for p in (proto_dir / "dmp" / "v1").glob("*.proto"))
    include = pathlib.Path(protoc.__file__).parent / "_proto"
    code = protoc.main(
        ["grpc_tools.protoc", f"-I{proto_dir}", f"-I{include}", f"--python_out={out}", f"--grpc_python_out={out}"]
        + files
    )
    if code != 0:
        sys.exit(f"protoc failed on {files}")
    sys.path.insert(0, str(out))
    return (
        importlib.import_module("dmp.v1.motion_pb2"),
        importlib.import_module("dmp.v1.motion_pb2_grpc"),
        importlib.import_module("dmp.v1.primitives_pb2"),
        importlib.import_module("dmp.v1.primitives_pb2_grpc"),
        importlib.import_module("dmp.v1.types_pb2"),
    )


def check(ok: bool, what: str):
    if not ok:
        sys.exit(f"FAILED: {what}")
    print(f"ok: {what}", flush=True)


def code_of(call) -> grpc.StatusCode:
    """The status code a call ends with (None when it succeeds)."""
    try:
        call()
    except grpc.RpcError as e:
        return e.code()
    return None


def as_robot(motion, motion_grpc, primitives, primitives_grpc, set_dir, addr, robot, other):
    token = (set_dir / f"{robot}.token").read_text().strip()
    ca = (set_dir / "ca.pem").read_bytes()
    channel = grpc.secure_channel(addr, grpc.ssl_channel_credentials(root_certificates=ca))
    grpc.channel_ready_future(channel).result(timeout=20)
    auth = [("authorization", f"Bearer {token}")]
    stub = motion_grpc.MotionServiceStub(channel)

    def execute(robot_id, metadata):
        request = motion.ExecuteRequest(
            motion=motion.MotionSpec(robot_id=robot_id, primitive="reach"),
            pacing=motion.PACING_AS_FAST_AS_READ,
            # The server's default profile holds the 2 m/s reach to 1 m/s: it arrives after 3 tau, the default end.
            max_duration_s=6.0,
        )
        return list(stub.Execute(request, metadata=metadata, timeout=20))

    segments = execute(robot, auth)
    check(len(segments) > 1 and all(s.robot_id == robot for s in segments), f"{robot} streams itself")
    check(segments[-1].status == motion.GOAL_REACHED, f"{robot}'s stream reaches its goal")
    last = segments[-1]
    goal = list(last.positions[-last.dim :])
    check(all(abs(a - b) < 1e-2 for a, b in zip(goal, [1.0, 0.5])), f"{robot} ends at the goal ({goal})")

    check(code_of(lambda: execute(other, auth)) == grpc.StatusCode.PERMISSION_DENIED, f"{robot} cannot stream {other}")
    check(code_of(lambda: execute(robot, [])) == grpc.StatusCode.UNAUTHENTICATED, "no token: unauthenticated")
    wrong = [("authorization", "Bearer " + "0" * 64)]
    check(code_of(lambda: execute(robot, wrong)) == grpc.StatusCode.UNAUTHENTICATED, "a wrong token: unauthenticated")

    library = primitives_grpc.PrimitiveServiceStub(channel)
    listed = library.List(primitives.ListPrimitivesRequest(robot_id=robot), metadata=auth, timeout=10)
    check([r.name for r in listed.records] == ["reach"], f"{robot} reads its own primitives")
    forbidden = code_of(
        lambda: library.Delete(primitives.DeletePrimitiveRequest(robot_id=robot, name="reach"), metadata=auth, timeout=10)
    )
    check(forbidden == grpc.StatusCode.PERMISSION_DENIED, f"{robot} cannot delete its primitives")

    # A client that trusts another CA fails the handshake.
    stranger = grpc.secure_channel(addr, grpc.ssl_channel_credentials(root_certificates=(set_dir / "other-ca.pem").read_bytes()))
    try:
        grpc.channel_ready_future(stranger).result(timeout=3)
        check(False, "a client trusting another CA connected")
    except grpc.FutureTimeoutError:
        check(True, "a client trusting another CA does not connect")
    channel.close()


def as_perception(types, set_dir, locator, cell):
    config = zenoh.Config.from_file(str(set_dir / "zenoh-perception.json5"))
    config.insert_json5("connect/endpoints", json.dumps([locator]))
    session = zenoh.open(config)

    def obstacle(oid):
        return json.dumps({"id": oid, "center": [5.0, 5.0], "semi_axes": [0.1, 0.1]})

    # Denied ones and a put then deleted first, the last put last: the server sees them in this order (one link).
    session.put("dmp/cell-b/obstacles/py-elsewhere", obstacle("py-elsewhere"))
    # A robot state the server would take from a server (fresh, in the workspace, with a footprint): only the
    # access control keeps it out.
    ghost = types.RobotState(
        robot_id="py-ghost",
        stamp_unix_s=time.time(),
        position=[0.5, 0.25],
        velocity=[0.0, 0.0],
        footprint=types.Superquadric(semi_axes=[0.2, 0.2]),
    )
    session.put(f"dmp/{cell}/robots/py-ghost/state", ghost.SerializeToString())
    session.put(f"dmp/{cell}/obstacles/py-gone", obstacle("py-gone"))
    session.delete(f"dmp/{cell}/obstacles/py-gone")
    session.put(f"dmp/{cell}/obstacles/py-seen", obstacle("py-seen"))
    print("ok: perception published", flush=True)
    # Stays up until the test has read the scene (it closes stdin), so that nothing is lost on close.
    sys.stdin.read()
    session.close()


def main():
    proto_dir, set_dir, addr, locator, cell, robot, other = sys.argv[1:8]
    set_dir = pathlib.Path(set_dir)
    with tempfile.TemporaryDirectory() as out:
        motion, motion_grpc, primitives, primitives_grpc, types = stubs(pathlib.Path(proto_dir), pathlib.Path(out))
        as_robot(motion, motion_grpc, primitives, primitives_grpc, set_dir, addr, robot, other)
        as_perception(types, set_dir, locator, cell)


if __name__ == "__main__":
    main()
