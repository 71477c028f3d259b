"""Driver selection by DriverType, DRIVER_NONE, driver names and config validation."""

import pytest

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.driver_base import ModemDriverError, NoDriver, driver_name
from pygoby.acomms.drivers import make_driver
from pygoby.acomms.drivers.micromodem import MMDriver
from pygoby.acomms.drivers.udp import UDPDriver
from pygoby.util.clock import VirtualClock


def test_factory_and_driver_none():
    clock = VirtualClock(0)
    none = make_driver(acomms_pb.DriverConfig(driver_type=1, modem_id=1), clock)
    assert isinstance(none, NoDriver)
    none.startup(acomms_pb.DriverConfig(driver_type=1, modem_id=1))
    requests = []
    none.signal_data_request.connect(requests.append)
    none.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1))
    none.do_work()
    assert requests == []
    assert isinstance(make_driver(acomms_pb.DriverConfig(driver_type=2), clock), MMDriver)
    assert isinstance(make_driver(acomms_pb.DriverConfig(driver_type=6), clock), UDPDriver)
    with pytest.raises(ModemDriverError):
        make_driver(acomms_pb.DriverConfig(driver_type=8), clock)  # Iridium: not implemented


def test_driver_name_and_missing_settings():
    assert driver_name(acomms_pb.DriverConfig(driver_type=2, modem_id=1)) == "WHOI_MICROMODEM::1"
    assert (
        driver_name(acomms_pb.DriverConfig(driver_name="my_plugin", modem_id=3)) == "my_plugin::3"
    )
    d = MMDriver(VirtualClock(0))
    with pytest.raises(ModemDriverError) as info:
        d.startup(acomms_pb.DriverConfig(driver_type=2))  # no modem_id
    assert info.value.status == acomms_pb.ModemDriverStatus.INVALID_CONFIGURATION
    with pytest.raises(ModemDriverError):
        d.startup(acomms_pb.DriverConfig(driver_type=2, modem_id=1))  # SERIAL without serial_port
    with pytest.raises(ModemDriverError):
        d.startup(
            acomms_pb.DriverConfig(
                driver_type=2,
                modem_id=1,
                connection_type=acomms_pb.DriverConfig.CONNECTION_TCP_AS_CLIENT,
            )
        )
