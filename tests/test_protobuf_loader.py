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


def test_default_loader_uses_the_generated_modules() -> None:
    from pygoby.protobuf import default_loader
    from pygoby.protobuf.goby.acomms.protobuf import modem_message_pb2

    loader = default_loader()
    file = loader.load_file("goby/acomms/protobuf/modem_message.proto")
    assert file is modem_message_pb2.DESCRIPTOR
    cls = loader.message_class("goby.acomms.protobuf.ModemTransmission")
    assert cls is modem_message_pb2.ModemTransmission


def test_users_file_in_the_default_pool_imports_our_classes(tmp_path: Path) -> None:
    from pygoby.protobuf import default_loader
    from pygoby.protobuf.goby.acomms.protobuf import modem_message_pb2

    (tmp_path / "uses_ours_in_default_pool.proto").write_text(
        'syntax = "proto2"; import "goby/acomms/protobuf/modem_message.proto";'
        " package uses_ours; message Wrapper {"
        " optional goby.acomms.protobuf.ModemTransmission transmission = 1; }"
    )
    loader = default_loader()
    loader.load_file(tmp_path / "uses_ours_in_default_pool.proto")
    wrapper = loader.message_class("uses_ours.Wrapper")(transmission={"src": 3})
    assert type(wrapper.transmission) is modem_message_pb2.ModemTransmission
    assert wrapper.transmission.src == 3


def test_generated_modules_import_each_other_inside_the_package(tmp_path: Path) -> None:
    from pygoby.protobuf import generate

    (tmp_path / "goby").mkdir()
    (tmp_path / "goby" / "base.proto").write_text(
        'syntax = "proto2"; package g; message Base { optional int32 v = 1; }'
    )
    (tmp_path / "goby" / "top.proto").write_text(
        'syntax = "proto2"; import "goby/base.proto"; package g;'
        " message Top { optional Base base = 1; }"
    )
    generate.generate(tmp_path)
    module, stub = generate.outputs("goby/top.proto", tmp_path)
    assert "from pygoby.protobuf.goby import base_pb2" in module.read_text()
    assert "'pygoby.protobuf.goby.top_pb2'" in module.read_text()
    assert "from pygoby.protobuf.goby import base_pb2" in stub.read_text()
    assert "class Top(" in stub.read_text()
    assert not generate.is_stale(tmp_path)
    (tmp_path / "goby" / "base.proto").unlink()  # a .proto gone: its outputs are stale
    assert generate.is_stale(tmp_path)
