"""The checks' window on the bus: one python-can bus, read by the check itself (no thread), every frame sent and
received kept with its time, so that a failed check can show the frames that make it fail.

Times are python-can's (``Message.timestamp``: the kernel's receive time on socketcan and udp_multicast), so a
heartbeat period is judged by when the frames reached the bus, not by when Python got round to reading them."""
from __future__ import annotations

import time
from dataclasses import dataclass
from collections import deque
from typing import Callable, Deque, Iterable, List, Optional

import can

#: How long after sending a frame its copy coming back is recognised (and dropped).
ECHO_S = 1.0


@dataclass(frozen=True)
class Frame:
    """A frame as seen: ``sent`` by the check, or received; ``time`` in seconds (python-can's clock)."""
    time: float
    can_id: int
    data: bytes
    sent: bool
    rtr: bool = False

    def describe(self, start: float = 0.0) -> str:
        """candump-like: ``  +0.012345  tx  605  [8]  40 00 10 00 00 00 00 00``."""
        body = "remote request" if self.rtr else " ".join(f"{b:02X}" for b in self.data)
        return f"{self.time - start:+11.6f}  {'tx' if self.sent else 'rx'}  {self.can_id:03X}  [{len(self.data)}]  {body}"


def describe_frames(frames: Iterable[Frame], limit: int = 40) -> str:
    """Frames one a line, times relative to the first; the last ``limit`` when there are more."""
    frames = list(frames)
    if not frames:
        return "(no frames)"
    start = frames[0].time
    shown = frames[-limit:]
    head = [f"... {len(frames) - len(shown)} earlier frame(s) left out"] if len(shown) < len(frames) else []
    return "\n".join(head + [f.describe(start) for f in shown])


class FrameLog:
    """A python-can bus with a record of its frames. ``relevant`` decides which frames a check's trace keeps
    (default: all); the record is cleared by ``start_trace()`` at the start of each check."""

    def __init__(self, bus: can.BusABC, relevant: Optional[Callable[[int], bool]] = None) -> None:
        self.bus = bus
        self.relevant = relevant or (lambda can_id: True)
        self.trace: List[Frame] = []
        # Frames this side sent in the last ECHO_S seconds: one received as sent (same ID, data, remote bit) is
        # this bus's own coming back (python-can's udp_multicast on loopback may deliver it) and is dropped.
        self._sent: Deque[Frame] = deque()

    def start_trace(self) -> None:
        """Throws away what is waiting (frames from before the check) and starts an empty record."""
        self.drain()
        self.trace = []

    def drain(self) -> None:
        while self.bus.recv(0.0) is not None:
            pass

    def send(self, can_id: int, data: bytes = b"", rtr: bool = False, dlc: Optional[int] = None) -> Frame:
        message = can.Message(arbitration_id=can_id, data=bytes(data), is_extended_id=False,
                              is_remote_frame=rtr, dlc=dlc if dlc is not None else len(data))
        sent_at = time.time()  # before the send: an answer's receive time stamp is then never earlier
        self.bus.send(message)
        frame = Frame(sent_at, can_id, bytes(data), True, rtr)
        self._sent.append(frame)
        self._keep(frame)
        return frame

    def recv(self, timeout: float) -> Optional[Frame]:
        """The next frame within timeout seconds (recorded), or None. Error frames and extended frames are read and
        left out: CANopen's frames are 11-bit."""
        deadline = time.monotonic() + timeout
        while True:
            left = max(0.0, deadline - time.monotonic())
            message = self.bus.recv(left)
            if message is None:
                return None
            if message.is_error_frame or message.is_extended_id:
                continue
            frame = Frame(message.timestamp or time.time(), message.arbitration_id, bytes(message.data), False,
                          message.is_remote_frame)
            if self._is_echo(frame):
                continue
            self._keep(frame)
            return frame

    def wait_for(self, match: Callable[[Frame], bool], timeout: float) -> Optional[Frame]:
        """The first received frame within timeout seconds that ``match`` takes (every frame read is recorded)."""
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            frame = self.recv(left)
            if frame is not None and match(frame):
                return frame

    def collect(self, match: Callable[[Frame], bool], duration: float) -> List[Frame]:
        """Every received frame that ``match`` takes during ``duration`` seconds."""
        found = []
        deadline = time.monotonic() + duration
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                return found
            frame = self.recv(left)
            if frame is not None and match(frame):
                found.append(frame)

    def _is_echo(self, frame: Frame) -> bool:
        now = time.time()
        while self._sent and now - self._sent[0].time > ECHO_S:
            self._sent.popleft()
        for sent in self._sent:
            if (sent.can_id, sent.data, sent.rtr) == (frame.can_id, frame.data, frame.rtr):
                self._sent.remove(sent)
                return True
        return False

    def _keep(self, frame: Frame) -> None:
        if self.relevant(frame.can_id):
            self.trace.append(frame)
