"""Load protobuf message definitions from .proto files at run time.

protoc (from grpcio-tools, in process) compiles users' files into a FileDescriptorSet, which is
added to a descriptor pool; message classes are then made from the pool. Our own .proto files live
in this folder under their upstream import paths ("dccl/option_extensions.proto", ...), and this
folder is always on the include path, so users' files that import them compile unchanged.

Our own files are also compiled at build time into `_pb2` modules beside them (see generate.py),
which register them in protobuf's default pool. The default loader works on that pool and imports
those modules instead of running protoc on our files, so a user's file loaded there that imports
ours gets the very classes pygoby's code uses.
"""

from __future__ import annotations

import functools
import importlib
import os
import tempfile
from collections.abc import Iterable, Sequence
from importlib import resources
from pathlib import Path
from typing import IO

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from google.protobuf.descriptor import Descriptor, FileDescriptor
from google.protobuf.message import Message

from pygoby.errors import PygobyError
from pygoby.protobuf.descriptors import AnyDescriptor, AnyEnumDescriptor, AnyFieldDescriptor

BUILTIN_PROTO_DIR = Path(__file__).resolve().parent


class ProtoError(PygobyError):
    """A .proto file could not be compiled or a message type could not be found (the root of
    the protobuf package's errors)."""


@functools.cache
def _well_known_include_dir() -> str:
    return str(resources.files("grpc_tools") / "_proto")


def builtin_module_name(name: str) -> str:
    """The generated module of our .proto import name ("goby/acomms/protobuf/queue.proto" ->
    "pygoby.protobuf.goby.acomms.protobuf.queue_pb2")."""
    return f"{__package__}.{name.removesuffix('.proto').replace('/', '.')}_pb2"


def is_builtin(name: str) -> bool:
    """Whether `name` is the import name of one of our own .proto files."""
    return name.endswith(".proto") and (BUILTIN_PROTO_DIR / name).is_file()


def import_builtin(name: str) -> FileDescriptor:
    """Our .proto file `name`, registered in the default pool by its generated module."""
    try:
        module = importlib.import_module(builtin_module_name(name))
    except ModuleNotFoundError as err:
        raise ProtoError(
            f"the generated module of {name} is missing ({err}): run "
            "`python -m pygoby.protobuf.generate` or reinstall pygoby"
        ) from None
    descriptor: FileDescriptor = module.DESCRIPTOR
    return descriptor


