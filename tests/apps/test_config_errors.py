"""Configuration errors that say what to change, each as the operator reads it: where (file:line),
which field, and what to do; and the upstream library names pygoby stands in for."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from pygoby.acomms import DriverNotFoundError
from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.drivers import make_driver
from pygoby.apps.pacommshandler import pAcommsHandler
from pygoby.errors import ConfigError
from pygoby.util.libraries import DCCL_CODECS, FRONTSEAT_DRIVER, MESSAGES, Builtin, builtin_for

from .acomms_mission import PROTO, STATUS

MISSION = """\
ProcessConfig = pAcommsHandler
{
  common { log: false }
  modem_id: 1
  queue_cfg {
    message_entry { protobuf_name: "@QUEUED@" role { type: SOURCE_ID field: "src" } }
  }
  load_proto_file: "@PROTO@"
@EXTRA@}
"""


def mission(tmp_path: Path, proto: str = str(PROTO), queued: str = STATUS, extra: str = "") -> Path:
    path = tmp_path / "vehicle.moos"
    path.write_text(
        MISSION.replace("@PROTO@", proto).replace("@QUEUED@", queued).replace("@EXTRA@", extra)
    )
    return path


def error_of(path: Path) -> str:
    with pytest.raises(ConfigError) as info:
        pAcommsHandler.from_mission(path)
    return str(info.value)


def test_a_proto_file_not_found_lists_every_folder_searched(tmp_path, monkeypatch):
    monkeypatch.chdir("/")
    path = mission(tmp_path, proto="messages/status.proto")
    text = error_of(path)
    head = (
        f'{path}:8: load_proto_file: "messages/status.proto" not found; searched: /, {tmp_path}, '
    )
    assert text.startswith(head), text  # the working directory, then the mission's folder
    assert "pygoby/protobuf" in text  # and the import path
    (tmp_path / "messages").mkdir()
    (tmp_path / "messages" / "status.proto").write_text(PROTO.read_text())
    assert pAcommsHandler.from_mission(path).message_types.loaded  # found beside the mission


def test_a_queue_for_a_type_that_is_not_loaded_names_the_loaded_types(tmp_path):
    text = error_of(mission(tmp_path, queued="pygoby.examples.SimpleStatuss"))
    assert text == (
        f"{tmp_path / 'vehicle.moos'}:6: queue_cfg.message_entry.protobuf_name: "
        '"pygoby.examples.SimpleStatuss" is not a loaded message type; the types load_proto_file '
        "and load_shared_library loaded are: pygoby.examples.SimpleStatus, pygoby.examples.Command"
    )


def test_a_translator_entry_for_a_type_that_is_not_loaded_is_located_and_names_the_loaded_types(
    tmp_path,
):
    """As the queue_cfg error, in each app that reads translator entries: pAcommsHandler, the
    commander tools reading its block (iCommander, liaison) and pTranslator."""
    from pygoby.apps.icommander import iCommander
    from pygoby.apps.ptranslator import pTranslator

    entry = (
        '  translator_entry {\n    protobuf_name: "pygoby.examples.SimpleStatuss"\n'
        '    trigger { type: TRIGGER_PUBLISH moos_var: "S" }\n  }\n'
    )
    path = mission(tmp_path, extra=entry)
    path.write_text(
        "LatOrigin = 42\nLongOrigin = -70\n"
        + path.read_text()
        + "ProcessConfig = iCommander\n{\n  common { log: false }\n}\n"
    )
    expected = (
        f"{path}:12: translator_entry.protobuf_name: "
        '"pygoby.examples.SimpleStatuss" is not a loaded message type; the types load_proto_file '
        "and load_shared_library loaded are: pygoby.examples.SimpleStatus, pygoby.examples.Command"
    )
    for app, name in ((pAcommsHandler, "pAcommsHandler"), (iCommander, "iCommander")):
        with pytest.raises(ConfigError) as info:
            app.from_mission(path, name)
        assert str(info.value) == expected
    path.write_text(f'ProcessConfig = pTranslator\n{{\n  load_proto_file: "{PROTO}"\n{entry}}}\n')
    with pytest.raises(ConfigError) as info:
        pTranslator.from_mission(path, "pTranslator")
    assert str(info.value) == expected.replace(":12:", ":5:")


@pytest.mark.parametrize(
    ("library", "error"),
    [
        ("/usr/lib/libgoby_moos.so.30", None),  # messages built into pygoby
        ("libgoby.so", None),
        ("libdccl.so.4", None),
        (
            "../build/lib/libmy_messages.so",
            '"../build/lib/libmy_messages.so": pygoby cannot load '
            "compiled C++ libraries; use load_proto_file with the .proto file(s) the library was "
            "built from instead",
        ),
        ("/home/toby/dccl/build/lib/libdccl_ccl_compat.so", None),  # pygoby.dccl's built-ins
        ("libdccl_arithmetic.so.31", None),
        (
            "libdccl_no_such_codecs.so",
            '"libdccl_no_such_codecs.so": pygoby has no built-in '
            "equivalent of this DCCL codec library (built in: libdccl_ccl_compat.so, "
            "libdccl_arithmetic.so, libdccl_native_protobuf.so, libdccl.so)",
        ),
        (
            "libgoby_frontseat_bluefin.so.30",
            '"libgoby_frontseat_bluefin.so.30": this library is a frontseat driver, not messages',
        ),
    ],
)
def test_load_shared_library_of_upstream_libraries(tmp_path, library, error):
    path = mission(tmp_path, extra=f'  load_shared_library: "{library}"\n')
    if error is None:
        assert pAcommsHandler.from_mission(path)
    else:
        assert error_of(path) == f"{path}:9: load_shared_library: {error}"


def test_upstream_library_table():
    assert builtin_for("/opt/lib/libgoby_frontseat_basic_simulator.so.30.0") == Builtin(
        FRONTSEAT_DRIVER, "basic_simulator"
    )
    assert builtin_for("libgoby_acomms.so.25") == Builtin(MESSAGES, "")
    assert builtin_for("/x/libdccl_ccl_compat.so.31") == Builtin(DCCL_CODECS, "dccl_ccl_compat")
    assert builtin_for("libgobyexample_protobuf.so") is None
    assert builtin_for("my_messages_pb2") is None  # a Python module: not a shared library


def test_driver_type_not_implemented_lists_those_that_are():
    with pytest.raises(DriverNotFoundError) as info:
        make_driver(acomms_pb.DriverConfig(driver_type=8))  # DRIVER_IRIDIUM
    assert info.value.status == acomms_pb.ModemDriverStatus.INVALID_CONFIGURATION
    assert str(info.value) == (
        "driver_type DRIVER_IRIDIUM is not implemented in pygoby; available: DRIVER_NONE, "
        "DRIVER_WHOI_MICROMODEM, DRIVER_ABC_EXAMPLE_MODEM, DRIVER_UFIELD_SIM_DRIVER, "
        "DRIVER_STORE_SERVER, DRIVER_UDP, DRIVER_UDP_MULTICAST (or a driver_name of "
        "pygoby.acomms_drivers entry points or $PACOMMSHANDLER_PLUGINS modules)"
    )


@pytest.mark.parametrize(
    ("extra", "line", "field"),
    [
        ("  driver_cfg\n  {\n    driver_type: DRIVER_IRIDIUM\n  }\n", 11, "driver_cfg.driver_type"),
        ("  driver_type: DRIVER_IRIDIUM\n", 9, "driver_type"),  # Goby 2's top-level form
        (
            "  listen_driver_cfg { driver_type: DRIVER_UDP }\n"
            "  listen_driver_cfg { driver_type: DRIVER_IRIDIUM }\n",
            10,
            "listen_driver_cfg[1].driver_type",
        ),
    ],
)
def test_a_driver_type_not_implemented_is_located_at_its_mission_line(tmp_path, extra, line, field):
    path = mission(tmp_path, extra=extra)
    assert error_of(path).startswith(
        f"{path}:{line}: {field}: driver_type DRIVER_IRIDIUM is not implemented in pygoby; available: "
    )


def test_compiled_driver_plugins_are_named_in_the_error(monkeypatch):
    monkeypatch.setenv("PACOMMSHANDLER_PLUGINS", "/usr/lib/libmy_modem_driver.so")
    with pytest.raises(DriverNotFoundError) as info:
        make_driver(acomms_pb.DriverConfig(driver_name="my_modem"))
    assert str(info.value).endswith(
        "$PACOMMSHANDLER_PLUGINS lists compiled C++ plug-ins (/usr/lib/libmy_modem_driver.so), "
        "which pygoby cannot load: list Python modules or .py files there"
    )


def test_the_console_script_prints_one_line_and_exits_1(tmp_path):
    path = mission(tmp_path, queued="no.Such")
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    done = subprocess.run(
        [Path(sys.executable).with_name("pAcommsHandler"), path],
        capture_output=True,
        text=True,
        timeout=60,
        env=env,
    )
    assert done.returncode == 1
    assert done.stderr.splitlines() == [
        f"pAcommsHandler: fatal configuration error: {path}:6: "
        'queue_cfg.message_entry.protobuf_name: "no.Such" is not a loaded message type; the '
        "types load_proto_file and load_shared_library loaded are: pygoby.examples.SimpleStatus, "
        "pygoby.examples.Command"
    ]
