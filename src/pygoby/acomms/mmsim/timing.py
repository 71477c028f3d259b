"""How long things take on a WHOI Micro-Modem: the emulator's duration table.

One table serves every channel: the emulator computes each packet's time on the water from it
(`AcousticPacket.duration`) and the plain channels and the netsim physics use that duration.
Figures and their confidence (WHOI's published rate tables):

* rate 0 (FH-FSK, 1 x 32 bytes): WHOI gives 80 bit/s as its burst rate, defined as user bytes over
  the whole packet time: 32 * 8 / 80 = 3.2 s on the water. KNOWN (WHOI).
* rate 6 (PSK, 6 x 32 bytes): WHOI's rate table: 2.95 s of packet, 3.25 s of signal with the
  probe and the null before it, so 0.30 s precede the frames and each frame takes 2.95 / 6 s.
  KNOWN (WHOI).
* rate 5 (PSK, 8 x 256 bytes): "~5000 bps" burst rate: 2048 * 8 / 5000 = 3.28 s in all. DERIVED.
* rates 1-4 (PSK, 3 x 64 / 2 x 256 bytes): durations are not published in any source available
  here. ESTIMATE: a full packet takes 3.25 s like rate 6.
* PSK probe and null before the frames: 0.30 s. KNOWN for rate 6, ESTIMATE for rates 1-5. A
  packet with fewer frames than the rate allows is shorter by the missing frames' time.
* mini-packets (the rate-0 cycle-init, acknowledgements, $CCMUC user mini-packets, hardware
  control, FDP pings): 1.0 s. ESTIMATE (Goby 1.1 manual: cycle-init packets take about 1 s).
* two-way ping and its reply ($CCMPC): 0.5 s each. ESTIMATE (the figure ros_acomms uses).
* LBL interrogation pings ($CCPDT, $CCPGT): 10 ms; $CCPNT gives its own length. ESTIMATE.
* $CATMQ comes 0.5 s after $CCTMQ and reports the time at the query. KNOWN (goby3 driver: "the
  Micro-Modem takes 0.5 second to respond to TMQ").
* the host's serial line: 19200 baud, 10 bits a character (goby3's default for the Micro-Modem;
  NVRAM BR1 3). KNOWN. A packet goes on the water once the host's sentences that make it
  ($CCCYC, each $CADRQ and $CCTXD, $CCMPC, ...) have crossed the line: a rate-0 frame's $CADRQ
  and $CCTXD take about 60 ms, a full rate-5 packet's about 2.3 s. (The modem's own output is
  not paced.)
* the ping reply leaves the turnaround time TAT (NVRAM, default 50 ms) after the ping has been
  heard; the pinging modem reports ((reply arrival - ping start) - ping length - its own TAT) / 2.
  TAT default: ESTIMATE (goby's REMUS LBL default turnaround).
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class RateTiming:
    """A rate's packet: `lead` seconds (probe, null) and then `per_frame` seconds per frame."""

    frames: int
    frame_bytes: int
    lead: float
    per_frame: float

    def duration(self, frames: int) -> float:
        return self.lead + max(1, min(frames, self.frames)) * self.per_frame

    @property
    def max_bytes(self) -> int:
        return self.frames * self.frame_bytes


PSK_LEAD = 0.30  # s of probe and null before the frames of a PSK packet
PSK_FULL_PACKET = 3.25  # s: rate 6's whole signal (KNOWN), rates 1-4's (ESTIMATE)

DEFAULT_RATES = {
    0: RateTiming(1, 32, 0.0, 32 * 8 / 80),
    1: RateTiming(3, 64, PSK_LEAD, (PSK_FULL_PACKET - PSK_LEAD) / 3),
    2: RateTiming(3, 64, PSK_LEAD, (PSK_FULL_PACKET - PSK_LEAD) / 3),
    3: RateTiming(2, 256, PSK_LEAD, (PSK_FULL_PACKET - PSK_LEAD) / 2),
    4: RateTiming(2, 256, PSK_LEAD, (PSK_FULL_PACKET - PSK_LEAD) / 2),
    5: RateTiming(8, 256, PSK_LEAD, (2048 * 8 / 5000 - PSK_LEAD) / 8),
    6: RateTiming(6, 32, PSK_LEAD, 2.95 / 6),
}
# Flexible Data Protocol data rates and their payloads (pyacomms' FDPDataRates: the only source)
FDP_RATES = (1, 3, 5)


@dataclass(frozen=True)
class ModemTiming:
    """The emulator's durations (s). Change any of them to model another modem or firmware."""

    rates: dict[int, RateTiming] = field(default_factory=lambda: dict(DEFAULT_RATES))
    mini_packet: float = 1.0
    ping: float = 0.5
    nav_ping: float = 0.010
    tmq_reply: float = 0.5
    baud: int = 19200  # (0: the host's sentences take no time)

    def data(self, rate: int, frames: int) -> float:
        return self.rates[rate].duration(frames)


DEFAULT_TIMING = ModemTiming()
