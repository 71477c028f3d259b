"""Wire the layers together with their signals (as goby3's bind.h)."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # (for the annotations only)
    from pygoby.acomms.driver_base import ModemDriverBase
    from pygoby.acomms.mac import MACManager
    from pygoby.acomms.queue import QueueManager


def bind(
    driver: ModemDriverBase, queue: QueueManager | None = None, mac: MACManager | None = None
) -> None:
    """driver ⇄ queue (receive, data request) and mac → driver (initiate transmission).

    A MAC doing auto-discovery also learns the sources the driver hears."""
    if queue is not None:
        driver.signal_receive.connect(queue.handle_modem_receive)
        driver.signal_data_request.connect(queue.handle_modem_data_request)
    if mac is not None:
        mac.signal_initiate_transmission.connect(driver.handle_initiate_transmission)
        driver.signal_receive.connect(mac.handle_modem_receive)


def unbind(
    driver: ModemDriverBase, queue: QueueManager | None = None, mac: MACManager | None = None
) -> None:
    if queue is not None:
        driver.signal_receive.disconnect(queue.handle_modem_receive)
        driver.signal_data_request.disconnect(queue.handle_modem_data_request)
    if mac is not None:
        mac.signal_initiate_transmission.disconnect(driver.handle_initiate_transmission)
        driver.signal_receive.disconnect(mac.handle_modem_receive)
