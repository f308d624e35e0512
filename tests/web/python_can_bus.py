"""The test's fake bus (tests/native/test_emulator_native.py FakeBus) as a python-can bus, so that a python-canopen
master (canopen.Network(bus=...)) talks to the nodes of canopen-emu-fakecan: what it sends goes onto the fake bus,
the frames the nodes send come to it. It takes the frames from FakeBus.frames: while it runs, nothing else should."""

import queue

import can


class FakeCanBus(can.BusABC):
    def __init__(self, fake_bus, **kwargs):
        self._fake = fake_bus
        super().__init__(channel="fakecan0", **kwargs)
        self.channel_info = "the test's fake CAN bus"

    def send(self, msg, timeout=None):
        self._fake.send(msg.arbitration_id, msg.data)

    def _recv_internal(self, timeout):
        try:
            t, can_id, data = self._fake.frames.get(timeout=timeout)
        except queue.Empty:
            return None, False
        return can.Message(timestamp=t, arbitration_id=can_id, data=data, is_extended_id=False), False
