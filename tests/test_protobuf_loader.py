from pathlib import Path

import pytest

from pygoby.protobuf import ProtoError, ProtoLoader


def test_loads_user_proto_importing_dccl_options(vectors_dir: Path) -> None:
    loader = ProtoLoader([vectors_dir / "dccl"])
    loader.load_file("example.proto")
    cls = loader.message_class("example.Tiny")
    assert cls(a=5).a == 5


def test_file_outside_include_path_gets_its_own_dir(tmp_path: Path) -> None:
    (tmp_path / "m.proto").write_text(
        'syntax = "proto2"; package t; message M { optional int32 x = 1; }'
    )
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


def test_same_import_compiled_twice_with_aliased_enum_default(tmp_path: Path) -> None:
    (tmp_path / "alias.proto").write_text(
        'syntax = "proto2"; package a; enum E { option allow_alias = true; X = 0; Y = 0; Z = 1; }'
        " message M { optional E e = 1 [default = Y]; }"
    )
    (tmp_path / "one.proto").write_text(
        'syntax = "proto2"; import "alias.proto"; package a; message One { optional M m = 1; }'
    )
    (tmp_path / "two.proto").write_text(
        'syntax = "proto2"; import "alias.proto"; package a; message Two { optional M m = 1; }'
    )
    loader = ProtoLoader([tmp_path])
    loader.load_file("one.proto")
    loader.load_file("two.proto")  # recompiles alias.proto: identical, so accepted
    assert loader.message_class("a.Two")().m.e == 0


def test_different_definition_under_a_loaded_name_is_refused(tmp_path: Path) -> None:
    first, second = tmp_path / "a", tmp_path / "b"
    first.mkdir()
    second.mkdir()
    (first / "x.proto").write_text(
        'syntax = "proto2"; package x; message M { optional int32 v = 1; }'
    )
    (second / "x.proto").write_text(
        'syntax = "proto2"; package x; message M { optional int64 v = 1; }'
    )
    (second / "y.proto").write_text(
        'syntax = "proto2"; import "x.proto"; package y; message N { optional x.M m = 1; }'
    )
    loader = ProtoLoader()
    loader.load_file(first / "x.proto")
    with pytest.raises(ProtoError, match="different definition"):
        loader.load_file(second / "y.proto")
