"""Message classes and extension handles for goby-acomms, from our .proto files.

The .proto files live under src/pygoby/protobuf/goby/acomms/protobuf/ at their upstream import
paths; their generated modules (made at build time) register them in protobuf's default pool, and
this module names the classes, extensions and enum values the rest of pygoby uses.
"""

from __future__ import annotations

from google.protobuf.message import Message

from pygoby.protobuf import default_loader
from pygoby.protobuf.descriptors import AnyFieldDescriptor
from pygoby.protobuf.goby.acomms.protobuf import (
    abc_driver_pb2,
    amac_config_pb2,
    amac_pb2,
    dccl_pb2,
    driver_base_pb2,
    mm_driver_pb2,
    mm_receive_statistics_pb2,
    modem_message_pb2,
    network_ack_pb2,
    queue_pb2,
    store_server_driver_pb2,
    store_server_pb2,
    udp_driver_pb2,
    udp_multicast_driver_pb2,
)
from pygoby.protobuf.goby.moos.protobuf import transitional_pb2, ufield_sim_driver_pb2
from pygoby.protobuf.pygoby.acomms import store_server_auth_pb2

BROADCAST_ID = 0
QUERY_DESTINATION_ID = -1
QUERY_SOURCE_ID = -1


def goby_message_class(full_name: str) -> type[Message]:
    """pygoby's own messages a mission may name (MACUpdate, RouteCommand, NetworkAck, ...)."""
    loader = default_loader()
    loader.load_file("goby/acomms/protobuf/route.proto")
    return loader.message_class(full_name)


def extension(full_name: str) -> AnyFieldDescriptor:
    """An extension field by full name, for `msg.Extensions[...]`."""
    return default_loader().pool.FindExtensionByName(full_name)


ModemTransmission = modem_message_pb2.ModemTransmission
ModemRaw = modem_message_pb2.ModemRaw
ModemReport = modem_message_pb2.ModemReport
DriverConfig = driver_base_pb2.DriverConfig
DriverType = driver_base_pb2.DriverType
ModemDriverStatus = driver_base_pb2.ModemDriverStatus
QueuedMessageEntry = queue_pb2.QueuedMessageEntry
QueueManagerConfig = queue_pb2.QueueManagerConfig
QueueSize = queue_pb2.QueueSize
QueueFlush = queue_pb2.QueueFlush
QueuedMessageMeta = queue_pb2.QueuedMessageMeta
NetworkAck = network_ack_pb2.NetworkAck
MACConfig = amac_config_pb2.MACConfig
MACType = amac_config_pb2.MACType
MACUpdate = amac_pb2.MACUpdate
DCCLConfig = dccl_pb2.DCCLConfig
StoreServerRequest = store_server_pb2.StoreServerRequest
StoreServerResponse = store_server_pb2.StoreServerResponse

MMConfig = mm_driver_pb2.Config
MMTransmission = mm_driver_pb2.Transmission
ReceiveStatistics = mm_receive_statistics_pb2.ReceiveStatistics
TransmitStatistics = mm_driver_pb2.TransmitStatistics
RangingReply = mm_driver_pb2.RangingReply
MMApplicationAck = mm_driver_pb2.MMApplicationAck
UDPConfig = udp_driver_pb2.Config
ABCConfig = abc_driver_pb2.Config
StoreServerConfig = store_server_driver_pb2.Config
StoreServerTransmission = store_server_driver_pb2.Transmission
StoreServerRequestAuth = store_server_auth_pb2.StoreServerRequestAuth
StoreServerResponseStatus = store_server_auth_pb2.StoreServerResponseStatus
UFldConfig = ufield_sim_driver_pb2.Config
UFldTransmission = ufield_sim_driver_pb2.Transmission

# Goby 1.1 forms (goby.transitional.protobuf): CCL queues and the 1.1 MOOS variables
V1QueueConfig = transitional_pb2.QueueConfig
V1ModemDataTransmission = transitional_pb2.ModemDataTransmission
V1ModemRangingRequest = transitional_pb2.ModemRangingRequest
V1ModemRangingReply = transitional_pb2.ModemRangingReply
V1MACUpdate = transitional_pb2.MACUpdate
V1ModemDataAck = transitional_pb2.ModemDataAck
V1ModemDataExpire = transitional_pb2.ModemDataExpire
V1QueueSize = transitional_pb2.QueueSize
V1QueueFlush = transitional_pb2.QueueFlush
V1RangingType = transitional_pb2.RangingType
QUEUE_CCL = transitional_pb2.QUEUE_CCL
QUEUE_DCCL = transitional_pb2.QUEUE_DCCL

MM_CONFIG = mm_driver_pb2.config
MM_TRANSMISSION = mm_driver_pb2.transmission
UDP_CONFIG = udp_driver_pb2.config
UDP_MULTICAST_CONFIG = udp_multicast_driver_pb2.config
UDPMulticastConfig = udp_multicast_driver_pb2.Config
ABC_CONFIG = abc_driver_pb2.config
STORE_SERVER_CONFIG = store_server_driver_pb2.config
STORE_SERVER_TRANSMISSION = store_server_driver_pb2.transmission
STORE_SERVER_AUTH = store_server_auth_pb2.store_server_auth
UFLD_CONFIG = ufield_sim_driver_pb2.config
UFLD_TRANSMISSION = ufield_sim_driver_pb2.transmission

# enum values used throughout
DATA = ModemTransmission.DATA
ACK = ModemTransmission.ACK
DRIVER_SPECIFIC = ModemTransmission.DRIVER_SPECIFIC
MICROMODEM_TWO_WAY_PING = mm_driver_pb2.MICROMODEM_TWO_WAY_PING
MICROMODEM_REMUS_LBL_RANGING = mm_driver_pb2.MICROMODEM_REMUS_LBL_RANGING
MICROMODEM_NARROWBAND_LBL_RANGING = mm_driver_pb2.MICROMODEM_NARROWBAND_LBL_RANGING
MICROMODEM_MINI_DATA = mm_driver_pb2.MICROMODEM_MINI_DATA
MICROMODEM_FLEXIBLE_DATA = mm_driver_pb2.MICROMODEM_FLEXIBLE_DATA
MICROMODEM_HARDWARE_CONTROL = mm_driver_pb2.MICROMODEM_HARDWARE_CONTROL
MICROMODEM_HARDWARE_CONTROL_REPLY = mm_driver_pb2.MICROMODEM_HARDWARE_CONTROL_REPLY
MICROMODEM_GENERIC_LBL_RANGING = mm_driver_pb2.MICROMODEM_GENERIC_LBL_RANGING
MICROMODEM_FM_SWEEP = mm_driver_pb2.MICROMODEM_FM_SWEEP
MICROMODEM_M_SEQUENCE = mm_driver_pb2.MICROMODEM_M_SEQUENCE


def now_us(seconds: float) -> int:
    """Seconds since the epoch -> ModemTransmission time (microseconds)."""
    return round(seconds * 1e6)
