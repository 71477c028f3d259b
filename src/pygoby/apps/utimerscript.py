"""uTimerScript: MOOS-IvP's timer script app (the subset missions use; see
pygoby.moos.timerscript), so that missions run without MOOS-IvP installed.

    uTimerScript mission.moos [AppName]
"""

from __future__ import annotations

from collections.abc import Sequence

from pygoby.moos.classic_app import ClassicMOOSApp
from pygoby.moos.protocol import MOOSMessage
from pygoby.moos.timerscript import TimerScript
from pygoby.protobuf.pygoby.moos.classic_app_pb2 import ClassicMOOSAppConfig

STATUS_PERIOD = 5.0


class uTimerScript(ClassicMOOSApp):  # noqa: N801 - the program's name
    default_name = "uTimerScript"
    keep_quotes = True  # MOOS-IvP's uTimerScript reads values with their quotes
    example_lines = (
        "EVENT = var=OUT_TEST, val=3.5, time=10           // a double 10 s after the start",
        'EVENT = var=OUT_TEXT, val="data: \\"x\\"", time=20:30  // a string (\\" is "), at random in [20, 30] s',
        "RESET_TIME = end        // start again after the last event (all-posted, none, SECONDS)",
        "RESET_MAX = nolimit     // or a count of resets",
        "PAUSED = false          // UTS_PAUSE = true/false/toggle pauses it",
        "CONDITION = DEPLOY = true   // post only while this holds (repeatable)",
        "UPON_AWAKE = n/a        // reset or restart when a CONDITION turns true again",
    )

    def __init__(self, cfg: ClassicMOOSAppConfig, **kwargs) -> None:
        super().__init__(cfg, **kwargs)
        self.script = TimerScript(self.params, file=self.mission_path)
        for warning in self.script.warnings:
            self.log.warning("%s", warning)
        for var in self.script.subscriptions():
            self.subscribe(var, self._on_mail)
        self._last_script_status = -1e300

    def _on_mail(self, msg: MOOSMessage) -> None:
        value = msg.value.decode("latin-1") if isinstance(msg.value, bytes) else msg.value
        self.script.on_mail(msg.key, value)

    def loop(self) -> None:
        now = self.clock.now()
        for post in self.script.tick(now):
            self.log.info("posting %s = %r", post.var, post.value)
            self.publish(post.var, post.value)
        if now - self._last_script_status >= STATUS_PERIOD:
            self._last_script_status = now
            self.publish(self.script.var_status, self.script.status())
        if self.script.quit:
            self.request_stop()


def main(argv: Sequence[str] | None = None) -> int:
    return uTimerScript.main(argv)


if __name__ == "__main__":
    raise SystemExit(main())
