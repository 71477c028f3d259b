"""Every formula of the channel model against vectors/netsim/physics_checks.json."""

from __future__ import annotations

import math

import pytest
from netsim_vectors import physics

from pygoby.netsim.channel import absorption, frame_errors, geometry, levels, soundspeed, timing

P = physics()
TOL = 0.01  # default absolute tolerance in the printed unit


def _cases(block, key="cases"):
    return pytest.mark.parametrize("case", block[key], ids=lambda c: str(c))


# -- sound speed -------------------------------------------------------------------------------


@_cases(P["sound_speed"]["mackenzie_1981"])
def test_mackenzie(case):
    assert soundspeed.mackenzie_1981(case["T"], case["S"], case["D"]) == pytest.approx(
        case["c"], abs=1e-4
    )


@_cases(P["sound_speed"]["medwin_1975"])
def test_medwin(case):
    assert soundspeed.medwin_1975(case["T"], case["S"], case["D"]) == pytest.approx(
        case["c"], abs=1e-4
    )


@_cases(P["sound_speed"]["unesco_1983_chen_millero"])
def test_unesco(case):
    c = soundspeed.unesco_1983(case["S"], case["T68"], case["P_dbar"])
    assert c == pytest.approx(case["c"], abs=1e-5)


@_cases(P["sound_speed"]["unesco_1983_chen_millero"], "its90_cases")
def test_unesco_its90_input(case):
    t68 = soundspeed.t68_from_t90(case["T90"])
    assert t68 == pytest.approx(case["T68"], abs=1e-9)
    assert soundspeed.unesco_1983(case["S"], t68, case["P_dbar"]) == pytest.approx(
        case["c"], abs=1e-5
    )


@_cases(P["sound_speed"]["teos10_gsw"])
def test_teos10(case):
    c = soundspeed.teos10(case["SA"], case["CT"], case["p_dbar"])
    assert c == pytest.approx(case["c"], abs=1e-4)


@pytest.mark.parametrize(
    "case", P["depth_to_pressure"]["saunders_1981"], ids=lambda c: f"{c['D']}m"
)
def test_saunders(case):
    p = soundspeed.saunders_pressure(case["D"], case["lat"])
    assert p == pytest.approx(case["P_dbar"], abs=1e-3)


@pytest.mark.parametrize("case", P["depth_to_pressure"]["gsw_p_from_z"], ids=lambda c: f"{c['D']}m")
def test_teos10_pressure(case):
    p = soundspeed.teos10_pressure(case["D"], case["lat"])
    assert p == pytest.approx(case["P_dbar"], abs=1e-4)
    # the note's claim: Saunders and TEOS-10 agree to < 0.1 %
    assert soundspeed.saunders_pressure(case["D"], case["lat"]) == pytest.approx(p, rel=1e-3)


def test_harmonic_mean_speed():
    # level path: the speed at that depth; linear profile: (z2 - z1) / integral = closed form
    assert soundspeed.harmonic_mean_speed(lambda z: 1500 + z, 10, 10) == 1510
    expected = 100 / math.log(1600 / 1500)
    assert soundspeed.harmonic_mean_speed(lambda z: 1500 + z, 0, 100) == pytest.approx(
        expected, abs=1e-6
    )


# -- absorption and transmission loss ---------------------------------------------------------


@_cases(P["absorption"]["thorp"])
def test_thorp(case):
    assert absorption.thorp(case["f_khz"]) == pytest.approx(case["alpha"], abs=1e-4)


@_cases(P["absorption"]["thorp_coa_variant"])
def test_thorp_coa(case):
    assert absorption.thorp_coa(case["f_khz"]) == pytest.approx(case["alpha"], abs=1e-5)


@_cases(P["absorption"]["francois_garrison_1982"])
def test_francois_garrison(case):
    alpha = absorption.francois_garrison(case["f_khz"], case["T"], case["S"], case["D"], case["pH"])
    assert alpha == pytest.approx(case["alpha"], abs=1e-4)


