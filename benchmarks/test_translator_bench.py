"""Translator throughput: publishing and creating a node report with each technique."""

from pathlib import Path

import pytest
from google.protobuf import text_format

from pygoby.moos.translator import Translator, entry_class
from pygoby.protobuf import ProtoLoader

PROTO = Path(__file__).resolve().parents[1] / "tests/moos/translator/protos/translator_test.proto"
NAME = "pygoby.test.translator.BasicNodeReport"
FORMAT = "NAME=%1%,X=%202%,Y=%3%,HEADING=%201%,REPEAT={%10%}"


@pytest.fixture(scope="module")
def setup():
    loader = ProtoLoader([PROTO.parent])
    loader.load_file(PROTO)
    entry = text_format.Parse(
        f"""protobuf_name: "{NAME}"
        create {{ technique: TECHNIQUE_FORMAT moos_var: "F" format: "{FORMAT}" }}
        create {{ technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS moos_var: "KV" }}
        create {{ technique: TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT moos_var: "PB" }}
        publish {{ technique: TECHNIQUE_FORMAT moos_var: "F" format: "{FORMAT}" }}
        publish {{ technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS moos_var: "KV" }}
        publish {{ technique: TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT moos_var: "PB" }}""",
        entry_class()(),
    )
    translator = Translator([entry], loader.message_class)
    report = loader.message_class(NAME)(
        Name="unicorn", x=550, y=1023.5, heading=240, repeat=[1, 2, 3]
    )
    return translator, report


def test_publish_three_techniques(benchmark, setup):
    translator, report = setup
    posts = benchmark(translator.publish, report)
    assert len(posts) == 3


def test_create_three_techniques(benchmark, setup):
    translator, report = setup
    variables = {post.var: post.value for post in translator.publish(report)}
    created = benchmark(translator.create, NAME, variables)
    assert created == report
