from pathlib import Path

import pytest

from pygoby.protobuf import ProtoError, ProtoLoader


def test_loads_user_proto_importing_dccl_options(vectors_dir: Path) -> None:
    loader = ProtoLoader([vectors_dir / "dccl"])
    loader.load_file("example.proto")
    cls = loader.message_class("example.Tiny")
    assert cls(a=5).a == 5


def test_file_outside_include_path_gets_its_own_dir(tmp_path: Path) -> None:
    (tmp_path / "m.proto").write_text('syntax = "proto2"; package t; message M { optional int32 x = 1; }')
    loader = ProtoLoader()
    loader.load_file(tmp_path / "m.proto")
    assert loader.message_class("t.M")(x=3).x == 3


def test_syntax_error_is_reported(tmp_path: Path) -> None:
    (tmp_path / "bad.proto").write_text('syntax = "proto2"; message { }')
    with pytest.raises(ProtoError, match="bad.proto"):
        ProtoLoader().load_file(tmp_path / "bad.proto")


def test_unknown_message(tmp_path: Path) -> None:
    with pytest.raises(ProtoError, match="unknown message type"):
        ProtoLoader().message_class("no.Such")
