"""The messages and stubs of `proto/dmp/v1`, generated when the package was built (see `hatch_build.py`)."""

from dmp_cell._pb.dmp.v1 import motion_pb2 as motion
from dmp_cell._pb.dmp.v1 import motion_pb2_grpc as motion_grpc
from dmp_cell._pb.dmp.v1 import primitives_pb2 as primitives
from dmp_cell._pb.dmp.v1 import primitives_pb2_grpc as primitives_grpc
from dmp_cell._pb.dmp.v1 import robots_pb2 as robots
from dmp_cell._pb.dmp.v1 import robots_pb2_grpc as robots_grpc
from dmp_cell._pb.dmp.v1 import scene_pb2 as scene
from dmp_cell._pb.dmp.v1 import scene_pb2_grpc as scene_grpc
from dmp_cell._pb.dmp.v1 import server_pb2 as server
from dmp_cell._pb.dmp.v1 import server_pb2_grpc as server_grpc
from dmp_cell._pb.dmp.v1 import types_pb2 as types

__all__ = [
    "motion",
    "motion_grpc",
    "primitives",
    "primitives_grpc",
    "robots",
    "robots_grpc",
    "scene",
    "scene_grpc",
    "server",
    "server_grpc",
    "types",
]
