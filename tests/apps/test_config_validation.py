"""Configuration mistakes are load-time ConfigErrors that say file:line and the field, and bytes
that are not UTF-8 in a configuration file never raise anything else (issue 16 items 10, 11)."""

from __future__ import annotations

import contextlib
import subprocess
import sys

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pygoby.apps.pacommshandler import pAcommsHandler
from pygoby.errors import ConfigError
from pygoby.moos.moosfile import MissionFile
from pygoby.netsim.manager.config import EXAMPLE_CONFIG, load_config, parse_config
from pygoby.netsim.sim.scenario import ScenarioError, load_scenario, parse_scenario
from tests.hypothesis_profiles import examples

from .acomms_mission import PROTO
from .test_pacommshandler_config import EXAMPLE, write

FUZZ = settings(
    max_examples=examples(200),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)


def line_of(path, text: str) -> int:
    """1-based line of the first line of the file at `path` that contains `text`."""
    for number, line in enumerate(path.read_bytes().split(b"\n"), start=1):
        if text.encode() in line:
            return number
    raise AssertionError(f"{text!r} not in {path}")


def load_error(tmp_path, old: str, new: str) -> tuple[ConfigError, object]:
    assert old in EXAMPLE
    path = write(tmp_path, EXAMPLE.replace(old, new, 1))
    with pytest.raises(ConfigError) as info:
        pAcommsHandler.from_mission(path)
    return info.value, path


@pytest.mark.parametrize(
    ("old", "new", "marker", "field", "reason"),
    [
        (
            "serial_baud: 19200",
            "serial_baud: 19200\n    tcp_port: 70000",
            "tcp_port",
            "driver_cfg.tcp_port",
            "70000 is not a port number",
        ),
        (
            "slot { src: 2 dest: -1 rate: 0",
            "slot { src: 2 dest: -1 rate: 9",
            "rate: 9",
            "mac_cfg.slot[1].rate",
            "rate 9 is not a rate of MMDriver (0-5)",
        ),
        (
            'moos_var: "NODE_REPORT_IN" }',
            'moos_var: "NODE_REPORT_IN" }\n    publish { technique: TECHNIQUE_FORMAT moos_var: "X" format: "%77:1%" }',
            "translator_entry {",
            "translator_entry[0]",
            "Invalid ':' syntax",  # goby3 throws at every publication: pAcommsHandler ends
        ),
        ('format: "%11%"', 'format: "%11"', "translator_entry {", "translator_entry[0]", "%11"),
    ],
    ids=["tcp_port", "slot_rate", "publish_format", "create_format"],
)
def test_mistakes_are_load_time_errors_with_file_line_and_field(
    tmp_path, old, new, marker, field, reason
):
    err, path = load_error(tmp_path, old, new)
    assert (err.file, err.line, err.field) == (str(path), line_of(path, marker), field), str(err)
    assert reason in err.reason
    assert str(err).startswith(f"{path}:{err.line}: {field}: ")


