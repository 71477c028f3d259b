"""A small Goby MOOS app used by the tests: echoes NAV_X x gain to `out_var`, counts ticks."""

from __future__ import annotations

import sys
from pathlib import Path

from pygoby.moos.app import GobyMOOSApp
from pygoby.protobuf import default_loader

PROTO = Path(__file__).resolve().parent / "data" / "test_app_config.proto"


def config_class():
    loader = default_loader()
    loader.load_file(PROTO)
    return loader.message_class("pygoby.test.TestAppConfig")


class pTestApp(GobyMOOSApp):
    config_class = config_class()
    default_name = "pTestApp"

    def __init__(self, cfg, **kwargs):
        super().__init__(cfg, **kwargs)
        self.seen = []
        self.pattern_seen = []
        self.ticks = 0
        self.timer_fired = 0
        self.subscribe("NAV_X", self.on_nav_x)
        self.subscribe_pattern("PAT_*", "*", self.pattern_seen.append)
        self.register_timer(0.2, self.on_timer)

    def on_nav_x(self, msg):
        self.seen.append(msg.value)
        self.publish(self.cfg.out_var, msg.value * self.cfg.gain)

    def on_timer(self):
        self.timer_fired += 1

    def loop(self):
        self.ticks += 1


if __name__ == "__main__":
    sys.exit(pTestApp.main())
