"""Driver selection by DriverType, DRIVER_NONE, driver names and config validation."""

import pytest

from pygoby.acomms import messages as m
from pygoby.acomms.driver_base import ModemDriverError, NoDriver, driver_name
from pygoby.acomms.drivers import make_driver
from pygoby.acomms.drivers.micromodem import MMDriver
from pygoby.acomms.drivers.udp import UDPDriver
from pygoby.util.clock import VirtualClock


def test_factory_and_driver_none():
    clock = VirtualClock(0)
    none = make_driver(m.DriverConfig(driver_type=1, modem_id=1), clock)
    assert isinstance(none, NoDriver)
    none.startup(m.DriverConfig(driver_type=1, modem_id=1))
    requests = []
    none.signal_data_request.connect(requests.append)
    none.handle_initiate_transmission(m.ModemTransmission(src=1))
    none.do_work()
    assert requests == []
    assert isinstance(make_driver(m.DriverConfig(driver_type=2), clock), MMDriver)
    assert isinstance(make_driver(m.DriverConfig(driver_type=6), clock), UDPDriver)
    with pytest.raises(ModemDriverError):
        make_driver(m.DriverConfig(driver_type=8), clock)  # Iridium: not implemented


def test_driver_name_and_missing_settings():
    assert driver_name(m.DriverConfig(driver_type=2, modem_id=1)) == "WHOI_MICROMODEM::1"
    assert driver_name(m.DriverConfig(driver_name="my_plugin", modem_id=3)) == "my_plugin::3"
    d = MMDriver(VirtualClock(0))
    with pytest.raises(ModemDriverError) as info:
        d.startup(m.DriverConfig(driver_type=2))  # no modem_id
    assert info.value.status == m.ModemDriverStatus.INVALID_CONFIGURATION
    with pytest.raises(ModemDriverError):
        d.startup(m.DriverConfig(driver_type=2, modem_id=1))  # SERIAL without serial_port
    with pytest.raises(ModemDriverError):
        d.startup(m.DriverConfig(driver_type=2, modem_id=1,
                                 connection_type=m.DriverConfig.CONNECTION_TCP_AS_CLIENT))  # fmt: skip
