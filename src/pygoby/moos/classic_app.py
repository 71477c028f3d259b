"""Classic MOOS applications (MOOS-IvP style `name = value` configuration) on pygoby's app base.

    class uExample(ClassicMOOSApp):
        default_name = "uExample"
        keep_quotes = False            # True: read values with their double quotes
        example_lines = ("Param = value   // what it does",)   # --example_config
        def __init__(self, cfg, **kwargs):
            super().__init__(cfg, **kwargs)
            self.params                # [Setting(name, value, line), ...] of the block
            raise self.setting_error("must be a number", setting)   # file:line: name: reason

The block's AppTick and CommsTick and the mission's globals (ServerHost, ServerPort, Community,
MOOSTimeWarp, LatOrigin, ...) fill the `common` settings Goby apps share, so the app runs with
the same MOOS client, tick loop, logging and command line (`uExample mission.moos [name]`).
No log file is written (classic MOOS apps write none).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, ClassVar

from google.protobuf.message import Message

from pygoby.errors import ConfigError
from pygoby.moos.app import GobyMOOSApp
from pygoby.moos.appconfig import apply_moos_globals
from pygoby.moos.moosfile import MissionFile, Setting, parse_number
from pygoby.protobuf.pygoby.moos.classic_app_pb2 import ClassicMOOSAppConfig


class ClassicMOOSApp(GobyMOOSApp):
    config_class = ClassicMOOSAppConfig
    cfg: ClassicMOOSAppConfig
    keep_quotes: ClassVar[bool] = False
    # the block's own `name = value` lines, as `--example_config` prints them
    example_lines: ClassVar[tuple[str, ...]] = ()

    @classmethod
    def example_config(cls, name: str | None = None) -> str:
        """The ProcessConfig block as this app reads it (MOOS-IvP style lines, not TextFormat)."""
        lines = ["AppTick = 4", "CommsTick = 4", *cls.example_lines]
        body = "".join(f"  {line}\n" for line in lines)
        return f"ProcessConfig = {name or cls.default_name or cls.__name__}\n{{\n{body}}}\n"

    @classmethod
    def read_config(
        cls, mission: MissionFile | None, name: str, overrides: Sequence[tuple[str, str]] = ()
    ) -> Message:
        if overrides:
            raise ConfigError(
                "takes no --option overrides: set them in its ProcessConfig block", field=name
            )
        cfg: Any = cls.load_config_class()()  # (a ClassicMOOSAppConfig or a subclass's)
        cfg.common.log = False
        if mission is None:
            return cfg
        apply_moos_globals(cfg, mission)
        for setting in mission.process_config(name) or []:
            field = {"apptick": "app_tick", "commstick": "comm_tick"}.get(setting.name.lower())
            if field is None:
                continue
            number = parse_number(setting.value)
            if number is None or number <= 0:
                raise ConfigError(
                    f"must be a positive number, not {setting.value!r}",
                    file=mission.path,
                    line=setting.line,
                    field=setting.name,
                )
            setattr(cfg.common, field, max(1, math.ceil(number)))
        return cfg

    def __init__(self, cfg: ClassicMOOSAppConfig, **kwargs) -> None:
        super().__init__(cfg, **kwargs)
        block = self.mission.process_config(self.name, self.keep_quotes) if self.mission else None
        if block is None:
            self.log.warning("no ProcessConfig = %s block; running with the defaults", self.name)
        self.params: list[Setting] = [
            s for s in (block or []) if s.name.lower() not in ("apptick", "commstick")
        ]

    @property
    def mission_path(self) -> str | None:
        """The mission file the settings come from (for errors)."""
        return str(self.mission.path) if self.mission and self.mission.path else None

    def setting_error(self, reason: str, setting: Setting | str) -> ConfigError:
        """A ConfigError about one setting of the block (a Setting: at its line; a name: a
        setting that is missing), as `mission.moos:LINE: Name: reason`."""
        if isinstance(setting, str):
            return ConfigError(reason, file=self.mission_path, field=setting)
        return ConfigError(reason, file=self.mission_path, line=setting.line, field=setting.name)