class ProtoLoader:
    """Compiles .proto files into one descriptor pool and hands out message classes.

    Loading the same file twice is free; two different files with the same import name are an
    error (protobuf's pools are keyed by file name).
    """

    def __init__(
        self,
        include_dirs: Iterable[str | os.PathLike[str]] = (),
        pool: descriptor_pool.DescriptorPool | None = None,
    ) -> None:
        self.include_dirs: list[Path] = [Path(d).resolve() for d in include_dirs]
        self.pool = pool if pool is not None else descriptor_pool.DescriptorPool()
        # What we added, as compiled: a descriptor copied back out of the pool is not always
        # byte-identical (e.g. an aliased enum default comes back under its other name).
        self._added: dict[str, bytes] = {}
        # our own files come from their generated modules when they go to protobuf's default pool
        self._uses_generated = self.pool is descriptor_pool.Default()

    def add_include_dir(self, directory: str | os.PathLike[str]) -> None:
        resolved = Path(directory).resolve()
        if resolved not in self.include_dirs:
            self.include_dirs.append(resolved)

    def _search_path(self, extra: Sequence[Path]) -> list[str]:
        dirs = [*extra, *self.include_dirs, BUILTIN_PROTO_DIR]
        unique = list(dict.fromkeys(str(d) for d in dirs))
        return [*unique, _well_known_include_dir()]

    def import_path(self) -> list[str]:
        """The folders import names are looked up in (the include dirs, then our own .proto
        folder and protobuf's well-known types)."""
        return self._search_path([])

    def on_import_path(self, name: str) -> bool:
        """Whether `name` is a .proto import name found on the import path."""
        return any((Path(d) / name).is_file() for d in self.import_path())

    def _import_name(self, path: Path, search: Sequence[str]) -> str | None:
        for directory in search:
            try:
                return path.relative_to(directory).as_posix()
            except ValueError:
                continue
        return None

    def load_file(
        self, path: str | os.PathLike[str], include_dirs: Iterable[str | os.PathLike[str]] = ()
    ) -> FileDescriptor:
        """Compile `path` (and its imports) into the pool; returns its FileDescriptor.

        `path` may be a file on disk or an import name found on the include path.
        """
        extra = [Path(d).resolve() for d in include_dirs]
        candidate = Path(path)
        search = self._search_path(extra)
        if candidate.is_file():
            resolved = candidate.resolve()
            name = self._import_name(resolved, search)
            if name is None:
                # Not under any include dir: its own directory becomes one (as protoc users do).
                extra.append(resolved.parent)
                search = self._search_path(extra)
                name = resolved.name
        else:
            name = candidate.as_posix()
            if self._uses_generated and is_builtin(name):
                return import_builtin(name)
            if not any((Path(d) / name).is_file() for d in search):
                raise ProtoError(f"cannot find .proto file {str(path)!r} (searched {search})")
        try:
            return self.pool.FindFileByName(name)
        except KeyError:
            pass
        for file_proto in self._compile(name, search):
            self._add(file_proto)
        return self.pool.FindFileByName(name)

    def _compile(
        self, name: str, search: Sequence[str]
    ) -> list[descriptor_pb2.FileDescriptorProto]:
        from grpc_tools import protoc  # imported lazily: it is slow to import

        with tempfile.TemporaryDirectory(prefix="pygoby-protoc-") as tmp:
            out = os.path.join(tmp, "set.pb")
            args = ["protoc", *(f"-I{d}" for d in search)]
            args += [f"--descriptor_set_out={out}", "--include_imports", name]
            with _CapturedStderr() as err:
                status = protoc.main(args)
            if status != 0:
                raise ProtoError(f"protoc failed on {name}:\n{err.read().strip()}")
            fds = descriptor_pb2.FileDescriptorSet()
            fds.ParseFromString(Path(out).read_bytes())
        return list(fds.file)

    def _add(self, file_proto: descriptor_pb2.FileDescriptorProto) -> None:
        if self._uses_generated and is_builtin(file_proto.name):
            import_builtin(file_proto.name)
            return
        compiled = file_proto.SerializeToString(deterministic=True)
        try:
            self.pool.FindFileByName(file_proto.name)
        except KeyError:
            self.pool.Add(file_proto)
            self._added[file_proto.name] = compiled
            return
        known = self._added.get(file_proto.name)
        if known is not None and known != compiled:
            raise ProtoError(f"{file_proto.name} is already loaded with a different definition")

    def add_file_proto(self, file_proto: descriptor_pb2.FileDescriptorProto) -> FileDescriptor:
        """Add a file built in memory (its imports are loaded first, by import name)."""
        for dependency in file_proto.dependency:
            self.load_file(dependency)
        try:
            self._add(file_proto)
            return self.pool.FindFileByName(file_proto.name)
        except (TypeError, KeyError) as err:  # the pool refuses a malformed descriptor
            raise ProtoError(f"cannot add {file_proto.name}: {err}") from None

    def find_descriptor(self, full_name: str) -> Descriptor:
        try:
            return self.pool.FindMessageTypeByName(full_name)
        except KeyError:
            raise ProtoError(f"unknown message type {full_name!r}") from None

    def message_class(self, full_name: str) -> type[Message]:
        return message_factory.GetMessageClass(self.find_descriptor(full_name))

    def load_files(
        self,
        paths: Iterable[str | os.PathLike[str]],
        include_dirs: Iterable[str | os.PathLike[str]] = (),
    ) -> list[FileDescriptor]:
        dirs = list(include_dirs)
        return [self.load_file(p, dirs) for p in paths]


class _CapturedStderr:
    """protoc writes its diagnostics to fd 2; capture them for the error message."""

    def __enter__(self) -> IO[str]:
        self._file = tempfile.TemporaryFile(mode="w+")
        self._saved = os.dup(2)
        os.dup2(self._file.fileno(), 2)
        return self._file

    def __exit__(self, *exc: object) -> None:
        os.dup2(self._saved, 2)
        os.close(self._saved)
        self._file.seek(0)


@functools.cache
def default_loader() -> ProtoLoader:
    """The process-wide loader used for pygoby's own messages and configs: on protobuf's default
    pool, where the generated modules of our .proto files register them."""
    return ProtoLoader(pool=descriptor_pool.Default())


def builtin_class(proto_file: str, full_name: str) -> type[Message]:
    """A message class from one of our own .proto files (loaded on first use)."""
    loader = default_loader()
    loader.load_file(proto_file)
    return loader.message_class(full_name)


def enum_type(field: AnyFieldDescriptor) -> AnyEnumDescriptor:
    """The enum type of an enum field (protobuf types it as optional: None for other fields)."""
    if field.enum_type is None:
        raise ProtoError(f"{field.full_name} is not an enum field")
    return field.enum_type


def message_type(field: AnyFieldDescriptor) -> AnyDescriptor:
    """The message type of a message field (protobuf types it as optional: None for others)."""
    if field.message_type is None:
        raise ProtoError(f"{field.full_name} is not a message field")
    return field.message_type


def initialization_errors(message: Message) -> list[str]:
    """Paths of the required fields `message` lacks ("node[0].track.speed"), as protobuf's
    FindInitializationErrors gives them (a method its type stubs leave out)."""
    errors: list[str] = message.FindInitializationErrors()  # type: ignore[attr-defined]
    return errors


def class_of(descriptor: AnyDescriptor) -> type[Message]:
    """The message class of a descriptor of any pool (protobuf's stubs take only the
    pure-Python descriptor type)."""
    return message_factory.GetMessageClass(descriptor)  # type: ignore[arg-type]
