"""netsim_manager configuration: protobuf TextFormat, loaded and checked like upstream.

Upstream configuration files contain Goby3 middleware blocks (``app { ... }``,
``interprocess { ... }``, the serial settings of ``gps_out``) that pygoby does not use. Their
contents are accepted and ignored; everywhere else an unknown field name is an error, so typos in
the parts pygoby uses are still caught.
"""

from __future__ import annotations

import os
from functools import cache

from google.protobuf import text_format

from pygoby.errors import ConfigError
from pygoby.netsim.channel.settings import environment_channel_configs
from pygoby.protobuf import initialization_errors
from pygoby.protobuf.netsim.messages.manager_config_pb2 import NetSimManagerConfig
from pygoby.protobuf.textconfig import check_config_values, merge_config_text, read_config_file

# Message types whose contents stand for upstream blocks with more fields than pygoby declares.
_OPEN_BLOCKS = frozenset({"netsim.protobuf.UnusedGoby3Block", "netsim.protobuf.SerialPortConfig"})

EXAMPLE_CONFIG = """\
# netsim_manager configuration (protobuf TextFormat; the same file upstream netsim reads).
# One sim_env_pair per simulated vehicle: its modem TCP port, the only IP address allowed to
# report its position, and the environment whose bounds apply.
sim_env_pair { modem_tcp_port: 62000 endpoint_ip_address: "127.0.0.1" environment_id: 0 }
sim_env_pair { modem_tcp_port: 62001 endpoint_ip_address: "127.0.0.1" environment_id: 0 }
# Region of each environment (inclusive; depth_min defaults to 0, so negative depths fail).
env_bounds { environment_id: 0 lat_min: 41.5 lon_min: -71.0 lat_max: 42.5 lon_max: -69.5
             depth_min: 0 depth_max: 200 }
manager_tcp_port: 61999          # default 61999
# pygoby-only settings:
listen_address: "127.0.0.1"      # IPv4 address to listen on ("0.0.0.0": every interface)
reject_nonfinite_position: true  # NaN/inf lat, lon or depth -> OUT_OF_DEFINED_REGION
max_line_length: 1048576         # longer NETSIM lines are discarded
# Channel model of environment 0 (every field optional; defaults shown or described).
environment_channel {
  environment_id: 0
  channel {
    sound_speed: 1500              # or water { temperature: 10 salinity: 35 } for Mackenzie;
                                   # water { sound_speed_formula: MEDWIN_1975 | UNESCO_1983 |
                                   #   TEOS_10  latitude: 41.5  longitude: -70.7 } for the others
    absorption: THORP              # or THORP_COA, or FRANCOIS_GARRISON (uses water { ... })
    source_level: 185  spreading: 1.5
    shipping: 0.5  wind_speed: 5   # Stojanovic noise; or a fixed noise_level: 60
    carrier_hz: 25000  bandwidth_hz: 5000
    # frame-error model per rate (built-in defaults: ros_acomms tables)
    rate_model { rate: 5 logistic { snr50_db: 4.22 width_db: 0.12 } }
    rate_model { rate: 0 table { snr_db: [-9, -8, -7] frame_error: [1, 0.5, 0] } }
    data_duration: 3.25  mini_duration: 1.0  ping_duration: 0.5
    half_duplex: true  receiver_lock: true  decode_latency: 0  position_staleness: 60
    seed: 1
  }
}
"""


@cache
def config_class() -> type[NetSimManagerConfig]:
    return NetSimManagerConfig


class _Parser(text_format._Parser):
    """TextFormat parser that skips unknown fields only inside the open upstream blocks."""

    def _MergeField(self, tokenizer, message):  # noqa: N802 - overrides protobuf's method
        self.allow_unknown_field = message.DESCRIPTOR.full_name in _OPEN_BLOCKS
        super()._MergeField(tokenizer, message)  # type: ignore[misc]  # (protobuf's private parser)


def parse_config(text: str, file: str | os.PathLike[str] | None = None) -> NetSimManagerConfig:
    """Parse and validate a TextFormat configuration; raises ConfigError (with `file`:line)."""
    config = config_class()()
    merge_config_text(text, config, file=file, parser=_Parser())
    check_config_values(config, text, file=file)
    try:
        validate_config(config)
    except ConfigError as err:
        raise err.located(file=file) from None
    return config


def load_config(path: str | os.PathLike[str]) -> NetSimManagerConfig:
    """The configuration file at `path`, whatever its bytes: ConfigError for every problem."""
    return parse_config(read_config_file(path), path)


def validate_config(config: NetSimManagerConfig) -> None:
    """The start-up checks of upstream, in its order; the first failure raises ConfigError."""
    if not config.IsInitialized():
        missing = ", ".join(initialization_errors(config))
        raise ConfigError(f"configuration is missing required fields: {missing}")
    environments: set[int] = set()
    for bounds in config.env_bounds:
        if bounds.environment_id in environments:
            raise ConfigError(f"duplicate env_bounds.environment_id {bounds.environment_id}")
        environments.add(bounds.environment_id)
    ports: set[int] = set()
    for pair in config.sim_env_pair:
        if pair.modem_tcp_port in ports:
            raise ConfigError(f"duplicate sim_env_pair.modem_tcp_port {pair.modem_tcp_port}")
        ports.add(pair.modem_tcp_port)
        if pair.environment_id not in environments:
            raise ConfigError(
                f"no env_bounds for environment {pair.environment_id} "
                f"(used by modem_tcp_port {pair.modem_tcp_port})"
            )
    try:
        environment_channel_configs(config)
    except ValueError as exc:
        raise ConfigError(f"invalid channel model: {exc}") from None