def test_francois_garrison_uses_high_branch_at_20_degrees():
    case = P["absorption"]["francois_garrison_1982"]["boundary_T20"]
    alpha = absorption.francois_garrison(case["f_khz"], case["T"], case["S"], case["D"], case["pH"])
    assert alpha == pytest.approx(case["alpha_high_branch"], abs=1e-6)
    # just below 20 deg C the low-temperature pure-water term applies; it meets the boundary
    # value of that form
    args = (case["f_khz"], case["T"] - 1e-9, case["S"], case["D"], case["pH"])
    assert absorption.francois_garrison(*args) == pytest.approx(case["alpha_low_branch"], abs=1e-6)


def _alpha(spec: str, f_khz: float) -> float:
    if spec == "thorp":
        return absorption.thorp(f_khz)
    # "francois_garrison T=10 S=35 D=100 pH=8"
    params = dict(item.split("=") for item in spec.split()[1:])
    return absorption.francois_garrison(
        f_khz, float(params["T"]), float(params["S"]), float(params["D"]), float(params["pH"])
    )


@_cases(P["transmission_loss"])
def test_transmission_loss(case):
    alpha = _alpha(case["absorption"], case["f_khz"])
    tl = levels.transmission_loss(case["r_m"], alpha, case["k"])
    assert tl == pytest.approx(case["tl_db"], abs=TOL)


# -- noise, SNR, SINR ---------------------------------------------------------------------------

NOISE = P["ambient_noise_stojanovic_2007"]


@_cases(NOISE, "psd_cases")
def test_stojanovic_psd(case):
    n = levels.stojanovic_noise(case["f_khz"], case["s"], case["w"])
    assert n.turbulence == pytest.approx(case["Nt"], abs=TOL)
    assert n.shipping == pytest.approx(case["Ns"], abs=TOL)
    assert n.wind == pytest.approx(case["Nw"], abs=TOL)
    assert n.thermal == pytest.approx(case["Nth"], abs=TOL)
    assert n.total == pytest.approx(case["N"], abs=TOL)


@_cases(NOISE, "band_levels")
def test_noise_band_levels(case):
    args = (case["fc_khz"], case["B_hz"], case["s"], case["w"])
    assert levels.noise_level_flat(*args) == pytest.approx(case["NL_flat"], abs=TOL)
    assert levels.noise_level_integrated(*args) == pytest.approx(case["NL_integrated"], abs=TOL)


@_cases(P["snr"])
def test_snr_budget(case):
    alpha = _alpha(case["absorption"], case["f_khz"])
    rl = levels.received_level(case["SL"], levels.transmission_loss(case["r_m"], alpha, case["k"]))
    assert rl == pytest.approx(case["RL"], abs=TOL)
    assert levels.snr(rl, case["NL"]) == pytest.approx(case["SNR"], abs=TOL)


@_cases(P["sinr"])
def test_sinr(case):
    total = levels.power_sum_db([case["NL"], *case["interferers"]])
    assert total == pytest.approx(case["noise_total"], abs=TOL)
    assert levels.sinr(case["RL"], case["NL"], case["interferers"]) == pytest.approx(
        case["SINR"], abs=TOL
    )


# -- packet errors ------------------------------------------------------------------------------

PE = P["packet_error"]


def test_builtin_tables_equal_the_vector_tables():
    for rate, table in PE["table_ros_acomms"]["tables"].items():
        model = frame_errors.ROS_ACOMMS_TABLES[int(rate)]
        assert list(model.snr_db) == table["snr_db"]
        assert list(model.frame_error_rate) == table["frame_error"]
        assert frame_errors.ROS_ACOMMS_FRAMES[int(rate)] == table["frames"]


