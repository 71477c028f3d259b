"""Message classes and extension handles for goby-acomms, from our .proto files.

The .proto files live under src/pygoby/protobuf/goby/acomms/protobuf/ at their upstream import
paths; this module loads them once into the process-wide pool and names the classes.
"""

from __future__ import annotations

from google.protobuf.descriptor import FieldDescriptor

from pygoby.protobuf import default_loader

BROADCAST_ID = 0
QUERY_DESTINATION_ID = -1
QUERY_SOURCE_ID = -1

_PROTO_FILES = (
    "goby/acomms/protobuf/modem_message.proto",
    "goby/acomms/protobuf/driver_base.proto",
    "goby/acomms/protobuf/queue.proto",
    "goby/acomms/protobuf/network_ack.proto",
    "goby/acomms/protobuf/amac_config.proto",
    "goby/acomms/protobuf/amac.proto",
    "goby/acomms/protobuf/dccl.proto",
    "goby/acomms/protobuf/mm_driver.proto",
    "goby/acomms/protobuf/udp_driver.proto",
    "goby/acomms/protobuf/udp_multicast_driver.proto",
    "goby/acomms/protobuf/abc_driver.proto",
    "goby/acomms/protobuf/store_server.proto",
    "goby/acomms/protobuf/store_server_driver.proto",
    "pygoby/acomms/store_server_auth.proto",
    "goby/moos/protobuf/ufield_sim_driver.proto",
)

_loader = default_loader()
for _name in _PROTO_FILES:
    _loader.load_file(_name)


def _cls(full_name: str):
    return _loader.message_class(full_name)


def goby_message_class(full_name: str):
    """pygoby's own messages a mission may name (MACUpdate, RouteCommand, NetworkAck, ...)."""
    _loader.load_file("goby/acomms/protobuf/route.proto")
    return _loader.message_class(full_name)


def extension(full_name: str) -> FieldDescriptor:
    """An extension field by full name, for `msg.Extensions[...]`."""
    return _loader.pool.FindExtensionByName(full_name)


ModemTransmission = _cls("goby.acomms.protobuf.ModemTransmission")
ModemRaw = _cls("goby.acomms.protobuf.ModemRaw")
ModemReport = _cls("goby.acomms.protobuf.ModemReport")
DriverConfig = _cls("goby.acomms.protobuf.DriverConfig")
ModemDriverStatus = _cls("goby.acomms.protobuf.ModemDriverStatus")
QueuedMessageEntry = _cls("goby.acomms.protobuf.QueuedMessageEntry")
QueueManagerConfig = _cls("goby.acomms.protobuf.QueueManagerConfig")
QueueSize = _cls("goby.acomms.protobuf.QueueSize")
QueueFlush = _cls("goby.acomms.protobuf.QueueFlush")
QueuedMessageMeta = _cls("goby.acomms.protobuf.QueuedMessageMeta")
NetworkAck = _cls("goby.acomms.protobuf.NetworkAck")
MACConfig = _cls("goby.acomms.protobuf.MACConfig")
MACUpdate = _cls("goby.acomms.protobuf.MACUpdate")
DCCLConfig = _cls("goby.acomms.protobuf.DCCLConfig")
StoreServerRequest = _cls("goby.acomms.protobuf.StoreServerRequest")
StoreServerResponse = _cls("goby.acomms.protobuf.StoreServerResponse")

MMConfig = _cls("goby.acomms.micromodem.protobuf.Config")
MMTransmission = _cls("goby.acomms.micromodem.protobuf.Transmission")
ReceiveStatistics = _cls("goby.acomms.micromodem.protobuf.ReceiveStatistics")
TransmitStatistics = _cls("goby.acomms.micromodem.protobuf.TransmitStatistics")
RangingReply = _cls("goby.acomms.micromodem.protobuf.RangingReply")
MMApplicationAck = _cls("goby.acomms.micromodem.protobuf.MMApplicationAck")
UDPConfig = _cls("goby.acomms.udp.protobuf.Config")
ABCConfig = _cls("goby.acomms.abc.protobuf.Config")
StoreServerConfig = _cls("goby.acomms.store_server.protobuf.Config")
StoreServerTransmission = _cls("goby.acomms.store_server.protobuf.Transmission")
StoreServerRequestAuth = _cls("pygoby.acomms.protobuf.StoreServerRequestAuth")
StoreServerResponseStatus = _cls("pygoby.acomms.protobuf.StoreServerResponseStatus")
UFldConfig = _cls("goby.moos.ufld.protobuf.Config")
UFldTransmission = _cls("goby.moos.ufld.protobuf.Transmission")

