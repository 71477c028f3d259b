"""A `ChannelConfig` (and seed) from the protobuf `netsim.protobuf.ChannelModelConfig`, which
lives per environment in the manager configuration (``environment_channel``, pygoby-only)."""

from __future__ import annotations

import functools
from collections.abc import Callable

from pygoby.netsim.channel.absorption import francois_garrison, thorp, thorp_coa
from pygoby.netsim.channel.frame_errors import (
    DEFAULT_RATE_MODELS,
    FrameErrorModel,
    LogisticModel,
    ProtocolModel,
    RateErrorModels,
    TableModel,
    ThresholdModel,
)
from pygoby.netsim.channel.model import Band, ChannelConfig, PacketKind
from pygoby.netsim.channel.propagation import BellhopLoss, propagation_model
from pygoby.netsim.channel.soundspeed import SoundSpeedProfile, water_profile
from pygoby.protobuf.netsim.messages.manager_config_pb2 import (
    ChannelModelConfig,
    NetSimManagerConfig,
)
from pygoby.protobuf.pygoby.netsim.scenario_pb2 import ChannelSettings

# the scenario's channel block and the manager's channel model share these fields
ChannelSettingsLike = ChannelSettings | ChannelModelConfig


def channel_settings_class() -> type[ChannelModelConfig]:
    return ChannelModelConfig


def _rate_model(entry: ChannelModelConfig.RateErrorModel) -> FrameErrorModel:
    kind = entry.WhichOneof("model")
    if kind == "table":
        try:
            return TableModel(tuple(entry.table.snr_db), tuple(entry.table.frame_error))
        except ValueError as exc:
            raise ValueError(f"rate {entry.rate}: {exc}") from None
    if kind == "logistic":
        return LogisticModel(entry.logistic.snr50_db, entry.logistic.width_db)
    if kind == "threshold_db":
        return ThresholdModel(entry.threshold_db)
    raise ValueError(f"rate_model for rate {entry.rate} has no model")


def sound_speed_of(settings: ChannelSettingsLike) -> float | SoundSpeedProfile:
    """The sound speed of channel settings with `sound_speed` and `water` fields (an
    environment's ChannelModelConfig, a scenario's ChannelSettings)."""
    if settings.HasField("water"):
        w = settings.water
        formula = w.SoundSpeedFormula.Name(w.sound_speed_formula)
        return water_profile(formula, w.temperature, w.salinity, w.latitude, w.longitude)
    return settings.sound_speed


def absorption_of(settings: ChannelSettingsLike) -> Callable[[float], float]:
    """The absorption formula (f kHz -> dB/km) of settings with `absorption` and `water`."""
    name = ChannelModelConfig.Absorption.Name(settings.absorption)
    if name == "FRANCOIS_GARRISON":
        w = settings.water  # defaults apply when unset
        return functools.partial(
            francois_garrison, T=w.temperature, S=w.salinity, D=w.absorption_depth, pH=w.ph
        )
    return thorp_coa if name == "THORP_COA" else thorp


def propagation_of(settings: ChannelSettingsLike, sound_speed) -> BellhopLoss | None:
    """The propagation model of settings with `propagation` and `spreading` fields."""
    if not settings.HasField("propagation"):
        return None
    return propagation_model(settings.propagation, sound_speed, settings.spreading)


def protocol_model_of(settings: ChannelSettingsLike) -> ProtocolModel | None:
    """The range-based protocol model of settings with a `protocol_model` field, if set."""
    if not settings.HasField("protocol_model"):
        return None
    p = settings.protocol_model
    return ProtocolModel(
        p.communication_range,
        p.detection_range,
        p.interference_range,
        p.p_detection,
        p.p_decoding,
    )


def channel_config_from_proto(settings: ChannelModelConfig) -> tuple[ChannelConfig, int]:
    """(ChannelConfig, seed) for a ChannelModelConfig message. Raises ValueError."""
    sound_speed = sound_speed_of(settings)
    absorption = absorption_of(settings)
    by_rate = dict(DEFAULT_RATE_MODELS)
    by_rate.update({entry.rate: _rate_model(entry) for entry in settings.rate_model})
    config = ChannelConfig(
        sound_speed=sound_speed,
        source_level=settings.source_level,
        spreading=settings.spreading,
        absorption=absorption,
        noise_level=settings.noise_level if settings.HasField("noise_level") else None,
        shipping=settings.shipping,
        wind=settings.wind_speed,
        band=Band(settings.carrier_hz, settings.bandwidth_hz),
        error_models=RateErrorModels(by_rate=by_rate),
        durations={
            PacketKind.DATA: settings.data_duration,
            PacketKind.MINI: settings.mini_duration,
            PacketKind.PING: settings.ping_duration,
        },
        half_duplex=settings.half_duplex,
        receiver_lock=settings.receiver_lock,
        decode_latency=settings.decode_latency,
        position_staleness=settings.position_staleness,
        protocol_model=protocol_model_of(settings),
        propagation=propagation_of(settings, sound_speed),
    )
    return config, settings.seed


def environment_channel_configs(
    manager_config: NetSimManagerConfig,
) -> dict[int, tuple[ChannelConfig, int]]:
    """(ChannelConfig, seed) per environment id of a NetSimManagerConfig; environments without
    an `environment_channel` entry get the defaults. Raises ValueError."""
    defaults = channel_config_from_proto(channel_settings_class()())
    configs = {bounds.environment_id: defaults for bounds in manager_config.env_bounds}
    for entry in manager_config.environment_channel:
        if entry.environment_id not in configs:
            raise ValueError(
                f"environment_channel for environment {entry.environment_id}, "
                "which has no env_bounds"
            )
        configs[entry.environment_id] = channel_config_from_proto(entry.channel)
    return configs