@_cases(PE["table_ros_acomms"], "checks")
def test_table_model(case):
    fer = frame_errors.ROS_ACOMMS_TABLES[case["rate"]].frame_error(case["snr_db"])
    assert fer == pytest.approx(case["frame_error"], abs=1e-6)
    frames = frame_errors.ROS_ACOMMS_FRAMES[case["rate"]]
    assert frame_errors.packet_success_probability(fer, frames) == pytest.approx(
        case["p_packet_ok"], abs=1e-6
    )


@_cases(PE["logistic"], "checks")
def test_logistic_model(case):
    fit = PE["logistic"]["fitted_to_ros_acomms"][str(case["rate"])]
    model = frame_errors.LogisticModel(fit["snr50_db"], fit["width_db"])
    assert model == frame_errors.LOGISTIC_FITS[case["rate"]]
    assert model.frame_error(case["snr_db"]) == pytest.approx(case["frame_error"], abs=1e-4)


@_cases(PE["threshold"])
def test_threshold_model(case):
    fer = frame_errors.ThresholdModel(case["threshold_db"]).frame_error(case["snr_db"])
    assert (fer == 0.0) is case["ok"]


@_cases(PE["ber_to_per"])
def test_ber_and_per(case):
    g = 10 ** (case["ebn0_db"] / 10)
    assert frame_errors.ber_bpsk(g) == pytest.approx(case["ber_bpsk"], rel=1e-5)
    assert frame_errors.ber_noncoherent_fsk(g) == pytest.approx(case["ber_ncfsk"], rel=1e-5)
    assert frame_errors.ber_rayleigh_noncoherent_fsk(g) == pytest.approx(
        case["ber_rayleigh_ncfsk"], rel=1e-5
    )
    per_bpsk = frame_errors.packet_error_from_ber(frame_errors.ber_bpsk(g), 32)
    assert per_bpsk == pytest.approx(case["per_bpsk_32_bytes"], abs=1e-5)
    per_fsk = frame_errors.packet_error_from_ber(frame_errors.ber_noncoherent_fsk(g), 32)
    assert per_fsk == pytest.approx(case["per_ncfsk_32_bytes"], abs=1e-5)


@_cases(PE["ber_to_per"], "ebn0_from_snr")
def test_ebn0_from_snr(case):
    ebn0 = frame_errors.ebn0_db(case["snr_db"], case["B_hz"], case["R_bps"])
    assert ebn0 == pytest.approx(case["ebn0_db"], abs=1e-4)


def test_ber_model_matches_per():
    model = frame_errors.BerModel("bpsk", bandwidth_hz=5000, bit_rate=500, frame_bytes=32)
    # SNR 0 dB at B/R = 10 -> Eb/N0 10 dB
    (case,) = [c for c in PE["ber_to_per"]["cases"] if c["ebn0_db"] == 10]
    assert model.frame_error(0.0) == pytest.approx(case["per_bpsk_32_bytes"], abs=1e-6)


@_cases(PE["netsim_udp_range_table"], "checks")
def test_range_table(case):
    table = [
        (row["range"], row["success_probability"]) for row in PE["netsim_udp_range_table"]["table"]
    ]
    assert frame_errors.range_table_probability(table, case["approx_range"]) == pytest.approx(
        case["p"], abs=1e-9
    )


@_cases(PE["netsim_udp_mpp"], "checks")
def test_mpp(case):
    assert frame_errors.mpp_probability(case["mpp"]) == pytest.approx(case["p"], abs=1e-9)


def test_protocol_model_defaults_and_ranges():
    d = PE["unetstack_protocol_model"]["defaults"]
    model = frame_errors.ProtocolModel()
    assert (
        model.communication_range,
        model.detection_range,
        model.interference_range,
        model.p_detection,
        model.p_decoding,
    ) == (
        d["communicationRange"],
        d["detectionRange"],
        d["interferenceRange"],
        d["pDetection"],
        d["pDecoding"],
    )
    outcomes = {
        1999: (1.0, True, True),
        2200: (0.0, True, True),
        2800: (0.0, False, True),
        3100: (0.0, False, False),
    }
    for check in PE["unetstack_protocol_model"]["checks"]:
        r = check["range_m"]
        got = (model.decode_probability(r), model.detected(r), model.interferes(r))
        assert got == outcomes[r]


