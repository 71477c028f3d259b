"""pREMUSCodec: MOOS vehicles talking to REMUS vehicles in CCL (Goby 1.1).

    pREMUSCodec mission.moos [AppName]
    pREMUSCodec --example_config

REMUS frames arrive on the `mdat_*_var` variables as Goby 1.1 ModemDataTransmission text (what
pAcommsHandler's CCL queues post on their `in_pubsub_var`) and become NODE_REPORT,
STATUS_REPORT_IN, CCL_*_IN and `<NAME>_NAV_*` (pygoby.moosacomms.remus_reports). With
`create_status`, our NAV_* become a State frame on `mdat_state_out` every 10 s (once all five
have arrived); an OUTGOING_COMMAND `MessageType=CCL_REDIRECT,...` becomes a Redirect frame on
`mdat_redirect_out`, addressed to its DestinationPlatformId. A bad frame or command is logged
with the reason and skipped. LatOrigin/LongOrigin (the datum of NAV_X/NAV_Y) are required.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from functools import partial

from pygoby.acomms import messages as acomms_pb
from pygoby.dccl import DcclError
from pygoby.errors import ConfigError
from pygoby.moos.app import GobyMOOSApp
from pygoby.moos.protocol import MOOSMessage
from pygoby.moos.translator import Technique, TranslatorError, parse_for_moos, serialize_for_moos
from pygoby.moosacomms.remus_reports import RemusReports
from pygoby.protobuf.pygoby.apps.premuscodec_config_pb2 import pREMUSCodecConfig
from pygoby.util.geodesy import UTMGeodesy
from pygoby.util.modem_id import ModemIdLookup, atoi

STATUS_INTERVAL = 10.0  # seconds between our State frames (Goby 1.1's fixed interval)
NAV_VARS = ("NAV_X", "NAV_Y", "NAV_DEPTH", "NAV_SPEED", "NAV_HEADING")
COMMAND_VAR = "OUTGOING_COMMAND"
TEXT = Technique.TECHNIQUE_PROTOBUF_TEXT_FORMAT  # Goby 1.1's ModemDataTransmission on MOOS


class pREMUSCodec(GobyMOOSApp):  # noqa: N801 - the program's name
    config_class = pREMUSCodecConfig
    cfg: pREMUSCodecConfig
    default_name = "pREMUSCodec"

    def __init__(self, cfg: pREMUSCodecConfig, **kwargs) -> None:
        super().__init__(cfg, **kwargs)
        if not (self.common.HasField("lat_origin") and self.common.HasField("lon_origin")):
            raise ConfigError(
                "LatOrigin and LongOrigin are required (REMUS frames carry latitude "
                "and longitude, MOOS vehicles local x/y)",
                field="common.lat_origin",
            )
        path = cfg.modem_id_lookup_path
        lookup = ModemIdLookup.from_file(self.find_file(path)) if path else ModemIdLookup()
        self.reports = RemusReports(
            UTMGeodesy(self.common.lat_origin, self.common.lon_origin), lookup
        )
        self._last_status = -math.inf
        incoming = {
            cfg.mdat_state_var: "state",
            cfg.mdat_ranger_var: "ranger",
            cfg.mdat_redirect_var: "redirect",
            cfg.mdat_alert_var: "alert",
            cfg.mdat_alert2_var: "alert2",
        }
        for var, kind in incoming.items():
            self.subscribe(var, partial(self._on_frame, kind))
        # Goby 1.1 registers for the outgoing variables too (they only update dynamic_vars)
        for var in (
            cfg.mdat_state_out,
            cfg.mdat_ranger_out,
            cfg.mdat_redirect_out,
            cfg.mdat_alert_out,
            cfg.mdat_alert2_out,
        ):
            if var not in incoming:
                self.subscribe(var)
        # state, not events: the newest values count even when posted before we started
        for var in ("MODEM_ID", *NAV_VARS):
            self.subscribe(var)
        self.subscribe(COMMAND_VAR, self._on_command)

    def on_start(self) -> None:
        if not self.cfg.modem_id_lookup_path:
            self.log.warning(
                "no modem_id_lookup_path: vehicles are named by their modem id "
                "(set it in ProcessConfig or as a MOOS global)"
            )

    @property
    def modem_id(self) -> int:
        """Ours, from MODEM_ID (a double from pAcommsHandler, or a string); 0 until it arrives."""
        msg = self.dynamic_vars.get("MODEM_ID")
        if msg is None:
            return 0
        if msg.is_double:
            return int(msg.dval) if math.isfinite(msg.dval) else 0
        value = msg.value
        return atoi(value.decode("latin-1") if isinstance(value, bytes) else str(value))

    # ------------------------------------------------------------------ frames in
    def _on_frame(self, kind: str, msg: MOOSMessage) -> None:
        if msg.src == self.name:
            return  # our own outgoing frame on a variable that is also an incoming one
        if msg.is_double:
            self.log.warning(
                "%s: a double (%g), not a ModemDataTransmission; skipped", msg.key, msg.dval
            )
            return
        transmission = acomms_pb.V1ModemDataTransmission()
        try:
            parse_for_moos(msg.value, transmission, TEXT)
        except TranslatorError as err:
            self.log.warning("%s: not a ModemDataTransmission (%s); skipped", msg.key, err)
            return
        data = transmission.data
        try:
            posts = self.reports.incoming(
                kind, data, transmission.base.src, transmission.base.dest, self.clock.now()
            )
        except DcclError as err:
            self.log.warning(
                "%s: bad CCL frame from modem %d (%s): %s; skipped",
                msg.key,
                transmission.base.src,
                err,
                data.hex(),
            )
            return
        self.log.info("%s: %s frame from modem %d", msg.key, kind, transmission.base.src)
        for var, value in posts:
            self.publish(var, value)

    # ------------------------------------------------------------------ frames out
    def _send(self, var: str, frame: bytes, dest: int, time: float | None = None) -> None:
        transmission = acomms_pb.V1ModemDataTransmission(data=frame)
        transmission.base.src, transmission.base.dest = self.modem_id, dest
        text = serialize_for_moos(transmission, TEXT)
        self.log.info("publishing to %s: %s", var, text)
        self.publish(var, text, time=time)

    def _nav(self) -> list[float] | None:
        """NAV_X, NAV_Y, NAV_DEPTH, NAV_SPEED, NAV_HEADING once all are doubles."""
        values = [self.dynamic_vars.get(var) for var in NAV_VARS]
        if any(msg is None or not msg.is_double for msg in values):
            return None
        return [msg.dval for msg in values]  # type: ignore[union-attr]

    def loop(self) -> None:
        now = self.clock.now()
        if not self.cfg.create_status or now - self._last_status < STATUS_INTERVAL:
            return
        nav = self._nav()
        if nav is None:
            return
        self._last_status = now
        x, y, depth, speed, heading = nav
        try:
            frame = self.reports.state_frame(x, y, depth, speed, heading, now)
        except DcclError as err:
            self.log.warning("cannot encode our State from NAV_*: %s", err)
            return
        self._send(
            self.cfg.mdat_state_out, frame, dest=0, time=now
        )  # stamped with the frame's time

    def _on_command(self, msg: MOOSMessage) -> None:
        if msg.is_double:
            return
        text = msg.value.decode("latin-1") if isinstance(msg.value, bytes) else str(msg.value)
        try:
            command = self.reports.redirect_command(text)
        except DcclError as err:
            self.log.warning("%s: %s; not sent", COMMAND_VAR, err)
            return
        if command is not None:
            dest, frame = command
            self._send(self.cfg.mdat_redirect_out, frame, dest)


def main(argv: Sequence[str] | None = None) -> int:
    return pREMUSCodec.main(argv)


if __name__ == "__main__":
    raise SystemExit(main())
