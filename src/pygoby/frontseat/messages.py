"""Message classes and enum constants of the frontseat interface, from our .proto files.

The files live under src/pygoby/protobuf/goby/middleware/ at their goby3 import paths; this module
imports their generated modules (which register them in protobuf's default pool), together with
the drivers' extensions (the basic simulator's and Bluefin's Config extensions, Bluefin's
InterfaceData and CommandRequest extensions), so configuration text and messages using them parse.
"""

from __future__ import annotations

from pygoby.protobuf.goby.acomms.protobuf import modem_message_pb2
from pygoby.protobuf.goby.middleware.frontseat.bluefin import bluefin_config_pb2, bluefin_pb2
from pygoby.protobuf.goby.middleware.frontseat.simulator.basic import (
    basic_simulator_frontseat_driver_config_pb2 as basic_simulator_pb2,
)
from pygoby.protobuf.goby.middleware.protobuf import (
    frontseat_config_pb2,
    frontseat_data_pb2,
    frontseat_pb2,
    geographic_pb2,
)

PACKAGE = "goby.middleware.frontseat.protobuf"

LatLonPoint = geographic_pb2.LatLonPoint

Config = frontseat_config_pb2.Config
NodeStatus = frontseat_data_pb2.NodeStatus
CartesianCoordinate = frontseat_data_pb2.CartesianCoordinate
EulerAngles = frontseat_data_pb2.EulerAngles
Speed = frontseat_data_pb2.Speed
Source = frontseat_data_pb2.Source
DesiredCourse = frontseat_data_pb2.DesiredCourse
CTDSample = frontseat_data_pb2.CTDSample
InterfaceStatus = frontseat_pb2.InterfaceStatus
CommandRequest = frontseat_pb2.CommandRequest
CommandResponse = frontseat_pb2.CommandResponse
InterfaceData = frontseat_pb2.InterfaceData
Raw = frontseat_pb2.Raw
HelmStateReport = frontseat_pb2.HelmStateReport

BasicSimulatorFrontSeatConfig = basic_simulator_pb2.BasicSimulatorFrontSeatConfig
BASIC_SIMULATOR_CONFIG = basic_simulator_pb2.basic_simulator_config

BluefinConfig = bluefin_config_pb2.BluefinConfig
BluefinExtraData = bluefin_pb2.BluefinExtraData
BluefinExtraCommands = bluefin_pb2.BluefinExtraCommands
BuoyancyStatus = bluefin_pb2.BuoyancyStatus
TrimStatus = bluefin_pb2.TrimStatus
BLUEFIN_CONFIG = bluefin_config_pb2.bluefin_config
BLUEFIN_DATA = bluefin_pb2.bluefin_data
BLUEFIN_COMMAND = bluefin_pb2.bluefin_command
ModemRaw = modem_message_pb2.ModemRaw  # in BluefinExtraData

# Enum wrappers (`.Name(value)`, `.Value(name)`) and their values
InterfaceState = frontseat_pb2.InterfaceState
FrontSeatState = frontseat_pb2.FrontSeatState
HelmState = frontseat_pb2.HelmState
HelmError = frontseat_pb2.HelmError
FrontSeatError = frontseat_pb2.FrontSeatError
VehicleType = frontseat_data_pb2.VehicleType

INTERFACE_STANDBY = frontseat_pb2.INTERFACE_STANDBY
INTERFACE_LISTEN = frontseat_pb2.INTERFACE_LISTEN
INTERFACE_COMMAND = frontseat_pb2.INTERFACE_COMMAND
INTERFACE_HELM_ERROR = frontseat_pb2.INTERFACE_HELM_ERROR
INTERFACE_FS_ERROR = frontseat_pb2.INTERFACE_FS_ERROR

FRONTSEAT_NOT_CONNECTED = frontseat_pb2.FRONTSEAT_NOT_CONNECTED
FRONTSEAT_IDLE = frontseat_pb2.FRONTSEAT_IDLE
FRONTSEAT_ACCEPTING_COMMANDS = frontseat_pb2.FRONTSEAT_ACCEPTING_COMMANDS
FRONTSEAT_IN_CONTROL = frontseat_pb2.FRONTSEAT_IN_CONTROL

HELM_NOT_RUNNING = frontseat_pb2.HELM_NOT_RUNNING
HELM_DRIVE = frontseat_pb2.HELM_DRIVE
HELM_PARK = frontseat_pb2.HELM_PARK

ERROR_HELM_NONE = frontseat_pb2.ERROR_HELM_NONE
ERROR_HELM_NOT_RUNNING = frontseat_pb2.ERROR_HELM_NOT_RUNNING
ERROR_HELM_PARKED = frontseat_pb2.ERROR_HELM_PARKED

ERROR_FRONTSEAT_NONE = frontseat_pb2.ERROR_FRONTSEAT_NONE
ERROR_FRONTSEAT_NOT_CONNECTED = frontseat_pb2.ERROR_FRONTSEAT_NOT_CONNECTED
ERROR_FRONTSEAT_NOT_PROVIDING_DATA = frontseat_pb2.ERROR_FRONTSEAT_NOT_PROVIDING_DATA
ERROR_FRONTSEAT_IGNORING_COMMANDS = frontseat_pb2.ERROR_FRONTSEAT_IGNORING_COMMANDS


ERROR_STATES = frozenset({INTERFACE_HELM_ERROR, INTERFACE_FS_ERROR})
