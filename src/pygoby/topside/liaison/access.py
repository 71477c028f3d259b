"""Who may use liaison's pages, and where the Commander page may save (sans-I/O: fed request
headers and names, answers with a refusal or a path).

Three rules, checked on every request before any handler runs:

* Host: the request must name the server by the address it is bound to (or, on loopback,
  `localhost`), by an IP literal or this machine's host name when it listens on every address,
  or by a name listed in `allowed_host`. A page on another domain that re-points its DNS name at this machine (DNS
  rebinding) sends its own name in Host, so it is refused before it can read or send anything.
* Origin: a request that carries an Origin header must come from a page of this server.
* Token: a random token is made at every launch and printed in the URL at start-up (as Jupyter
  does). Requests that change something (POST) need it, wherever the server listens; off loopback
  every request needs it. The page keeps it as a cookie set from the printed URL's `?token=`
  (HttpOnly, SameSite=Strict, named after the port so that two liaisons on one host keep theirs);
  scripts may send `Authorization: Bearer TOKEN` instead.
"""

from __future__ import annotations

import hmac
import ipaddress
import socket
from collections.abc import Iterable, Mapping
from pathlib import Path
from urllib.parse import parse_qs, urlsplit

from pygoby.topside.errors import SaveFileError

WILDCARD_ADDRESSES = ("0.0.0.0", "::", "")


def is_loopback(address: str) -> bool:
    if address in ("localhost", ""):
        return address == "localhost"
    try:
        return ipaddress.ip_address(address).is_loopback
    except ValueError:
        return False


def _host_name(host: str) -> str:
    """`Host`/Origin authority without its port, brackets and case: `[::1]:80` -> `::1`."""
    host = host.strip().lower()
    if host.startswith("["):
        return host[1 : host.find("]")] if "]" in host else host
    return host.rsplit(":", 1)[0] if host.count(":") == 1 else host


def _is_ip(name: str) -> bool:
    try:
        ipaddress.ip_address(name)
    except ValueError:
        return False
    return True


class Access:
    """The Host, Origin and token rules for a server bound to `address` with `token`."""

    def __init__(self, address: str, token: str, port: int, allowed_hosts: Iterable[str] = ()):
        self.token = token
        self.loopback = is_loopback(address)
        self.any_address = address in WILDCARD_ADDRESSES
        self.names = {_host_name(address), *(_host_name(h) for h in allowed_hosts)}
        if self.loopback:
            self.names |= {"localhost", "127.0.0.1", "::1"}
        if self.any_address:  # this machine's own names (another site cannot take them over)
            self.names |= {socket.gethostname().lower(), socket.getfqdn().lower()}
        self.cookie = f"liaison_token_{port}"

    def host_allowed(self, host: str) -> bool:
        name = _host_name(host)
        # an IP literal cannot be re-pointed by DNS: any of them reaches a wildcard bind
        return name in self.names or (self.any_address and _is_ip(name))

    def origin_allowed(self, origin: str | None) -> bool:
        if origin is None:
            return True
        parts = urlsplit(origin)
        return parts.scheme in ("http", "https") and self.host_allowed(parts.netloc)

    def offered_token(
        self, headers: Mapping[str, str], query: str, cookies: Mapping[str, str]
    ) -> str:
        from_query = parse_qs(query).get("token", [""])[0]
        bearer = headers.get("authorization", "")
        return (
            from_query
            or cookies.get(self.cookie, "")
            or (bearer.removeprefix("Bearer ") if bearer.startswith("Bearer ") else "")
        )

    def token_ok(self, offered: str) -> bool:
        return bool(offered) and hmac.compare_digest(offered.encode(), self.token.encode())

    def refusal(
        self,
        method: str,
        headers: Mapping[str, str],
        query: str,
        cookies: Mapping[str, str],
    ) -> tuple[int, str] | None:
        """(status, reason) when the request is refused, None when it may go on. `headers`
        with lower-case names."""
        if not self.host_allowed(headers.get("host", "")):
            return 403, "liaison: this server is not reachable under that Host name"
        if not self.origin_allowed(headers.get("origin")):
            return 403, "liaison: requests from other sites' pages are refused"
        changes_state = method not in ("GET", "HEAD")
        if (changes_state or not self.loopback) and not self.token_ok(
            self.offered_token(headers, query, cookies)
        ):
            return 401, "liaison: access token required (open the URL printed at start-up)"
        if changes_state and headers.get("x-liaison") != "1":
            # a page from another site cannot add this header without a CORS permission
            return 403, "liaison: POST without the X-Liaison header"
        return None


class SaveFolder:
    """The one folder the Commander page saves to and loads from. Names are relative paths
    inside it; `..`, absolute paths and links that lead out are refused with one error text,
    whether or not what they name exists (so a refusal tells nothing about the server's
    files)."""

    REFUSED = "save files are names inside liaison's save folder (no '..', no absolute path)"

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)

    def path(self, name: str) -> Path:
        parts = Path(name).parts
        if not name or "\0" in name or Path(name).is_absolute() or ".." in parts or not parts:
            raise SaveFileError(self.REFUSED)
        root = self.folder.resolve()
        path = (root / name).resolve()
        if path == root or not path.is_relative_to(root):
            raise SaveFileError(self.REFUSED)  # a symbolic link inside that leads out
        return path

    def for_saving(self, name: str) -> Path:
        path = self.path(name)
        path.parent.mkdir(parents=True, exist_ok=True)
        return path
