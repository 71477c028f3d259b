"""iModemSim: Goby 1.1's WHOI Micro-Modem simulator process (moos-ivp-local), as pygoby's
Micro-Modem emulator on the serial line the mission names.

    iModemSim mission.moos [AppName]

ProcessConfig:
  Port = /tmp/ttyLOOPA1     serial device of the emulated modem; the host (pAcommsHandler)
                            opens its partner, /tmp/ttyLOOPA2. When the pair does not exist (or
                            its links are stale) iModemSim makes it, so pAntler alone is enough.
  Speed = 19200             baud of the modem's serial line: the time the host's sentences take
                            to reach the modem (a pseudo-terminal itself has no speed)
  IPPort = 49234            UDP port shared by the emulators of a mission
  BroadcastAddr = 127.0.0.1 loopback: every emulator on this host hears every other one (UDP
                            multicast on the loopback); another address: UDP broadcast to it
  InputLocType = constant_local | constant_global | moos_local | moos_global
  ConstantPosX/ConstantPosY/ConstantDepth (local, metres from the mission's LatOrigin/
  LongOrigin) or ConstantLat/ConstantLon/ConstantDepth
                            the modem's position: every packet carries its sender's, and the
                            receiving emulator hears it through netsim's acoustic model at that
                            range (travel time, received level, frame errors, out of reach)
  ChannelModel = range      range: as above; perfect: every packet heard at once, no loss,
                            whatever the positions (pygoby extension)
  ModemID = 1               NVRAM SRC before the host configures it (pygoby extension)
"""

from __future__ import annotations

import dataclasses
import functools
import ipaddress
import logging
from collections.abc import Sequence
from typing import NoReturn

from pygoby.acomms.mmsim.model import MicroModemModel
from pygoby.acomms.mmsim.multicast_channel import BroadcastChannel, MulticastChannel
from pygoby.acomms.mmsim.server import MMSimServer
from pygoby.acomms.mmsim.timing import DEFAULT_TIMING
from pygoby.moos.classic_app import ClassicMOOSApp
from pygoby.moos.protocol import MOOSMessage
from pygoby.netsim.sim.range_link import RangeLink
from pygoby.protobuf.pygoby.moos.classic_app_pb2 import ClassicMOOSAppConfig
from pygoby.util.geodesy import UTMGeodesy
from pygoby.util.pty import PtyError, PtyPair, is_live, partner_of

log = logging.getLogger(__name__)

MULTICAST_GROUP = "239.255.42.99"
LOCATION_TYPES = {
    "constant_local": ("ConstantPosX", "ConstantPosY", "ConstantDepth"),
    "constant_global": ("ConstantLat", "ConstantLon", "ConstantDepth"),
    "moos_local": ("NAV_X", "NAV_Y", "NAV_DEPTH"),
    "moos_global": ("NAV_LAT", "NAV_LONG", "NAV_DEPTH"),
}
KNOWN_NAMES = (
    "Port",
    "Speed",
    "IPPort",
    "BroadcastAddr",
    "InputLocType",
    "ConstantPosX",
    "ConstantPosY",
    "ConstantDepth",
    "ConstantLat",
    "ConstantLon",
    "ChannelModel",
    "ModemID",
)
CHANNEL_MODELS = ("range", "perfect")
KNOWN = {name.lower() for name in KNOWN_NAMES}