# -- geometry, delay, Doppler, ranging, timing ------------------------------------------------

GEO = P["geometry_and_delay"]


@_cases(GEO, "geodesic_wgs84")
def test_geodesic(case):
    a = geometry.NavFix(case["lat1"], case["lon1"], 0.0)
    b = geometry.NavFix(case["lat2"], case["lon2"], case["dz_m"])
    distance, azimuth = geometry.horizontal_range(a, b)
    assert distance == pytest.approx(case["horizontal_m"], abs=1e-3)
    assert azimuth == pytest.approx(case["azimuth_deg"], abs=1e-3)
    slant = geometry.slant_range(a, b)
    assert slant == pytest.approx(case["slant_m"], abs=1e-3)
    assert geometry.owtt(slant, 1500) == pytest.approx(case["owtt_s_c1500"], abs=1e-6)


@_cases(GEO, "owtt_cases")
def test_owtt(case):
    assert geometry.owtt(case["slant_m"], case["c"]) == pytest.approx(case["owtt_s"], abs=1e-6)


@_cases(P["moving_receiver"])
def test_moving_receiver(case):
    tx = case["tx_xyz"]
    rx0, v = case["rx_xyz_at_tx_time"], case["rx_velocity"]

    def range_at(tau):
        rx = [rx0[i] + v[i] * tau for i in range(3)]
        return math.dist(tx, rx)

    assert range_at(0) / case["c"] == case["static_owtt"]
    assert geometry.arrival_delay(range_at, case["c"]) == pytest.approx(case["owtt"], abs=1e-9)


@_cases(P["dead_reckoning"])
def test_dead_reckoning(case):
    east, north = geometry.dead_reckoning_offset(case["speed"], case["heading"], case["dt"])
    assert east == pytest.approx(case["d_east"], abs=1e-6)
    assert north == pytest.approx(case["d_north"], abs=1e-6)


def test_position_dead_reckons_on_the_ellipsoid():
    start = geometry.NavFix(42.0, -70.0, 5.0, time=100.0, speed=1.0, heading=200.0)
    later = start.at(160.0)
    distance, azimuth = geometry.horizontal_range(start, later)
    assert distance == pytest.approx(60.0, abs=1e-6)
    assert azimuth % 360 == pytest.approx(200.0, abs=1e-3)


def test_remembered_geodesics_are_the_geodesics():
    """Fixed nodes ask for the same geodesics again and again (they are remembered): every
    answer, the first or a recurring one, is the geodesic's, zero coordinates of either sign
    included."""
    a = geometry.NavFix(42.0, -70.0, 5.0)
    ends = [
        geometry.NavFix(42.01, -69.99, 30.0),
        geometry.NavFix(0.0, -70.0, 5.0),
        geometry.NavFix(-0.0, -70.0, 5.0),
        geometry.NavFix(42.01, 0.0, 5.0),
        geometry.NavFix(42.01, -0.0, 5.0),
    ]
    for b in ends * 2:
        azimuth, _, distance = geometry.WGS84.inv(a.lon, a.lat, b.lon, b.lat)
        assert geometry.horizontal_range(a, b) == (distance, azimuth)
        assert geometry.horizontal_range(a, b) == (distance, azimuth)


@_cases(P["doppler"])
def test_doppler(case):
    f = geometry.doppler_frequency(case["f_tx"], case["v_closing"], case["c"])
    assert f == pytest.approx(case["f_rx"], abs=TOL)


@pytest.mark.parametrize("case", P["ranging"]["two_way"], ids=str)
def test_two_way_ranging(case):
    leg = geometry.owtt(case["range_m"], case["c"])
    round_trip = timing.two_way_round_trip(leg, leg, case["tat_s"])
    assert round_trip == pytest.approx(case["round_trip_s"], abs=1e-6)
    assert timing.two_way_reported_owtt(round_trip, case["tat_s"]) == pytest.approx(
        case["owtt_s"], abs=1e-6
    )


