"""Generates the gRPC stubs of the repository's `proto/dmp/v1/*.proto` at build time.

grpcio-tools' bundled protoc writes them into `src/dmp_cell/_pb/` (ignored by git, shipped as build artifacts).
protoc's Python output imports its siblings as `dmp.v1.x_pb2`; they are rewritten to `dmp_cell._pb.dmp.v1.x_pb2`,
so that the package installs no top-level `dmp` package of its own.

The .proto files are read from `$DMP_PROTO_DIR`, else `proto/` beside this file (an sdist), else the repository's
`../proto`.
"""

import os
import re
import shutil
import sys
import tempfile
from pathlib import Path

from hatchling.builders.hooks.plugin.interface import BuildHookInterface

PACKAGE = "dmp_cell._pb"
IMPORT = re.compile(r"^from dmp\.v1 import ", re.MULTILINE)


def proto_root(root: Path) -> Path:
    candidates = [Path(os.environ["DMP_PROTO_DIR"])] if os.environ.get("DMP_PROTO_DIR") else []
    candidates += [root / "proto", root.parent / "proto"]
    for c in candidates:
        if (c / "dmp" / "v1").is_dir():
            return c.resolve()
    tried = ", ".join(str(c) for c in candidates)
    raise RuntimeError(f"dmp_cell: no proto/dmp/v1 directory found (tried {tried}); set DMP_PROTO_DIR")


def generate(protos: Path, out: Path) -> None:
    """Writes the stubs of every protos/dmp/v1/*.proto into out/dmp/v1 (out is replaced)."""
    from grpc_tools import protoc

    files = sorted(str(p.relative_to(protos)) for p in (protos / "dmp" / "v1").glob("*.proto"))
    if not files:
        raise RuntimeError(f"dmp_cell: {protos / 'dmp' / 'v1'} holds no .proto file")
    include = Path(protoc.__file__).parent / "_proto"
    with tempfile.TemporaryDirectory() as tmp:
        args = ["grpc_tools.protoc", f"-I{protos}", f"-I{include}", f"--python_out={tmp}", f"--grpc_python_out={tmp}"]
        if protoc.main(args + files) != 0:
            raise RuntimeError(f"dmp_cell: protoc failed on {files} in {protos}")
        generated = Path(tmp) / "dmp" / "v1"
        if out.exists():
            shutil.rmtree(out)
        (out / "dmp" / "v1").mkdir(parents=True)
        for d in (out, out / "dmp", out / "dmp" / "v1"):
            (d / "__init__.py").write_text('"""Generated at build time from proto/ (hatch_build.py): do not edit."""\n')
        for f in sorted(generated.glob("*.py")):
            text = IMPORT.sub(f"from {PACKAGE}.dmp.v1 import ", f.read_text())
            (out / "dmp" / "v1" / f.name).write_text(text)


class CustomBuildHook(BuildHookInterface):
    def initialize(self, version, build_data):
        root = Path(self.root)
        protos = proto_root(root)
        generate(protos, root / "src" / "dmp_cell" / "_pb")
        print(f"dmp_cell: generated the stubs of {protos}/dmp/v1", file=sys.stderr)