class iModemSim(ClassicMOOSApp):  # noqa: N801 - the program's name
    default_name = "iModemSim"
    example_lines = (
        "Port = /tmp/ttyLOOPA1       // the emulated modem; the host opens /tmp/ttyLOOPA2",
        "Speed = 19200",
        "IPPort = 49234              // UDP port of the mission's emulators",
        "BroadcastAddr = 127.0.0.1   // loopback: every emulator of this host hears the others",
        f"InputLocType = constant_local   // {' | '.join(LOCATION_TYPES)}",
        "ConstantPosX = 0",
        "ConstantPosY = 0",
        "ConstantDepth = 0",
        "ChannelModel = range        // range (netsim's model at the positions) | perfect",
        "ModemID = 1                 // NVRAM SRC before the host configures it (pygoby)",
    )

    def __init__(self, cfg: ClassicMOOSAppConfig, **kwargs) -> None:
        super().__init__(cfg, **kwargs)
        self.settings = {s.name.lower(): s for s in self.params}  # the last of a name wins
        for setting in self.params:
            if setting.name.lower() not in KNOWN:
                self.log.warning("unknown iModemSim parameter %r ignored", setting.name)
        self.port_path = self._text("port", "")
        if not self.port_path:
            self._error("port", "the serial device is required")
        speed = int(self._number("speed", 19200))
        if speed <= 0:
            self._error("speed", f"{speed} is not a baud rate")
        udp_port = int(self._number("ipport", 49234))
        if not 0 < udp_port < 65536:
            self._error("ipport", f"{udp_port} is not a UDP port")
        address = self._text("broadcastaddr", "127.0.0.1")
        try:
            loopback = ipaddress.ip_address(address).is_loopback
        except ValueError:
            self._error("broadcastaddr", f"{address!r} is not an IPv4 address")
        model = self._text("channelmodel", "range").lower()
        if model not in CHANNEL_MODELS:
            self._error("channelmodel", f"{model!r} is not one of {', '.join(CHANNEL_MODELS)}")
        location = self._text("inputloctype", "constant_local").lower()
        if location not in LOCATION_TYPES:
            self._error("inputloctype", f"{location!r} is not one of {', '.join(LOCATION_TYPES)}")
        self.position = [0.0, 0.0, 0.0]
        if location.startswith("constant"):
            names = LOCATION_TYPES[location]
            self.position = [self._number(n.lower(), 0.0) for n in names]
        else:
            for index, var in enumerate(LOCATION_TYPES[location]):
                self.subscribe(var, functools.partial(self._on_position, index))
        self.is_local = location.endswith("local")
        self.geodesy = UTMGeodesy(self.cfg.common.lat_origin, self.cfg.common.lon_origin)
        modem_id = int(self._number("modemid", 1))
        # (the channel's deliveries on the app's clock, which MOOSTimeWarp speeds up)
        link = RangeLink(seed=modem_id) if model == "range" else None
        channel_type = MulticastChannel if loopback else BroadcastChannel
        self.channel = channel_type(
            MULTICAST_GROUP if loopback else address,
            udp_port,
            self.clock,
            position=self.geo_position,
            link=link,
        )
        self.pair = self._make_pair()
        self.model = MicroModemModel(
            modem_id,
            self.clock,
            self.channel,
            name=f"{self.name}:{self.port_path}",
            timing=dataclasses.replace(DEFAULT_TIMING, baud=speed),
        )
        self.server = MMSimServer(self.model, self.channel, port=None, serial_path=self.port_path)

    def _error(self, key: str, reason: str) -> NoReturn:
        """A ConfigError at the line of the setting `key` (lower case), or naming it if unset."""
        setting = self.settings.get(key)
        name = next(n for n in KNOWN_NAMES if n.lower() == key)
        raise self.setting_error(reason, setting if setting is not None else name)

    def _text(self, key: str, default: str) -> str:
        setting = self.settings.get(key)
        return default if setting is None else setting.value

    def _number(self, key: str, default: float) -> float:
        setting = self.settings.get(key)
        if setting is None:
            return default
        try:
            return float(setting.value)
        except ValueError:
            self._error(key, f"must be a number, not {setting.value!r}")

    def _make_pair(self) -> PtyPair | None:
        """The Goby 1.1 loopback pair, made here unless a running process (pygoby loopbacks,
        socat) provides it."""
        if is_live(self.port_path):
            self.log.info("using %s (made by another process)", self.port_path)
            return None
        partner = partner_of(self.port_path)
        if partner is None:
            self._error(
                "port",
                f"{self.port_path} does not exist, and only loopback names ending "
                "in 1 or 2 (/tmp/ttyLOOPA1 <-> /tmp/ttyLOOPA2) can be made here; run "
                "`pygoby loopbacks` or give a real serial device",
            )
        try:
            pair = PtyPair(self.port_path, partner).open()
        except (PtyError, OSError) as err:
            self._error("port", f"cannot make the loopback {self.port_path} <-> {partner}: {err}")
        self.log.info(
            "made the loopback %s <-> %s (the host opens %s)", self.port_path, partner, partner
        )
        return pair

    def geo_position(self) -> list[float]:
        """[lat, lon, depth] of the modem (local x/y from the mission's origin)."""
        first, second, depth = self.position
        if self.is_local:
            lat, lon = self.geodesy.to_geo(first, second)
            return [lat, lon, depth]
        return [first, second, depth]

    def _on_position(self, index: int, msg: MOOSMessage) -> None:
        if isinstance(msg.value, float):
            self.position[index] = msg.value

    async def start(self, connect_timeout: float | None = None) -> None:
        if self.pair is not None:
            self.pair.attach()
        self.channel.open()
        await self.server.start()
        await super().start(connect_timeout)
        self.log.info(
            "Micro-Modem emulator on %s, channel %s:%d, position %s",
            self.port_path,
            self.channel.group,
            self.channel.port,
            self.position,
        )

    async def stop(self) -> None:
        """The serial line and its links go first: they must not outlive a quick kill."""
        try:
            await self.server.close()
            self.channel.close()
            if self.pair is not None:
                self.pair.close()
        finally:
            await super().stop()


def main(argv: Sequence[str] | None = None) -> int:
    return iModemSim.main(argv)


if __name__ == "__main__":
    raise SystemExit(main())
