"""Priority queuing of DCCL messages for the acoustic link."""

from pygoby.acomms.errors import QueueError
from pygoby.acomms.queue.manager import QueueManager
from pygoby.acomms.queue.queue import MessageQueue, QueuedItem

__all__ = ["MessageQueue", "QueueError", "QueueManager", "QueuedItem"]
