"""Shared-secret authentication of store-server requests (a pygoby addition: upstream's
store-server has none: any client could read and consume another modem's mail by sending its modem
id).

A driver with a secret appends `auth_time` and, last, `auth_hmac` = HMAC-SHA256(secret, every
byte before it) to its request. The server with a secret for that modem id answers only a
request whose HMAC matches, whose time is within its window, and which is newer than the last
one it accepted for the id (a recorded request cannot be replayed). The secret never travels;
the mail itself does, in clear: use a VPN or SSH tunnel where the network is not trusted.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import stat

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.errors import StoreServerAuthError
from pygoby.errors import ConfigError

# room the two fields take in a request: auth_time (key + 8 bytes) and auth_hmac (key, length,
# 32 bytes), rounded up
AUTH_BYTES = 64


def sign_request(payload: bytes, secret: bytes, now: float) -> bytes:
    signed = payload + acomms_pb.StoreServerRequestAuth(auth_time=now).SerializeToString()
    tag = hmac.new(secret, signed, hashlib.sha256).digest()
    return signed + acomms_pb.StoreServerRequestAuth(auth_hmac=tag).SerializeToString()


def verify_request(payload: bytes, secret: bytes) -> float:
    """The request's auth_time if it is signed with `secret`; StoreServerAuthError otherwise."""
    auth = acomms_pb.StoreServerRequestAuth.FromString(
        payload
    )  # the other fields are unknown to it
    if not (auth.HasField("auth_hmac") and auth.HasField("auth_time")):
        raise StoreServerAuthError("the request is not signed")
    tail = acomms_pb.StoreServerRequestAuth(auth_hmac=auth.auth_hmac).SerializeToString()
    if not payload.endswith(tail):
        raise StoreServerAuthError("the signature is not the request's last field")
    expected = hmac.new(secret, payload[: -len(tail)], hashlib.sha256).digest()
    if not hmac.compare_digest(expected, auth.auth_hmac):
        raise StoreServerAuthError("wrong signature")
    return auth.auth_time


def read_secret_file(path: str | os.PathLike[str]) -> bytes:
    """A driver's secret: the first line of the file."""
    try:
        with open(path, "rb") as file:
            secret = file.readline().rstrip(b"\r\n")
    except OSError as exc:
        raise ConfigError(exc.strerror or str(exc), file=path) from None
    if not secret:
        raise ConfigError("the secret is empty", file=path, line=1)
    return secret


def read_secrets(path: str | os.PathLike[str], allow_readable: bool = False) -> dict[int, bytes]:
    """The server's secrets: one `MODEM_ID SECRET` per line (# comments, blank lines).

    A file that its group or others may read or write is refused unless `allow_readable`
    (as ssh refuses such a private key): anyone who can read it can sign as every modem."""
    try:
        with open(path, "rb") as file:
            mode = os.fstat(file.fileno()).st_mode
            lines = file.read().split(b"\n")
    except OSError as exc:
        raise ConfigError(exc.strerror or str(exc), file=path) from None
    if mode & (stat.S_IRWXG | stat.S_IRWXO) and not allow_readable:
        raise ConfigError(
            f"permissions {stat.S_IMODE(mode):04o} let others than its owner use it "
            f"(chmod 600 {os.fspath(path)}, or --allow-readable-secrets)",
            file=path,
        )
    secrets: dict[int, bytes] = {}
    for number, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line or line.startswith(b"#"):
            continue
        modem_id, _, secret = line.partition(b" ")
        secret = secret.strip()
        if not modem_id.isdigit() or not secret:
            raise ConfigError("expected MODEM_ID SECRET", file=path, line=number)
        if int(modem_id) in secrets:
            raise ConfigError(f"modem id {int(modem_id)} listed twice", file=path, line=number)
        secrets[int(modem_id)] = secret
    return secrets