# Goby 1.1 forms (goby.transitional.protobuf): CCL queues and the 1.1 MOOS variables
V1QueueConfig = _cls("goby.transitional.protobuf.QueueConfig")
V1ModemDataTransmission = _cls("goby.transitional.protobuf.ModemDataTransmission")
V1ModemRangingRequest = _cls("goby.transitional.protobuf.ModemRangingRequest")
V1ModemRangingReply = _cls("goby.transitional.protobuf.ModemRangingReply")
V1MACUpdate = _cls("goby.transitional.protobuf.MACUpdate")
V1ModemDataAck = _cls("goby.transitional.protobuf.ModemDataAck")
V1ModemDataExpire = _cls("goby.transitional.protobuf.ModemDataExpire")
V1QueueSize = _cls("goby.transitional.protobuf.QueueSize")
V1QueueFlush = _cls("goby.transitional.protobuf.QueueFlush")
QUEUE_CCL = (
    _loader.pool.FindEnumTypeByName("goby.transitional.protobuf.QueueType")
    .values_by_name["QUEUE_CCL"]
    .number
)
QUEUE_DCCL = (
    _loader.pool.FindEnumTypeByName("goby.transitional.protobuf.QueueType")
    .values_by_name["QUEUE_DCCL"]
    .number
)

MM_CONFIG = extension("goby.acomms.micromodem.protobuf.config")
MM_TRANSMISSION = extension("goby.acomms.micromodem.protobuf.transmission")
UDP_CONFIG = extension("goby.acomms.udp.protobuf.config")
ABC_CONFIG = extension("goby.acomms.abc.protobuf.config")
STORE_SERVER_CONFIG = extension("goby.acomms.store_server.protobuf.config")
STORE_SERVER_TRANSMISSION = extension("goby.acomms.store_server.protobuf.transmission")
STORE_SERVER_AUTH = extension("pygoby.acomms.protobuf.store_server_auth")
UFLD_CONFIG = extension("goby.moos.ufld.protobuf.config")
UFLD_TRANSMISSION = extension("goby.moos.ufld.protobuf.transmission")

# enum values used throughout
DATA = ModemTransmission.DATA
ACK = ModemTransmission.ACK
DRIVER_SPECIFIC = ModemTransmission.DRIVER_SPECIFIC
_MM_TYPE = _loader.pool.FindEnumTypeByName(
    "goby.acomms.micromodem.protobuf.TransmissionType"
).values_by_name
MICROMODEM_TWO_WAY_PING = _MM_TYPE["MICROMODEM_TWO_WAY_PING"].number
MICROMODEM_REMUS_LBL_RANGING = _MM_TYPE["MICROMODEM_REMUS_LBL_RANGING"].number
MICROMODEM_NARROWBAND_LBL_RANGING = _MM_TYPE["MICROMODEM_NARROWBAND_LBL_RANGING"].number
MICROMODEM_MINI_DATA = _MM_TYPE["MICROMODEM_MINI_DATA"].number
MICROMODEM_FLEXIBLE_DATA = _MM_TYPE["MICROMODEM_FLEXIBLE_DATA"].number
MICROMODEM_HARDWARE_CONTROL = _MM_TYPE["MICROMODEM_HARDWARE_CONTROL"].number
MICROMODEM_HARDWARE_CONTROL_REPLY = _MM_TYPE["MICROMODEM_HARDWARE_CONTROL_REPLY"].number
MICROMODEM_GENERIC_LBL_RANGING = _MM_TYPE["MICROMODEM_GENERIC_LBL_RANGING"].number
MICROMODEM_FM_SWEEP = _MM_TYPE["MICROMODEM_FM_SWEEP"].number
MICROMODEM_M_SEQUENCE = _MM_TYPE["MICROMODEM_M_SEQUENCE"].number


def now_us(seconds: float) -> int:
    """Seconds since the epoch -> ModemTransmission time (microseconds)."""
    return int(round(seconds * 1e6))
