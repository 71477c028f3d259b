"""Our .proto files (under their upstream import paths) and the run-time .proto loader."""

from pygoby.protobuf.loader import (
    BUILTIN_PROTO_DIR,
    ProtoError,
    ProtoLoader,
    builtin_class,
    class_of,
    default_loader,
    enum_type,
    initialization_errors,
    message_type,
)

__all__ = [
    "BUILTIN_PROTO_DIR",
    "ProtoError",
    "ProtoLoader",
    "builtin_class",
    "class_of",
    "default_loader",
    "enum_type",
    "initialization_errors",
    "message_type",
]
