"""Channel model settings in the manager configuration (environment_channel, pygoby-only)."""

from __future__ import annotations

import pytest

from pygoby.netsim.channel import Band, PacketKind
from pygoby.netsim.channel.absorption import francois_garrison, thorp
from pygoby.netsim.channel.frame_errors import (
    DEFAULT_RATE_MODELS,
    LogisticModel,
    ProtocolModel,
    TableModel,
    ThresholdModel,
)
from pygoby.netsim.channel.settings import environment_channel_configs
from pygoby.netsim.manager.config import EXAMPLE_CONFIG, ConfigError, parse_config

BOUNDS = (
    "env_bounds { environment_id: 0 lat_min: 0 lon_min: 0 lat_max: 1 lon_max: 1 depth_max: 10 }\n"
    "env_bounds { environment_id: 1 lat_min: 0 lon_min: 0 lat_max: 1 lon_max: 1 depth_max: 10 }\n"
)


def test_defaults_for_environments_without_settings():
    configs = environment_channel_configs(parse_config(BOUNDS))
    config, seed = configs[0]
    assert seed == 0 and set(configs) == {0, 1}
    assert config.sound_speed == 1500 and config.absorption is thorp
    assert config.noise_level is None and config.band == Band(25000, 5000)
    assert config.durations == {PacketKind.DATA: 3.25, PacketKind.MINI: 1.0, PacketKind.PING: 0.5}
    assert dict(config.error_models.by_rate) == DEFAULT_RATE_MODELS
    assert config.protocol_model is None


def test_every_setting_is_applied():
    text = (
        BOUNDS
        + """
    environment_channel { environment_id: 1 channel {
        water { temperature: 27 salinity: 35 ph: 8.1 absorption_depth: 10 }
        absorption: FRANCOIS_GARRISON source_level: 180 spreading: 2 noise_level: 60
        carrier_hz: 10000 bandwidth_hz: 4000
        rate_model { rate: 1 threshold_db: 8 }
        rate_model { rate: 3 logistic { snr50_db: -1.49 width_db: 0.33 } }
        rate_model { rate: 7 table { snr_db: [0, 10] frame_error: [1, 0] } }
        data_duration: 5 mini_duration: 2 ping_duration: 0.25 half_duplex: false
        receiver_lock: false decode_latency: 0.5 position_staleness: 30 seed: 42
        protocol_model { communication_range: 1000 }
    } }
    """
    )
    config, seed = environment_channel_configs(parse_config(text))[1]
    assert seed == 42
    assert config.sound_speed(10) == pytest.approx(1539.0866, abs=1e-4)  # Mackenzie(27, 35, 10)
    assert config.absorption(50) == pytest.approx(francois_garrison(50, 27, 35, 10, 8.1))
    assert (config.source_level, config.spreading, config.noise_level) == (180, 2, 60)
    assert config.band == Band(10000, 4000)
    models = config.error_models
    assert models.model(1) == ThresholdModel(8)
    assert models.model(3) == LogisticModel(-1.49, 0.33)
    assert models.model(7) == TableModel((0.0, 10.0), (1.0, 0.0))
    assert models.model(5) == DEFAULT_RATE_MODELS[5]
    assert config.durations[PacketKind.DATA] == 5 and config.durations[PacketKind.PING] == 0.25
    assert (config.half_duplex, config.receiver_lock) == (False, False)
    assert (config.decode_latency, config.position_staleness) == (0.5, 30)
    assert config.protocol_model == ProtocolModel(communication_range=1000)


@pytest.mark.parametrize(
    ("channel", "message"),
    [
        ("rate_model { rate: 1 table { snr_db: [1, 0] frame_error: [1, 0] } }", "increasing"),
        ("rate_model { rate: 1 table { snr_db: [1] frame_error: [] } }", "equally many"),
        ("rate_model { rate: 1 }", "no model"),
    ],
)
def test_invalid_channel_settings_are_config_errors(channel, message):
    text = BOUNDS + f"environment_channel {{ environment_id: 0 channel {{ {channel} }} }}"
    with pytest.raises(ConfigError, match=message):
        parse_config(text)


def test_channel_for_unknown_environment_is_a_config_error():
    with pytest.raises(ConfigError, match="environment 5"):
        parse_config(BOUNDS + "environment_channel { environment_id: 5 }")


def test_example_config_channel_block():
    config, seed = environment_channel_configs(parse_config(EXAMPLE_CONFIG))[0]
    assert seed == 1
    assert config.error_models.model(5) == LogisticModel(4.22, 0.12)
    assert config.error_models.model(0).frame_error(-8.5) == pytest.approx(0.75)


@pytest.mark.parametrize(
    ("formula", "expected"),
    [
        # spec netsim.md 7.3 check values at T 10 deg C, S 35, 100 m
        ("MACKENZIE_1981", 1491.4351),
        ("MEDWIN_1975", 1491.59),
        # Chen & Millero at Saunders' 100.751 dbar (lat 30): 1491.46887 at 100 dbar + ~0.0164/dbar
        ("UNESCO_1983", 1491.4898),
        # gsw from SP 35 / t 10 at 100 m, lat 30, lon -70 (spec's SA/CT check: 1491.5205 at 100 dbar)
        ("TEOS_10", 1491.4541),
    ],
)
def test_sound_speed_formula_is_selectable(formula, expected):
    water = (
        f"temperature: 10 salinity: 35 latitude: 30 longitude: -70 sound_speed_formula: {formula}"
    )
    text = BOUNDS + f"environment_channel {{ environment_id: 0 channel {{ water {{ {water} }} }} }}"
    config, _ = environment_channel_configs(parse_config(text))[0]
    assert config.sound_speed(100) == pytest.approx(expected, abs=1e-4)


def test_unesco_profile_uses_saunders_pressure_and_t68():
    from pygoby.netsim.channel.soundspeed import (
        saunders_pressure,
        t68_from_t90,
        unesco_1983,
        water_profile,
    )

    profile = water_profile("UNESCO_1983", 12, 34, lat=60)
    assert profile(2500) == unesco_1983(34, t68_from_t90(12), saunders_pressure(2500, 60))


def test_thorp_variant_is_selectable():
    from pygoby.netsim.channel.absorption import thorp_coa

    text = BOUNDS + "environment_channel { environment_id: 0 channel { absorption: THORP_COA } }"
    config, _ = environment_channel_configs(parse_config(text))[0]
    assert config.absorption is thorp_coa
    assert config.absorption(25) == pytest.approx(6.12073, abs=1e-5)  # spec 7.5's variant check
