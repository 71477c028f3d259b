"""The AcommsError family: what goby-acomms (drivers, queue, MAC, handler, wire formats)
raises on purpose."""

from pygoby.errors import ConfigError, PygobyError

INVALID_CONFIGURATION = 4  # goby.acomms.protobuf.ModemDriverStatus.INVALID_CONFIGURATION


class AcommsError(PygobyError):
    """Base class of every acomms error."""


class ModemDriverError(AcommsError):
    """A driver failure; `status` is a ModemDriverStatus.Status value."""

    def __init__(self, message: str, status: int) -> None:
        super().__init__(message)
        self.status = status


class QueueError(AcommsError):
    """A message cannot be queued (no queue for its type, empty encoding, bad config)."""


class RoleError(AcommsError, ValueError):
    """A role in the queue configuration is invalid for its message type (or a message's role
    field holds a value the role cannot use)."""


class DriverNotFoundError(ModemDriverError):
    """No driver of that type or name (an INVALID_CONFIGURATION driver failure)."""

    def __init__(self, message: str) -> None:
        super().__init__(message, INVALID_CONFIGURATION)


class HandlerError(AcommsError):
    """The handler's configuration cannot be used, or a failure it cannot recover from."""


class DriverConfigError(HandlerError, ConfigError):
    """A driver configuration the handler cannot use (a driver_type or driver_name with no
    driver, a driver refusing its settings); `field` is where in the handler's configuration
    (`driver_cfg.driver_type`, `listen_driver_cfg[1].driver_name`, ...), for the mission line."""


class StoreServerAuthError(AcommsError):
    """A store-server request is not signed with its modem id's secret, or replays an older one."""


class RudicsPacketError(AcommsError, ValueError):
    """A RUDICS packet is too short, too long or fails its CRC."""


class ABCParseError(AcommsError, ValueError):
    """A line is not `KEY,NAME:VALUE,...` (the ABC example modem's protocol)."""
