"""Micro-Modem application acknowledgements (`use_application_acks`).

Acks travel in software, as an MMApplicationAck DCCL message (id 10) at the start of frame 0:
one part per peer we owe acks to, with a bitmask of its Goby frame numbers (0-31), plus our own
`frame_start` and whether we want our frames acknowledged. Needed for FDP, whose firmware ack
field is always 0, and usable with every data rate.
"""

from __future__ import annotations

import logging
from typing import cast

from pygoby.acomms import messages as acomms_pb
from pygoby.dccl import Codec, DcclError

log = logging.getLogger(__name__)

MAX_FRAME_NUMBER = 32
MMApplicationAck = acomms_pb.MMApplicationAck


class ApplicationAcks:
    def __init__(self, ack_ids: set[int]) -> None:
        self.ack_ids = ack_ids
        self.codec = Codec()
        self.codec.load(MMApplicationAck)
        self.dccl_id = self.codec.compiled(MMApplicationAck).id
        self.owed: dict[int, int] = {}  # peer id -> bitmask of its frames we must ack
        self.frame_counter = 0

    # ------------------------------------------------------------------ sending
    def _ack_message(self, frame_start: int, ack_requested: bool):
        ack = MMApplicationAck(frame_start=frame_start, ack_requested=ack_requested)
        for peer, mask in sorted(self.owed.items())[:4]:
            ack.part.add(ack_dest=peer, acked_frames=mask)
        return ack

    def prepare(self, msg: acomms_pb.ModemTransmission) -> int:
        """Before the data request: number the frames and reserve room for the ack at the start
        of frame 0. Returns the placeholder's size."""
        if self.frame_counter + msg.max_num_frames > MAX_FRAME_NUMBER:
            self.frame_counter = 0
        msg.frame_start = self.frame_counter
        placeholder = len(self.codec.encode(self._ack_message(msg.frame_start, False)))
        if msg.frame:  # frames given with the request keep their content after the ack
            msg.frame[0] = b"\0" * placeholder + bytes(msg.frame[0])
        else:
            msg.frame.append(b"\0" * placeholder)
        return placeholder

    def finish(self, msg: acomms_pb.ModemTransmission, placeholder: int) -> bool:
        """After the data request: write the real ack; False if there is nothing to send."""
        has_data = len(msg.frame[0]) > placeholder or any(msg.frame[1:])
        if not has_data and not self.owed:
            return False
        if msg.dest < 0:
            msg.dest = acomms_pb.BROADCAST_ID
        ack = self.codec.encode(self._ack_message(msg.frame_start, msg.ack_requested))
        msg.frame[0] = ack + bytes(msg.frame[0])[placeholder:]
        self.owed.clear()
        self.frame_counter += len(msg.frame)
        return True

    # ------------------------------------------------------------------ receiving
    def strip(self, msg: acomms_pb.ModemTransmission) -> list:
        """Remove the ack from a received transmission's frame 0, remember what we owe the
        sender and return the ACK transmissions it carries for us."""
        if not msg.frame or not msg.frame[0]:
            return []
        data = bytes(msg.frame[0])
        try:
            if self.codec.id(data) != self.dccl_id:
                return []
            decoded, used = self.codec.decode_prefix(data)
            ack = cast(acomms_pb.MMApplicationAck, decoded)  # (the id checked above is its)
        except DcclError as exc:
            log.warning("cannot decode an application ack: %s", exc)
            return []
        msg.frame[0] = data[used:]
        if msg.dest in self.ack_ids and ack.ack_requested:
            bad = set(msg.Extensions[acomms_pb.MM_TRANSMISSION].frame_with_bad_crc)
            for i in range(len(msg.frame)):
                if i not in bad:
                    self.owed[msg.src] = self.owed.get(msg.src, 0) | 1 << (ack.frame_start + i)
        acks = []
        for part in ack.part:
            if part.ack_dest not in self.ack_ids:
                continue
            for j in range(MAX_FRAME_NUMBER):
                if part.acked_frames >> j & 1:
                    acks.append(
                        acomms_pb.ModemTransmission(
                            type=acomms_pb.ACK, src=msg.src, dest=part.ack_dest, acked_frame=[j]
                        )
                    )
        return acks