def test_a_server_port_that_is_not_a_number_is_an_error_at_its_line(tmp_path):
    path = write(tmp_path, "ServerHost = localhost\nServerPort = abc\n" + EXAMPLE)
    with pytest.raises(ConfigError) as info:
        pAcommsHandler.from_mission(path)
    assert (info.value.file, info.value.line) == (str(path), 2)
    assert "ServerPort = abc is not a number" in str(info.value)
    with pytest.raises(ConfigError, match=r"mission.moos:2: ServerPort: .*not a port number"):
        MissionFile.read(path).get_port("ServerPort")
    moosdb = subprocess.run(
        [sys.executable, "-m", "pygoby.cli", "moosdb", str(path)],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert moosdb.returncode == 1 and "mission.moos:2: ServerPort" in moosdb.stderr


def test_non_utf8_bytes_in_a_mission_file(tmp_path):
    """A Latin-1 comment is harmless; a Latin-1 string value is an error at its line."""
    text = EXAMPLE.replace("modem_id: 1\n", "modem_id: 1  # caf\xe9 du port\n", 1)
    path = tmp_path / "latin1.moos"
    path.write_bytes(text.replace("@PROTO@", str(PROTO)).encode("latin-1"))
    assert pAcommsHandler.from_mission(path).acomms.modem_id == 1
    text = text.replace('nvram_cfg: "DQF,1"', 'nvram_cfg: "DQF,\xe9"')
    path.write_bytes(text.replace("@PROTO@", str(PROTO)).encode("latin-1"))
    with pytest.raises(ConfigError) as info:
        pAcommsHandler.from_mission(path)
    assert info.value.line == line_of(path, "nvram_cfg")
    assert "not valid UTF-8" in str(info.value) and "DQF,\\xe9" in str(info.value)


def _not_utf8(text: str) -> bool:
    try:
        text.encode("latin-1").decode("utf-8")
    except UnicodeDecodeError:
        return True
    return False


latin1_values = st.text(
    st.characters(min_codepoint=0x21, max_codepoint=0xFF, exclude_characters='#"\\'),
    min_size=1,
    max_size=12,
).filter(_not_utf8)


@FUZZ
@given(value=latin1_values, quoted=st.booleans())
def test_latin1_in_an_enum_value_or_a_moos_global_is_a_located_error(tmp_path, value, quoted):
    # issue 25, item 11: Latin-1 bytes in an enum value (protobuf's parser: SystemError) or in
    # a MOOS global copied into a string field (UnicodeEncodeError) are errors at their line
    enum_value = f'"{value}"' if quoted else value
    path = tmp_path / "latin1.moos"
    for lines, line in (
        (
            [
                "Community = v1",
                "ProcessConfig = pAcommsHandler",
                "{",
                f"  driver_type: {enum_value}",
                "}",
            ],
            4,
        ),
        ([f"Community = {value}", "ProcessConfig = pAcommsHandler", "{", "  modem_id: 1", "}"], 1),
    ):
        path.write_bytes("\n".join(lines).encode("latin-1"))
        with pytest.raises(ConfigError) as info:
            pAcommsHandler.read_config(MissionFile.read(path), "pAcommsHandler")
        assert (info.value.file, info.value.line) == (str(path), line)
        assert "not valid UTF-8" in str(info.value)


def test_netsim_config_errors_say_file_line_and_field(tmp_path):
    path = tmp_path / "netsim.cfg"
    path.write_bytes(
        EXAMPLE_CONFIG.replace("manager_tcp_port: 61999", "manager_tcp_port: 70000").encode()
    )
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert (info.value.file, info.value.line, info.value.field) == (
        str(path),
        line_of(path, "manager_tcp_port"),
        "manager_tcp_port",
    )
    # a Latin-1 comment loads; a Latin-1 string is an error at its line
    path.write_bytes(EXAMPLE_CONFIG.encode() + b"# r\xe9sum\xe9\n")
    assert load_config(path).manager_tcp_port == 61999
    path.write_bytes(
        EXAMPLE_CONFIG.encode().replace(b'"127.0.0.1"      #', b'"127.0.0.\xe9"      #')
    )
    with pytest.raises(ConfigError, match=r"netsim.cfg:\d+: listen_address: string is not valid"):
        load_config(path)
    # the console script: one clear line, exit 1, no traceback
    run = subprocess.run(
        [sys.executable, "-m", "pygoby.netsim.manager.server", str(path)],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert run.returncode == 1 and "Traceback" not in run.stderr
    assert f"{path}:{line_of(path, 'listen_address')}: listen_address" in run.stderr


def test_netsim_scenario_with_non_utf8_bytes(tmp_path):
    path = tmp_path / "scenario.pb.cfg"
    path.write_bytes(b'# \xff\nnode { modem_id: 1 track { speed: 1 } }\nevent_log: "\xff"\n')
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert (info.value.file, info.value.line, info.value.field) == (str(path), 3, "event_log")


# -- fuzz: the TextFormat and .moos configuration parsers -----------------------------------------

textformat_bytes = st.one_of(
    st.binary(max_size=120),
    st.lists(
        st.sampled_from(
            [
                b"manager_tcp_port: ",
                b"70000",
                b"1",
                b"listen_address: ",
                b'"',
                b"\xe9",
                b"\xff",
                b"{",
                b"}",
                b"#",
                b"\n",
                b"sim_env_pair",
                b"node",
                b"modem_id: ",
                b"\\",
                b"[",
                b"]",
                b"-",
                b"1e99",
            ]
        ),
        max_size=30,
    ).map(b"".join),
)


@FUZZ
@given(data=textformat_bytes)
def test_netsim_parsers_raise_only_config_errors(data):
    text = data.decode("utf-8", "surrogateescape")
    for parse in (parse_config, parse_scenario):
        try:
            parse(text, "fuzz.cfg")
        except ConfigError as err:
            assert err.file == "fuzz.cfg"


@FUZZ
@given(data=textformat_bytes)
def test_goby_app_block_parser_raises_only_config_errors(tmp_path, data):
    body = data.replace(b"manager_tcp_port", b"modem_id").replace(b"listen_address", b"common")
    path = tmp_path / "fuzz.moos"
    path.write_bytes(b"ServerPort = 9000\nProcessConfig = pAcommsHandler\n{\n" + body + b"\n}\n")
    with contextlib.suppress(ConfigError):
        pAcommsHandler.read_config(MissionFile.read(path), "pAcommsHandler")


@FUZZ
@given(data=st.binary(max_size=200))
def test_mission_file_reader_never_raises_on_bytes(tmp_path, data):
    path = tmp_path / "any.moos"
    path.write_bytes(data)
    mission = MissionFile.read(path)
    mission.get_value("ServerPort")
    mission.goby_block("pAcommsHandler")
    try:
        mission.get_port("ServerPort")
    except ConfigError as err:
        assert err.line is not None
