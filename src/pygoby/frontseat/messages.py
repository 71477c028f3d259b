"""Message classes and enum constants of the frontseat interface, from our .proto files.

The files live under src/pygoby/protobuf/goby/middleware/ at their goby3 import paths; this module
loads them once into the process-wide pool, together with the drivers' extensions (the basic
simulator's and Bluefin's Config extensions, Bluefin's InterfaceData and CommandRequest extensions),
so configuration text and messages using them parse.
"""

from __future__ import annotations

from google.protobuf.internal.enum_type_wrapper import EnumTypeWrapper

from pygoby.protobuf import default_loader

PACKAGE = "goby.middleware.frontseat.protobuf"

_PROTO_FILES = (
    "goby/middleware/protobuf/geographic.proto",
    "goby/middleware/protobuf/frontseat_data.proto",
    "goby/middleware/protobuf/frontseat.proto",
    "goby/middleware/protobuf/frontseat_config.proto",
    "goby/middleware/frontseat/simulator/basic/basic_simulator_frontseat_driver_config.proto",
    "goby/middleware/frontseat/bluefin/bluefin.proto",
    "goby/middleware/frontseat/bluefin/bluefin_config.proto",
)

_loader = default_loader()
for _name in _PROTO_FILES:
    _loader.load_file(_name)


def _cls(name: str):
    return _loader.message_class(f"{PACKAGE}.{name}")


def _enum(name: str) -> EnumTypeWrapper:
    return EnumTypeWrapper(_loader.pool.FindEnumTypeByName(f"{PACKAGE}.{name}"))


LatLonPoint = _loader.message_class("goby.middleware.protobuf.LatLonPoint")

Config = _cls("Config")
NodeStatus = _cls("NodeStatus")
CartesianCoordinate = _cls("CartesianCoordinate")
EulerAngles = _cls("EulerAngles")
Speed = _cls("Speed")
Source = _cls("Source")
DesiredCourse = _cls("DesiredCourse")
CTDSample = _cls("CTDSample")
InterfaceStatus = _cls("InterfaceStatus")
CommandRequest = _cls("CommandRequest")
CommandResponse = _cls("CommandResponse")
InterfaceData = _cls("InterfaceData")
Raw = _cls("Raw")
HelmStateReport = _cls("HelmStateReport")

BasicSimulatorFrontSeatConfig = _cls("BasicSimulatorFrontSeatConfig")
BASIC_SIMULATOR_CONFIG = _loader.pool.FindExtensionByName(f"{PACKAGE}.basic_simulator_config")

BluefinConfig = _cls("BluefinConfig")
BluefinExtraData = _cls("BluefinExtraData")
BluefinExtraCommands = _cls("BluefinExtraCommands")
BuoyancyStatus = _cls("BuoyancyStatus")
TrimStatus = _cls("TrimStatus")
BLUEFIN_CONFIG = _loader.pool.FindExtensionByName(f"{PACKAGE}.bluefin_config")
BLUEFIN_DATA = _loader.pool.FindExtensionByName(f"{PACKAGE}.bluefin_data")
BLUEFIN_COMMAND = _loader.pool.FindExtensionByName(f"{PACKAGE}.bluefin_command")
ModemRaw = _loader.message_class("goby.acomms.protobuf.ModemRaw")  # in BluefinExtraData

# Enum wrappers (`.Name(value)`, `.Value(name)`) and their values as plain ints.
InterfaceState = _enum("InterfaceState")
FrontSeatState = _enum("FrontSeatState")
HelmState = _enum("HelmState")
HelmError = _enum("HelmError")
FrontSeatError = _enum("FrontSeatError")
VehicleType = _enum("VehicleType")

INTERFACE_STANDBY: int = InterfaceState.INTERFACE_STANDBY
INTERFACE_LISTEN: int = InterfaceState.INTERFACE_LISTEN
INTERFACE_COMMAND: int = InterfaceState.INTERFACE_COMMAND
INTERFACE_HELM_ERROR: int = InterfaceState.INTERFACE_HELM_ERROR
INTERFACE_FS_ERROR: int = InterfaceState.INTERFACE_FS_ERROR

FRONTSEAT_NOT_CONNECTED: int = FrontSeatState.FRONTSEAT_NOT_CONNECTED
FRONTSEAT_IDLE: int = FrontSeatState.FRONTSEAT_IDLE
FRONTSEAT_ACCEPTING_COMMANDS: int = FrontSeatState.FRONTSEAT_ACCEPTING_COMMANDS
FRONTSEAT_IN_CONTROL: int = FrontSeatState.FRONTSEAT_IN_CONTROL

HELM_NOT_RUNNING: int = HelmState.HELM_NOT_RUNNING
HELM_DRIVE: int = HelmState.HELM_DRIVE
HELM_PARK: int = HelmState.HELM_PARK

ERROR_HELM_NONE: int = HelmError.ERROR_HELM_NONE
ERROR_HELM_NOT_RUNNING: int = HelmError.ERROR_HELM_NOT_RUNNING
ERROR_HELM_PARKED: int = HelmError.ERROR_HELM_PARKED

ERROR_FRONTSEAT_NONE: int = FrontSeatError.ERROR_FRONTSEAT_NONE
ERROR_FRONTSEAT_NOT_CONNECTED: int = FrontSeatError.ERROR_FRONTSEAT_NOT_CONNECTED
ERROR_FRONTSEAT_NOT_PROVIDING_DATA: int = FrontSeatError.ERROR_FRONTSEAT_NOT_PROVIDING_DATA
ERROR_FRONTSEAT_IGNORING_COMMANDS: int = FrontSeatError.ERROR_FRONTSEAT_IGNORING_COMMANDS

ERROR_STATES = frozenset({INTERFACE_HELM_ERROR, INTERFACE_FS_ERROR})
