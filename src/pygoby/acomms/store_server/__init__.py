"""goby_store_server: a mailbox of ModemTransmissions kept in SQLite."""

from pygoby.acomms.store_server.server import StoreServer, serve_store
from pygoby.acomms.store_server.store import TransmissionStore

__all__ = ["StoreServer", "TransmissionStore", "serve_store"]
