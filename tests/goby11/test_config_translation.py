"""Goby 1.1 / Goby 2 configuration forms mapped onto today's configuration in one step at load
(pygoby.moos.goby11_config, through read_configuration), with notes and unchanged lines."""

from __future__ import annotations

import pytest

from pygoby.acomms import messages as acomms_pb
from pygoby.errors import ConfigError
from pygoby.moos import goby11_config
from pygoby.moos.appconfig import read_configuration
from pygoby.moos.moosfile import MissionFile
from pygoby.protobuf import builtin_class
from tests.goby11.seed_listings import EXAMPLES

PACOMMS = builtin_class(
    "goby/apps/moos/protobuf/pAcommsHandler_config.proto",
    "goby.apps.moos.protobuf.pAcommsHandlerConfig",
)
VERBOSITY = (
    PACOMMS.DESCRIPTOR.fields_by_name["common"]
    .message_type.fields_by_name["verbosity"]
    .enum_type.values_by_name
)
PTRANSLATOR = builtin_class(
    "goby/apps/moos/protobuf/pTranslator_config.proto", "goby.apps.moos.protobuf.pTranslatorConfig"
)


def read(block: str, cls=PACOMMS, app="pAcommsHandler"):
    mission = MissionFile.from_text(
        f"ServerPort = 9000\n\nProcessConfig = {app}\n{{\n{block}\n}}\n"
    )
    notes: list[str] = []
    return read_configuration(cls, mission, app, notes=notes), notes


@pytest.mark.parametrize(
    "example",
    ["basic_ccl/mm1.moos", "basic_ccl/mm2.moos", "ccl_and_dccl/mm1.moos", "ccl_and_dccl/mm2.moos"],
)
def test_seed_examples_read_verbatim(example):
    path = EXAMPLES / "MOOS" / example
    notes: list[str] = []
    cfg = read_configuration(PACOMMS, MissionFile.read(path), "pAcommsHandler", notes=notes)
    assert cfg.driver_cfg.Extensions[acomms_pb.MM_CONFIG].reset_nvram is False
    assert cfg.driver_cfg.Extensions[acomms_pb.MM_CONFIG].HasField("reset_nvram")
    assert {s.type for s in cfg.mac_cfg.slot} == {acomms_pb.DATA}
    (queue,) = cfg.queue_cfg.queue
    assert queue.key.type == acomms_pb.QUEUE_CCL and queue.key.id in (2, 14)
    assert any("[MicroModemConfig.reset_nvram]" in n for n in notes)
    assert all(n.startswith(f"{path}:") for n in notes)
    if "ccl_and_dccl" in example:
        assert cfg.common.verbosity == VERBOSITY["VERBOSE"].number
        assert [f.path for f in cfg.transitional_cfg.message_file] == [
            "../../xml/simple_status.xml"
        ]
        assert not cfg.dccl_cfg.message_file
        assert any("VERBOSITY_GUI -> VERBOSE" in n for n in notes)


def test_notes_name_the_file_lines_of_the_changed_fields():
    _, notes = read(
        "modem_id: 1\ncommon { verbosity: VERBOSITY_WARN }\n"
        'driver_cfg {\n  [MicroModemConfig.nvram_cfg]: "DQF,1"\n}'
    )
    assert notes == [
        "mission file:6: verbosity: VERBOSITY_WARN -> WARN",
        "mission file:8: [MicroModemConfig.nvram_cfg] -> "
        "[goby.acomms.micromodem.protobuf.config] { nvram_cfg }",
    ]


@pytest.mark.parametrize(
    ("old", "new"),
    [
        ("VERBOSITY_QUIET", "QUIET"),
        ("VERBOSITY_WARN", "WARN"),
        ("VERBOSITY_VERBOSE", "VERBOSE"),
        ("VERBOSITY_DEBUG", "DEBUG1"),
        ("VERBOSITY_GUI", "VERBOSE"),
    ],
)
def test_every_app_common_accepts_goby_1_1_verbosity(old, new):
    cfg, notes = read(f"common {{ verbosity: {old} log: false }}", PTRANSLATOR, "pTranslator")
    assert cfg.common.show_gui == (old == "VERBOSITY_GUI")  # Goby 2's mapping: the live view
    assert cfg.common.verbosity == VERBOSITY[new].number
    assert len(notes) == 1


def test_slot_types_and_dropped_forms():
    cfg, notes = read("""modem_id: 1
  mac_cfg { type: MAC_FIXED_DECENTRALIZED
    slot { src: 1 dest: 2 type: SLOT_PING slot_seconds: 10 last_heard_time: "2011-Jan-22 12:08:06" }
    slot { src: 1 dest: 0 type: SLOT_REMUS_LBL slot_seconds: 10 }
    slot { src: 1 type: SLOT_NARROWBAND_LBL slot_seconds: 10 } }
  dccl_cfg { modem_id: 1 crypto_passphrase: "secret" message_file { path: "a.xml" manipulator: TCP_SHARE_IN } }
  queue_cfg { modem_id: 1 message_file { path: "a.xml" } message_file { path: "b.xml" manipulator: LOOPBACK } }
  tcp_share_enable: false tcp_share_port: 11000 tcp_share_to_ip: "1.2.3.4:11000"
  """)
    _ping, _remus, _narrowband = cfg.mac_cfg.slot
    assert [s.type for s in cfg.mac_cfg.slot] == [acomms_pb.DRIVER_SPECIFIC] * 3
    assert [s.Extensions[acomms_pb.MM_TRANSMISSION].type for s in cfg.mac_cfg.slot] == [
        acomms_pb.MICROMODEM_TWO_WAY_PING,
        acomms_pb.MICROMODEM_REMUS_LBL_RANGING,
        acomms_pb.MICROMODEM_NARROWBAND_LBL_RANGING,
    ]
    assert cfg.dccl_cfg.crypto_passphrase == "secret"
    assert [(f.path, list(f.manipulator)) for f in cfg.transitional_cfg.message_file] == [
        ("a.xml", []),
        ("b.xml", [5]),
    ]
    text = "\n".join(notes)
    for word in (
        "last_heard_time dropped",
        "dccl_cfg.modem_id dropped",
        "TCP_SHARE_IN dropped",
        "tcp_share_enable dropped",
        "tcp_share_port dropped",
        "tcp_share_to_ip dropped",
        "2 XML message file(s)",
    ):
        assert word in text, word


