"""Compile our own .proto files into `_pb2.py` modules and `.pyi` stubs beside them.

Run at build time (setup.py's build_py, also in editable installs) and by `make` before the
tests (`python -m pygoby.protobuf.generate`; it does nothing when every output is newer than
every .proto). The outputs are not committed. At run time pygoby imports these modules for its
own messages and needs protoc only for users' files.

protoc writes each module's imports under the .proto import path ("from goby.acomms.protobuf
import queue_pb2"); our files live inside the pygoby.protobuf package, so those imports are
rewritten to "from pygoby.protobuf.goby.acomms.protobuf import queue_pb2" (one top-level "goby"
or "dccl" package would collide with other installs, e.g. the dccl bindings).

This file uses only the standard library, grpc_tools and mypy_protobuf: setup.py loads it by path,
before pygoby itself can be imported.
"""

from __future__ import annotations

import re
import stat
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path

PROTO_DIR = Path(__file__).resolve().parent
PACKAGE = "pygoby.protobuf"
_SUFFIXES = ("_pb2.py", "_pb2.pyi")


def proto_names(proto_dir: Path = PROTO_DIR) -> list[str]:
    """Import names ("goby/acomms/protobuf/queue.proto") of the .proto files under proto_dir."""
    return sorted(p.relative_to(proto_dir).as_posix() for p in proto_dir.rglob("*.proto"))


def outputs(name: str, proto_dir: Path = PROTO_DIR) -> list[Path]:
    stem = proto_dir / name[: -len(".proto")]
    return [stem.with_name(stem.name + suffix) for suffix in _SUFFIXES]


def _generated_files(proto_dir: Path) -> list[Path]:
    return [p for suffix in _SUFFIXES for p in proto_dir.rglob(f"*{suffix}")]


def is_stale(proto_dir: Path = PROTO_DIR) -> bool:
    """Whether an output is missing, older than a .proto or this generator, or left over from a
    .proto that is gone."""
    names = proto_names(proto_dir)
    expected = {out for name in names for out in outputs(name, proto_dir)}
    if set(_generated_files(proto_dir)) != expected:
        return True
    sources = [proto_dir / name for name in names] + [Path(__file__)]
    newest_source = max(p.stat().st_mtime for p in sources)
    return min(out.stat().st_mtime for out in expected) < newest_source


def _rewrite_imports(text: str, roots: Sequence[str]) -> str:
    alternatives = "|".join(re.escape(r) for r in roots)
    text = re.sub(rf"^from ({alternatives})([.\s])", rf"from {PACKAGE}.\1\2", text, flags=re.M)
    # the module name protobuf gives the classes' __module__ (pickle finds them by it)
    return re.sub(
        rf"(BuildTopDescriptorsAndMessages\(DESCRIPTOR, ')(({alternatives})\.)",
        rf"\1{PACKAGE}.\2",
        text,
    )


def _mypy_plugin(tmp: Path) -> Path:
    """protoc-gen-mypy run by this interpreter (its console script may not be on PATH)."""
    plugin = tmp / "protoc-gen-mypy"
    plugin.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m mypy_protobuf.main "$@"\n')
    plugin.chmod(plugin.stat().st_mode | stat.S_IXUSR)
    return plugin


def generate(proto_dir: Path = PROTO_DIR) -> None:
    """Compile every .proto under proto_dir, replacing all previous outputs."""
    from grpc_tools import protoc  # build-time dependency

    names = proto_names(proto_dir)
    roots = sorted({name.split("/", 1)[0] for name in names})
    well_known = Path(protoc.__file__).resolve().parent / "_proto"
    with tempfile.TemporaryDirectory(prefix="pygoby-generate-") as tmp_name:
        tmp = Path(tmp_name)
        out = tmp / "out"
        out.mkdir()
        args = ["protoc", f"-I{proto_dir}", f"-I{well_known}", f"--python_out={out}"]
        args += [f"--plugin=protoc-gen-mypy={_mypy_plugin(tmp)}", f"--mypy_out=quiet:{out}"]
        if protoc.main([*args, *names]) != 0:
            raise SystemExit(f"protoc failed on the .proto files under {proto_dir}")
        for stale in _generated_files(proto_dir):
            stale.unlink()
        for name in names:
            for generated, target in zip(outputs(name, out), outputs(name, proto_dir), strict=True):
                target.write_text(_rewrite_imports(generated.read_text(), roots))


def main(argv: Sequence[str] | None = None) -> int:
    """`python -m pygoby.protobuf.generate [--force]`: regenerate when stale (or always)."""
    force = "--force" in (sys.argv[1:] if argv is None else argv)
    if force or is_stale():
        generate()
        print(f"generated Python modules for {len(proto_names())} .proto files in {PROTO_DIR}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
