import math

import pytest

from pygoby.moos.translator import (
    AlgorithmRegistry,
    ModemIdLookup,
    TranslatorConfigError,
    render_double,
)
from pygoby.moos.translator.algorithms import mackenzie_soundspeed

LOOKUP = """// modem id, vehicle name (should be community name), vehicle type
0, broadcast, broadcast
1, endeavor, ship
3, unicorn, auv
4, macrura, auv
"""


@pytest.fixture(scope="module")
def registry():
    return AlgorithmRegistry(42.35, -70.95, ModemIdLookup.from_text(LOOKUP))


@pytest.mark.parametrize(
    ("value", "text"),
    [
        (0.5, "0.500000000000000"),
        (0.0, "0.000000000000000"),
        (1.0, "1.000000000000000"),
        (-0.25, "-0.250000000000000"),
        (240.0, "240"),
        (1573.5, "1573.5"),
        (math.nan, "nan"),
        (-473.5, "-473.5"),
        (1.5, "1.5"),
        (math.inf, "inf"),
    ],
)
def test_value_rule(value, text):
    assert render_double(value) == text


@pytest.mark.parametrize(
    ("name", "value", "refs", "result"),
    [
        ("to_upper", "unicorn", [], "UNICORN"),
        ("to_lower", "UniCorn", [], "unicorn"),
        ("angle_0_360", "-120", [], "240"),
        ("angle_0_360", "720.5", [], "0.500000000000000"),
        ("angle_0_360", "360", [], "0.000000000000000"),
        ("angle_-180_180", "190", [], "-170"),
        ("angle_-180_180", "180", [], "-180"),
        ("angle_-180_180", "-180", [], "-180"),
        ("angle_0_360", "junk", [], "nan"),
        ("abs", "-3.5", [], "3.5"),
        ("power_to_dB", "100", [], "20"),
        ("power_to_dB", "0", [], "-inf"),
        ("dB_to_power", "30", [], "1000"),
        ("dB_to_power", "0", [], "1.000000000000000"),
        ("lat2hemisphere_initial", "-3", [], "S"),
        ("lat2hemisphere_initial", "3", [], "N"),
        ("lon2hemisphere_initial", "-70", [], "W"),
        ("lon2hemisphere_initial", "0", [], "E"),
        ("lat2nmea_lat", "42.5", [], "4230.0000"),
        ("lat2nmea_lat", "-43.5", [], "-4430.0000"),
        ("lat2nmea_lat", "5.123456", [], "0507.4073"),
        ("lon2nmea_lon", "70.95", [], "07057.0000"),
        ("lon2nmea_lon", "5.5", [], "00530.0000"),
        ("unix_time2nmea_time", "1700000000.25", [], "221320.250000"),
        ("add", "550", ["1023.5"], "1573.5"),
        ("add", "1", ["2", "3", "true"], "7"),
        ("subtract", "550", ["1023.5"], "-473.5"),
        ("subtract", "0.5", [], "0.500000000000000"),
        ("TSD_to_soundspeed", "10", ["35", "100"], "1491.435"),
        ("TSD_to_soundspeed", "31", ["35", "100"], "nan"),
        ("TSD_to_soundspeed", "10", ["24", "100"], "nan"),
        ("TSD_to_soundspeed", "10", ["35", "8001"], "nan"),
        ("utm_y2lat", "300", ["100"], "42.352720906492"),
        ("utm_x2lon", "100", ["300"], "-70.94887000425"),
        ("lat2utm_y", "42.36", ["-70.94"], "1091.57403572928"),
        ("lon2utm_x", "-70.94", ["42.36"], "849.007463140995"),
        ("lat2utm_y", "nan", ["-70.94"], "nan"),
        ("utm_x2lon", "abc", ["300"], "nan"),
        ("modem_id2name", "3", [], "unicorn"),
        ("modem_id2name", "7", [], "7"),
        ("modem_id2name", "unicorn", [], "unicorn"),
        ("modem_id2name", "", [], ""),
        ("modem_id2name", "0003", [], "unicorn"),
        # beyond an unsigned int (goby3 throws) and beyond Python's int() digit limit: unchanged
        ("modem_id2name", "4294967296", [], "4294967296"),
        ("modem_id2name", "9" * 5000, [], "9" * 5000),
        ("modem_id2type", "9" * 5000, [], "9" * 5000),
        ("modem_id2type", "4", [], "auv"),
        ("modem_id2type", "9", [], "unknown_type"),
        ("modem_id2type", "x", [], "x"),
        ("name2modem_id", "UNICORN", [], "3"),
        ("name2modem_id", "endeavor", [], "1"),
        ("name2modem_id", "12abc", [], "12"),
        ("name2modem_id", "nobody", [], "0"),
    ],
)
def test_algorithm(registry, name, value, refs, result):
    assert registry.run(name, value, refs) == result


def test_mackenzie_reference_value():
    # Mackenzie (1981) check value: T=25, S=35, D=1000 -> 1550.744 m/s
    assert round(mackenzie_soundspeed(25, 35, 1000), 3) == 1550.744


def test_utm_origin_zero_and_datum_change():
    registry = AlgorithmRegistry()
    assert registry.geodesy.zone == 31
    assert registry.run("lat2utm_y", "0", ["0"]) == "0.000000000000000"
    registry.set_datum(42.35, -70.95)
    assert registry.geodesy.zone == 19
    assert registry.run("utm_y2lat", "0", ["0"]) == "42.35"


def test_an_unknown_algorithm_passes_the_value_through(registry):
    # goby3's algorithm performer does nothing for a name it does not know.
    assert registry.find("alg_TSD_to_soundspeed") is None
    assert registry.run("alg_TSD_to_soundspeed", "10.5", ["35", "3"]) == "10.5"
    assert registry.unknown_reason("alg_TSD_to_soundspeed") == (
        "unknown algorithm 'alg_TSD_to_soundspeed'"
    )


def test_modem_id_algorithms_need_lookup_table():
    registry = AlgorithmRegistry()
    assert registry.run("modem_id2name", "3") == "3"
    assert registry.unknown_reason("modem_id2name") == (
        "unknown algorithm 'modem_id2name' (needs modem_id_lookup_path)"
    )


def test_missing_references_is_a_config_error(registry):
    with pytest.raises(TranslatorConfigError, match="needs 2 reference"):
        registry.run("TSD_to_soundspeed", "10", ["35"])


def test_all_documented_algorithms_exist(registry):
    assert set(registry.names()) == {
        "to_upper",
        "to_lower",
        "angle_0_360",
        "angle_-180_180",
        "abs",
        "power_to_dB",
        "dB_to_power",
        "lat2hemisphere_initial",
        "lon2hemisphere_initial",
        "lat2nmea_lat",
        "lon2nmea_lon",
        "unix_time2nmea_time",
        "add",
        "subtract",
        "TSD_to_soundspeed",
        "lat2utm_y",
        "lon2utm_x",
        "utm_x2lon",
        "utm_y2lat",
        "modem_id2name",
        "modem_id2type",
        "name2modem_id",
    }
