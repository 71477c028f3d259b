"""The error family: every exception class pygoby defines is a PygobyError, sits under its
package's root, is exported by its package, and configuration errors say file:line: field."""

from __future__ import annotations

import importlib
import inspect
import pkgutil
from collections import Counter

import pytest

import pygoby
from pygoby.acomms import AcommsError
from pygoby.dccl import DcclDecodeError, DcclEncodeError, DcclError
from pygoby.errors import ConfigError, PygobyError
from pygoby.frontseat import FrontSeatError
from pygoby.moos import MoosError
from pygoby.moos.translator import TranslatorConfigError
from pygoby.netsim import NetsimError, ScenarioError
from pygoby.protobuf import ProtoError
from pygoby.topside import TopsideError
from pygoby.util import LinkClosedError, MissingExtraError, NMEAError, PluginError, PtyError

# the root(s) every error class of a package derives from
PACKAGE_ROOTS: dict[str, tuple[type[BaseException], ...]] = {
    "pygoby.acomms": (AcommsError,),
    "pygoby.dccl": (DcclError,),
    "pygoby.frontseat": (FrontSeatError,),
    "pygoby.moos": (MoosError,),
    "pygoby.netsim": (NetsimError,),
    "pygoby.protobuf": (ProtoError,),
    "pygoby.topside": (TopsideError,),
    # one root per kind
    "pygoby.util": (NMEAError, LinkClosedError, PtyError, PluginError, MissingExtraError),
    "pygoby.errors": (PygobyError,),
}


def _all_error_classes() -> list[type[BaseException]]:
    found = []
    for info in pkgutil.walk_packages(pygoby.__path__, "pygoby."):
        module = importlib.import_module(info.name)
        for obj in vars(module).values():
            if (
                inspect.isclass(obj)
                and issubclass(obj, BaseException)
                and obj.__module__ == module.__name__
            ):
                found.append(obj)
    return found


ERRORS = _all_error_classes()


def _package_of(cls: type) -> str:
    return next(
        p for p in PACKAGE_ROOTS if cls.__module__ == p or cls.__module__.startswith(p + ".")
    )


def test_the_family_is_found():
    assert len(ERRORS) >= 36  # (33 classes before the family had roots, plus the roots)


@pytest.mark.parametrize("cls", ERRORS, ids=lambda c: f"{c.__module__}.{c.__name__}")
def test_every_error_is_a_pygoby_error_under_its_package_root(cls):
    assert issubclass(cls, PygobyError)
    roots = PACKAGE_ROOTS[_package_of(cls)]
    assert issubclass(cls, roots), f"{cls.__name__} is not under {[r.__name__ for r in roots]}"


@pytest.mark.parametrize("cls", ERRORS, ids=lambda c: f"{c.__module__}.{c.__name__}")
def test_every_error_is_exported_by_its_package(cls):
    package = importlib.import_module(cls.__module__.rpartition(".")[0])
    assert getattr(package, cls.__name__, None) is cls
    assert cls.__name__ in package.__all__


def test_names_are_unique_and_say_error():
    names = Counter(cls.__name__ for cls in ERRORS)
    assert [name for name, count in names.items() if count > 1] == []
    assert [name for name in names if not name.endswith("Error")] == []
    assert [cls for cls in ERRORS if cls.__name__ == "ConfigError"] == [ConfigError]


def test_callers_can_catch_the_standard_kinds():
    assert issubclass(ConfigError, ValueError)
    assert issubclass(DcclEncodeError, ValueError) and issubclass(DcclDecodeError, ValueError)
    assert issubclass(NMEAError, ValueError)
    assert issubclass(LinkClosedError, ConnectionError)
    # a package's configuration errors are caught both as the package's and as ConfigError
    for cls in (ScenarioError, TranslatorConfigError):
        assert issubclass(cls, ConfigError) and issubclass(cls, PygobyError)


@pytest.mark.parametrize(
    ("where", "text"),
    [
        ({}, "bad value"),
        ({"file": "a.moos"}, "a.moos: bad value"),
        ({"file": "a.moos", "line": 12}, "a.moos:12: bad value"),
        ({"line": 12}, "line 12: bad value"),
        ({"field": "modem_id"}, "modem_id: bad value"),
        ({"file": "a.moos", "line": 12, "field": "modem_id"}, "a.moos:12: modem_id: bad value"),
    ],
)
def test_config_error_says_file_line_and_field(where, text):
    err = ConfigError("bad value", **where)
    assert str(err) == text
    assert (err.reason, err.file, err.line, err.field) == (
        "bad value",
        where.get("file"),
        where.get("line"),
        where.get("field"),
    )


def test_located_fills_only_what_is_missing():
    err = ConfigError("bad value", field="modem_id")
    assert err.located(file="a.moos", line=3) is err
    assert str(err) == "a.moos:3: modem_id: bad value"
    assert str(err.located(file="b.moos", line=9)) == "a.moos:3: modem_id: bad value"
    assert str(ScenarioError("no nodes").located(file="s.pb.cfg")) == "s.pb.cfg: no nodes"


def test_a_text_format_parse_error_names_the_line_of_the_file():
    from pygoby.netsim.manager.config import config_class
    from pygoby.protobuf.textconfig import merge_config_text

    with pytest.raises(ConfigError) as info:
        merge_config_text(
            "manager_tcp_port: 1\n  nope: 2\n", config_class()(), file="m.cfg", first_line=10
        )
    err = info.value
    assert (err.file, err.line, err.field) == ("m.cfg", 11, "nope")
    assert str(err).startswith('m.cfg:11: nope: Message type "')
    assert 'no field named "nope"' in str(err)


def test_configuration_errors_from_files_carry_file_and_line(tmp_path):
    from pygoby.moos.appconfig import read_configuration
    from pygoby.moos.moosfile import MissionFile
    from pygoby.netsim.sim.scenario import load_scenario
    from pygoby.protobuf import builtin_class

    scenario = tmp_path / "run.pb.cfg"
    scenario.write_text("duration: 10\nnode { modem_id: 1 }\nspeed: fast fast\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(scenario)
    assert (info.value.file, info.value.line) == (str(scenario), 3)
    assert str(info.value).startswith(f"{scenario}:3: speed: Expected string")

    mission = tmp_path / "m.moos"
    mission.write_text("ProcessConfig = pApp\n{\n  app_tick: soon\n}\n")
    common = builtin_class(
        "goby/moos/protobuf/goby_moos_app.proto", "goby.moos.protobuf.GobyMOOSAppConfig"
    )
    with pytest.raises(ConfigError) as info:
        read_configuration(common, MissionFile.read(mission), "pApp")
    assert (info.value.file, info.value.line) == (str(mission), 3)
