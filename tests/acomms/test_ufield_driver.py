"""uField driver core: two nodes joined by a stand-in for uFldNodeComms + uFldMessageHandler."""

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.drivers.ufield import UFldDriver, parse_moos_pairs
from pygoby.util.clock import VirtualClock

from .queue_helpers import status_link


class Shoreside:
    """Delivers NODE_MESSAGE_LOCAL to the named node(s) as their `var_name` mail."""

    def __init__(self):
        self.nodes: dict[str, UFldDriver] = {}
        self.posted: list[tuple[str, str, str]] = []

    def publisher(self, name):
        def publish(var, text):
            self.posted.append((name, var, text))
            if var == "NODE_MESSAGE_LOCAL":
                fields = dict(part.split("=", 1) for part in text.split(","))
                for node, driver in self.nodes.items():
                    if node != fields["src_node"] and fields["dest_node"] in (node, "all"):
                        driver.handle_mail(fields["var_name"], fields["string_val"])

        return publish


def make_node(shore, tmp_path, modem_id, name):
    lookup = tmp_path / "ids.txt"
    lookup.write_text("// id, name, type\n0, broadcast, broadcast\n1, alpha, auv\n2, bravo, auv\n")
    driver = UFldDriver(VirtualClock(1_700_000_000.0), shore.publisher(name))
    cfg = acomms_pb.DriverConfig(driver_type=4, modem_id=modem_id)
    cfg.Extensions[acomms_pb.UFLD_CONFIG].modem_id_lookup_path = str(lookup)
    driver.startup(cfg)
    shore.nodes[name] = driver
    return driver


def test_data_ack_and_poll_through_ufield(tmp_path):
    shore = Shoreside()
    d1, d2 = make_node(shore, tmp_path, 1, "alpha"), make_node(shore, tmp_path, 2, "bravo")
    clock = d1.clock
    q1, q2, Status, got, acked = status_link(clock, d1, d2)
    q1.push_message(Status(src=1, dest=2, value=3))
    d1.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1, dest=-1, rate=0))
    assert [x.value for x in got] == [3] and acked == [3]
    node_msg = next(t for n, v, t in shore.posted if v == "NODE_MESSAGE_LOCAL")
    assert node_msg.startswith("src_node=alpha,dest_node=bravo,var_name=ACOMMS_UFIELD_DRIVER_IN,")
    assert ("alpha", "ACOMMS_UFIELD_DRIVER_OUT", node_msg.rsplit("=", 1)[1]) in shore.posted
    # alpha polls bravo for data addressed to alpha
    back = []
    q1.signal_receive.connect(back.append)
    q2.push_message(Status(src=2, dest=1, value=4))
    d1.handle_initiate_transmission(acomms_pb.ModemTransmission(src=2, dest=1, rate=0))
    assert [x.value for x in back] == [4]


def test_ranging_through_range_request_and_report(tmp_path):
    shore = Shoreside()
    d1 = make_node(shore, tmp_path, 1, "alpha")
    got = []
    d1.signal_receive.connect(got.append)
    ping = acomms_pb.ModemTransmission(src=1, dest=2, type=acomms_pb.DRIVER_SPECIFIC)
    ping.Extensions[acomms_pb.MM_TRANSMISSION].type = acomms_pb.MICROMODEM_TWO_WAY_PING
    d1.handle_initiate_transmission(ping)
    assert ("alpha", "CRS_RANGE_REQUEST", "name=alpha") in shore.posted
    d1.handle_mail("CRS_RANGE_REPORT", "range=1500.0,target=charlie,time=1364413337.272")
    assert got == []  # not our target
    d1.handle_mail("CRS_RANGE_REPORT", "range=750.0,target=bravo,time=1364413337.272")
    (r,) = got
    assert (r.src, r.dest, r.time) == (1, 2, 1364413337_000_000)
    assert list(r.Extensions[acomms_pb.MM_TRANSMISSION].ranging_reply.one_way_travel_time) == [0.5]
    d1.handle_mail("ACOMMS_UFIELD_DRIVER_IN", "zz-not-hex")  # logged and skipped
    assert parse_moos_pairs("a=1, B = x") == {"a": "1", "b": "x"}
