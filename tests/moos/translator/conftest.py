from pathlib import Path

import pytest

from pygoby.moos.translator import entry_class
from pygoby.protobuf import ProtoLoader

PROTO_DIR = Path(__file__).parent / "protos"
PACKAGE = "pygoby.test.translator"


@pytest.fixture(scope="session")
def loader() -> ProtoLoader:
    proto_loader = ProtoLoader([PROTO_DIR])
    proto_loader.load_file(PROTO_DIR / "translator_test.proto")
    return proto_loader


@pytest.fixture(scope="session")
def msgs(loader):
    """Namespace of the test message classes."""

    class Classes:
        BasicNodeReport = loader.message_class(f"{PACKAGE}.BasicNodeReport")
        TestMsg = loader.message_class(f"{PACKAGE}.TestMsg")
        EmbeddedMsg1 = loader.message_class(f"{PACKAGE}.EmbeddedMsg1")
        Deploy = loader.message_class(f"{PACKAGE}.Deploy")

    return Classes


@pytest.fixture(scope="session")
def Entry():
    return entry_class()


def populate_test_msg(msg) -> None:
    """Every field of TestMsg set, with distinct values (as goby3's translator test does)."""
    i = 0

    def nxt() -> int:
        nonlocal i
        i += 1
        return i

    for suffix in ("optional", "required"):
        setattr(msg, f"double_default_{suffix}", nxt() + 0.1)
        setattr(msg, f"float_default_{suffix}", nxt() + 0.2)
        setattr(msg, f"int32_default_{suffix}", nxt())
        setattr(msg, f"int64_default_{suffix}", -nxt())
        setattr(msg, f"uint32_default_{suffix}", nxt())
        setattr(msg, f"uint64_default_{suffix}", nxt())
        setattr(msg, f"sint32_default_{suffix}", -nxt())
        setattr(msg, f"sint64_default_{suffix}", nxt())
        setattr(msg, f"fixed32_default_{suffix}", nxt())
        setattr(msg, f"fixed64_default_{suffix}", nxt())
        setattr(msg, f"sfixed32_default_{suffix}", nxt())
        setattr(msg, f"sfixed64_default_{suffix}", -nxt())
        setattr(msg, f"bool_default_{suffix}", True)
        setattr(msg, f"string_default_{suffix}", "abc123")
        setattr(msg, f"bytes_default_{suffix}", bytes.fromhex("00112233aabbcc1234"))
        setattr(msg, f"enum_default_{suffix}", 3)
        embedded = getattr(msg, f"msg_default_{suffix}")
        embedded.val = nxt() + 0.3
        embedded.msg.val = nxt()
    for j in range(2):
        msg.double_default_repeat.append(nxt() + 0.1)
        msg.float_default_repeat.append(nxt() + 0.2)
        msg.int32_default_repeat.append(nxt())
        msg.int64_default_repeat.append(-nxt())
        msg.uint32_default_repeat.append(nxt())
        msg.uint64_default_repeat.append(nxt())
        msg.sint32_default_repeat.append(-nxt())
        msg.sint64_default_repeat.append(nxt())
        msg.fixed32_default_repeat.append(nxt())
        msg.fixed64_default_repeat.append(nxt())
        msg.sfixed32_default_repeat.append(nxt())
        msg.sfixed64_default_repeat.append(-nxt())
        msg.bool_default_repeat.append(True)
        msg.string_default_repeat.append("abc123")
        msg.bytes_default_repeat.append(bytes.fromhex("00aabbcc" if j else "ffeedd12"))
        msg.enum_default_repeat.append(nxt() % 3 + 1)
        embedded = msg.msg_default_repeat.add()
        embedded.val = nxt() + 0.3
        embedded.msg.val = nxt()


@pytest.fixture
def full_test_msg(msgs):
    """A TestMsg with every field set."""
    msg = msgs.TestMsg()
    populate_test_msg(msg)
    return msg