def test_goby2_forms():
    cfg, notes = read("""modem_id: 3
  driver_cfg { driver_type: DRIVER_UDP
    [UDPDriverConfig.local] { port: 50001 }
    [UDPDriverConfig.remote] { ip: "127.0.0.1" port: 50002 } }
  listen_driver_cfg { driver_type: DRIVER_WHOI_MICROMODEM [micromodem.protobuf.Config.reset_nvram]: true }
  transitional_cfg { message_file { path: "x.xml" } generated_proto_dir: "/tmp/proto" }""")
    udp = cfg.driver_cfg.Extensions[acomms_pb.UDP_CONFIG]
    assert (udp.local.port, udp.remote[0].port) == (50001, 50002)
    assert cfg.listen_driver_cfg[0].Extensions[acomms_pb.MM_CONFIG].reset_nvram is True
    assert cfg.transitional_cfg.generated_proto_dir == "/tmp/proto"
    assert len(notes) == 3


def test_goby3_configuration_is_left_alone():
    block = "modem_id: 1\ncommon { verbosity: DEBUG2 }\ndriver_cfg { [goby.acomms.micromodem.protobuf.config] { reset_nvram: true } }"
    translation = goby11_config.translate(block, PACOMMS.DESCRIPTOR)
    assert translation == goby11_config.Translation(block, [])


def test_errors_after_translated_fields_keep_their_line():
    with pytest.raises(ConfigError, match=r"mission file:9: .*no_such_field"):
        read(
            "modem_id: 1\ncommon { verbosity: VERBOSITY_GUI }\n"
            "driver_cfg { [MicroModemConfig.reset_nvram]: false }\n"
            "mac_cfg { slot { type: SLOT_PING } }\nno_such_field: 3"
        )


def test_unparsable_text_is_left_to_protobuf():
    with pytest.raises(ConfigError, match=r"mission file:5: "):
        read('modem_id: 1 common { verbosity: "unterminated }')


def test_goby11_mac_updates_become_todays():
    from pygoby.moosacomms.goby11 import mac_update_from_goby11

    U = acomms_pb.MACUpdate.UpdateType
    current = [
        acomms_pb.ModemTransmission(src=1, dest=2, type=acomms_pb.DATA, slot_seconds=10),
        acomms_pb.ModemTransmission(src=2, dest=1, type=acomms_pb.DATA, slot_seconds=10),
    ]
    add = mac_update_from_goby11(
        "dest: 1 update_type: ADD slot { src: 1 dest: 3 rate: 0 slot_seconds: 15 type: SLOT_DATA }",
        current,
        1,
    )
    assert (add.src, add.dest, add.update_type) == (1, 1, U.Value("PUSH_BACK"))
    assert (add.slot[0].dest, add.slot[0].type, add.slot[0].slot_seconds) == (
        3,
        acomms_pb.DATA,
        15.0,
    )
    remove = mac_update_from_goby11(
        "dest: 1 update_type: REMOVE slot { src: 2 dest: 1 slot_seconds: 10 type: SLOT_DATA }",
        current,
        1,
    )
    assert remove.update_type == U.Value("ASSIGN") and [(s.src, s.dest) for s in remove.slot] == [
        (1, 2)
    ]
    replace = mac_update_from_goby11(
        "dest: 1 slot { src: 1 type: SLOT_PING slot_seconds: 5 }", current, 1
    )
    assert replace.update_type == U.Value("ASSIGN")
    assert (
        replace.slot[0].Extensions[acomms_pb.MM_TRANSMISSION].type
        == acomms_pb.MICROMODEM_TWO_WAY_PING
    )
    assert mac_update_from_goby11("src: 1 dest: 1 update_type: PUSH_BACK", current, 1) is None


@pytest.mark.parametrize(
    ("right", "wrong", "reason"),
    [
        (
            'in_pubsub_var: "IN_REMUS_STATUS"',
            'in_pubsub_var "IN_REMUS_STATUS"',
            "expected ':' after in_pubsub_var",
        ),
        (
            'message_file { path: "../../xml/simple_status.xml" }',
            'message_file { path: "../../xml/simple_status.xml"',
            "the '{' after dccl_cfg is never closed",
        ),
    ],
)
def test_a_syntax_error_is_reported_at_its_line_in_the_users_words(tmp_path, right, wrong, reason):
    """The manual's mission with one mistake past its Goby 1.1 forms (which were reported
    instead, at their own line, as not registered extensions or unknown enum values)."""
    text = (EXAMPLES / "MOOS" / "ccl_and_dccl" / "mm1.moos").read_text()
    assert text.count(right) == 1
    text = text.replace(right, wrong)
    path = tmp_path / "mm1.moos"
    path.write_text(text)
    line = next(n for n, x in enumerate(text.splitlines(), 1) if wrong.strip() in x)
    if "never closed" in reason:  # the next '}' closes message_file: dccl_cfg's stays open
        line -= 2
    with pytest.raises(ConfigError) as caught:
        read_configuration(PACOMMS, MissionFile.read(path), "pAcommsHandler")
    assert str(caught.value) == f"{path}:{line}: {reason}"