@pytest.mark.parametrize("case", P["ranging"]["synchronous"], ids=str)
def test_synchronous_ranging(case):
    arrival = case["tx_time_s"] + case["true_owtt_s"]
    assert arrival == pytest.approx(case["arrival_s"], abs=1e-6)
    assert timing.synchronous_owtt(arrival) == pytest.approx(case["owtt_from_fraction_s"], abs=1e-6)


TIMING = P["timing_rules"]


@_cases(TIMING, "overlap_cases")
def test_overlap_rule(case):
    i, j = timing.Interval(*case["reception_i"]), timing.Interval(*case["other_j"])
    assert i.overlaps(j) is case["overlap"]
    assert j.overlaps(i) is case["overlap"]


@_cases(TIMING, "half_duplex_cases")
def test_half_duplex_rule(case):
    lost = timing.lost_to_half_duplex(
        timing.Interval(*case["reception"]), [timing.Interval(*case["own_tx"])]
    )
    assert lost is case["reception_lost"]


def test_reception_interval():
    ex = TIMING["duration_example"]
    interval = timing.reception_interval(ex["t_start"], ex["owtt"], ex["duration"])
    assert interval.start == pytest.approx(ex["arrival"], abs=1e-9)
    assert interval.end == pytest.approx(ex["reception_end"], abs=1e-9)


# -- every block of the vector file has a test above ---------------------------------------------

CHECKED_BLOCKS = {
    "sound_speed": {
        "mackenzie_1981/cases",
        "medwin_1975/cases",
        "unesco_1983_chen_millero/cases",
        "unesco_1983_chen_millero/its90_cases",
        "teos10_gsw/cases",
    },
    "depth_to_pressure": {"saunders_1981", "gsw_p_from_z"},
    "absorption": {
        "thorp/cases",
        "thorp_coa_variant/cases",
        "francois_garrison_1982/cases",
        "francois_garrison_1982/boundary_T20",
    },
    "transmission_loss": {"cases"},
    "ambient_noise_stojanovic_2007": {"psd_cases", "band_levels"},
    "snr": {"cases"},
    "sinr": {"cases"},
    "packet_error": {
        *(
            f"table_ros_acomms/tables/{rate}/{column}"
            for rate in (1, 3, 5)
            for column in ("snr_db", "frame_error")
        ),
        "table_ros_acomms/checks",
        *(f"logistic/fitted_to_ros_acomms/{rate}" for rate in (1, 3, 5)),
        "logistic/checks",
        "threshold/cases",
        "ber_to_per/cases",
        "ber_to_per/ebn0_from_snr",
        "netsim_udp_range_table/table",
        "netsim_udp_range_table/checks",
        "netsim_udp_mpp/checks",
        "unetstack_protocol_model/defaults",
        "unetstack_protocol_model/checks",
    },
    "geometry_and_delay": {"geodesic_wgs84", "owtt_cases"},
    "moving_receiver": {"cases"},
    "dead_reckoning": {"cases"},
    "doppler": {"cases"},
    "ranging": {"two_way", "synchronous"},
    "timing_rules": {"overlap_cases", "half_duplex_cases", "duration_example"},
}


def _data_blocks(node: dict, path: str = ""):
    """Paths of the lists and flat records in the vector file (notes and formulas are strings)."""
    for key, value in node.items():
        here = f"{path}{key}"
        if isinstance(value, list):
            yield here
        elif isinstance(value, dict):
            if any(isinstance(v, (dict, list)) for v in value.values()):
                yield from _data_blocks(value, here + "/")
            else:
                yield here


def test_every_vector_block_is_checked():
    checked = {f"{top}/{block}" for top, blocks in CHECKED_BLOCKS.items() for block in blocks}
    in_file = set(_data_blocks({k: v for k, v in P.items() if k != "units"}))
    assert in_file == checked
