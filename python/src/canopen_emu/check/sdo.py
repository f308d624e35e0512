"""A small SDO client (CiA 301 §7.2.4) that builds every frame itself, so that the checks can send what a library
would refuse to (a wrong toggle bit, an unknown command specifier) and show the exact frames of a failed transfer.

Each request waits for the answer on the server's COB-ID; other frames read meanwhile are recorded by the FrameLog
and skipped. ``SdoAbort`` (the server aborted), ``SdoTimeout`` (no answer) and ``SdoProtocolError`` (an answer
that breaks the protocol) carry the frames of the transfer."""
from __future__ import annotations

import struct
from typing import List, Optional, Tuple

from .frames import Frame, FrameLog

#: CiA 301 §7.2.4.3.17, table 22: the SDO abort codes.
ABORT_TEXTS = {
    0x05030000: "toggle bit not alternated",
    0x05040000: "SDO protocol timed out",
    0x05040001: "client/server command specifier not valid or unknown",
    0x05040002: "invalid block size",
    0x05040003: "invalid sequence number",
    0x05040004: "CRC error",
    0x05040005: "out of memory",
    0x06010000: "unsupported access to an object",
    0x06010001: "attempt to read a write only object",
    0x06010002: "attempt to write a read only object",
    0x06020000: "object does not exist in the object dictionary",
    0x06040041: "object cannot be mapped to the PDO",
    0x06040042: "the number and length of the objects to be mapped would exceed PDO length",
    0x06040043: "general parameter incompatibility reason",
    0x06040047: "general internal incompatibility in the device",
    0x06060000: "access failed due to a hardware error",
    0x06070010: "data type does not match, length of service parameter does not match",
    0x06070012: "data type does not match, length of service parameter too high",
    0x06070013: "data type does not match, length of service parameter too low",
    0x06090011: "sub-index does not exist",
    0x06090030: "invalid value for parameter (download only)",
    0x06090031: "value of parameter written too high (download only)",
    0x06090032: "value of parameter written too low (download only)",
    0x06090036: "maximum value is less than minimum value",
    0x060A0023: "resource not available: SDO connection",
    0x08000000: "general error",
    0x08000020: "data cannot be transferred or stored to the application",
    0x08000021: "data cannot be transferred or stored to the application because of local control",
    0x08000022: "data cannot be transferred or stored to the application because of the present device state",
    0x08000023: "object dictionary dynamic generation fails or no object dictionary is present",
    0x08000024: "no data available",
}


def sdo_crc(data: bytes) -> int:
    """The CRC of SDO block transfer (CiA 301 §7.2.4.3.16): CRC-16-CCITT, x^16 + x^12 + x^5 + 1, start value 0."""
    crc = 0
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021 if crc & 0x8000 else crc << 1) & 0xFFFF
    return crc


def abort_text(code: int) -> str:
    """``0x06020000 (object does not exist in the object dictionary)``."""
    return f"0x{code:08X} ({ABORT_TEXTS.get(code, 'not a CiA 301 abort code')})"


class SdoError(Exception):
    """A transfer that did not end as asked; ``frames``: the frames of the transfer."""

    def __init__(self, message: str, frames: List[Frame]) -> None:
        super().__init__(message)
        self.frames = frames

    @property
    def reason(self) -> str:
        """The message without the entry it names first (``aborted with 0x06020000 (...)``)."""
        text = str(self)
        head, sep, tail = text.partition(": ")
        return tail if sep and head.startswith("0x") and ":" in head else text


class SdoAbort(SdoError):
    def __init__(self, code: int, index: int, sub: int, frames: List[Frame]) -> None:
        super().__init__(f"0x{index:04X}:{sub:02X}: aborted with {abort_text(code)}", frames)
        self.code, self.index, self.sub = code, index, sub


class SdoTimeout(SdoError):
    pass


class SdoProtocolError(SdoError):
    pass


class SdoClient:
    """The client of one SDO server: requests on ``request_id`` (client -> server, default 0x600 + node-ID),
    answers on ``response_id`` (server -> client, default 0x580 + node-ID)."""

    def __init__(self, log: FrameLog, node_id: int, timeout: float = 1.0, request_id: Optional[int] = None,
                 response_id: Optional[int] = None) -> None:
        self.log = log
        self.node_id = node_id
        self.timeout = timeout
        self.request_id = 0x600 + node_id if request_id is None else request_id
        self.response_id = 0x580 + node_id if response_id is None else response_id
        self.frames: List[Frame] = []  # of the current transfer

    # --- single frames ------------------------------------------------------------------------------------------

    def request(self, data: bytes, timeout: Optional[float] = None) -> Frame:
        """Sends one request (padded to 8 bytes) and returns the server's answer; SdoTimeout when none comes."""
        self.frames.append(self.log.send(self.request_id, bytes(data).ljust(8, b"\0")))
        answer = self.log.wait_for(lambda f: f.can_id == self.response_id and not f.rtr,
                                   self.timeout if timeout is None else timeout)
        if answer is None:
            raise SdoTimeout(f"no answer on 0x{self.response_id:03X} within "
                             f"{self.timeout if timeout is None else timeout} s", list(self.frames))
        self.frames.append(answer)
        return answer

    def send_abort(self, index: int, sub: int, code: int) -> None:
        """An abort from the client (unconfirmed: no answer is waited for)."""
        self.frames.append(self.log.send(self.request_id, struct.pack("<BHBI", 0x80, index, sub, code)))

    def silence(self, duration: float) -> Optional[Frame]:
        """The first frame from the server within ``duration`` seconds, None when it stays silent."""
        frame = self.log.wait_for(lambda f: f.can_id == self.response_id, duration)
        if frame is not None:
            self.frames.append(frame)
        return frame

    # --- transfers ----------------------------------------------------------------------------------------------

    def upload(self, index: int, sub: int) -> bytes:
        """Reads an entry: expedited or segmented, as the server chooses (§7.2.4.3.4..7)."""
        self.frames = []
        answer = self.request(struct.pack("<BHB", 0x40, index, sub))
        self._check_answer(answer, index, sub, 2)
        command = answer.data[0]
        if command & 0x02:  # expedited
            size = 4 - ((command >> 2) & 3) if command & 0x01 else 4
            return bytes(answer.data[4:4 + size])
        size = struct.unpack_from("<I", answer.data, 4)[0] if command & 0x01 else None
        return self.upload_segments(index, sub, size)

    def start_segmented_upload(self, index: int, sub: int) -> Optional[int]:
        """The initiate step alone: the size the server indicated (None: not indicated). SdoProtocolError when it
        answers expedited."""
        self.frames = []
        answer = self.request(struct.pack("<BHB", 0x40, index, sub))
        self._check_answer(answer, index, sub, 2)
        if answer.data[0] & 0x02:
            raise SdoProtocolError(f"0x{index:04X}:{sub:02X}: the server answered expedited", list(self.frames))
        return struct.unpack_from("<I", answer.data, 4)[0] if answer.data[0] & 0x01 else None

    def upload_segments(self, index: int, sub: int, size: Optional[int]) -> bytes:
        """The segments of an upload whose initiate was answered segmented (``size`` as indicated, or None)."""
        data = bytearray()
        toggle = 0
        while True:
            answer = self.request(bytes([0x60 | toggle << 4]))
            self._check_answer(answer, index, sub, 0, mux=False)
            command = answer.data[0]
            if (command >> 4) & 1 != toggle:
                raise SdoProtocolError(f"0x{index:04X}:{sub:02X}: upload segment with toggle bit "
                                       f"{(command >> 4) & 1}, expected {toggle}", list(self.frames))
            data += answer.data[1:8 - ((command >> 1) & 7)]
            if command & 0x01:
                break
            toggle ^= 1
            if len(data) > (1 << 20):
                raise SdoProtocolError(f"0x{index:04X}:{sub:02X}: more than 1 MiB without an end", list(self.frames))
        if size is not None and size != len(data):
            raise SdoProtocolError(f"0x{index:04X}:{sub:02X}: {len(data)} bytes sent, {size} indicated",
                                   list(self.frames))
        return bytes(data)

    def download(self, index: int, sub: int, data: bytes, segmented: bool = False) -> None:
        """Writes an entry: expedited when it fits in 4 bytes and ``segmented`` is false, else segmented with the
        size indicated (§7.2.4.3.2..3, §7.2.4.3.8..9)."""
        self.frames = []
        if len(data) <= 4 and not segmented:
            command = 0x23 | (4 - len(data)) << 2
            answer = self.request(struct.pack("<BHB", command, index, sub) + bytes(data).ljust(4, b"\0"))
            self._check_answer(answer, index, sub, 3)
            return
        answer = self.request(struct.pack("<BHBI", 0x21, index, sub, len(data)))
        self._check_answer(answer, index, sub, 3)
        toggle, offset = 0, 0
        while True:
            chunk = data[offset:offset + 7]
            offset += len(chunk)
            last = offset >= len(data)
            command = toggle << 4 | (7 - len(chunk)) << 1 | int(last)
            answer = self.request(bytes([command]) + chunk)
            self._check_answer(answer, index, sub, 1, mux=False)
            if (answer.data[0] >> 4) & 1 != toggle:
                raise SdoProtocolError(f"0x{index:04X}:{sub:02X}: download segment answered with toggle bit "
                                       f"{(answer.data[0] >> 4) & 1}, expected {toggle}", list(self.frames))
            if last:
                return
            toggle ^= 1

    def block_upload(self, index: int, sub: int, block_size: int = 127) -> Tuple[bytes, bool]:
        """Reads an entry by SDO block upload (§7.2.4.3.9-16) with CRC and no protocol switch (pst 0): the data and
        whether the server used the CRC (it is then checked). SdoAbort when the server refuses (0x05040001: it has
        no block transfer); SdoProtocolError for a wrong sequence number, size or CRC."""
        self.frames = []
        answer = self.request(struct.pack("<BHBBB", 0xA4, index, sub, block_size, 0))
        self._check_answer(answer, index, sub, 6)
        command = answer.data[0]
        crc_used = bool(command & 0x04)
        size = struct.unpack_from("<I", answer.data, 4)[0] if command & 0x02 else None
        self.frames.append(self.log.send(self.request_id, bytes([0xA3]).ljust(8, b"\0")))
        data = bytearray()
        while True:
            last_seq, done = 0, False
            while True:  # the segments of one block, streamed by the server
                segment = self.log.wait_for(lambda f: f.can_id == self.response_id, self.timeout)
                if segment is None:
                    raise SdoTimeout(f"0x{index:04X}:{sub:02X}: block upload: segment {last_seq + 1} did not come",
                                     list(self.frames))
                self.frames.append(segment)
                seq = segment.data[0] & 0x7F
                if segment.data[0] == 0x80 and len(segment.data) == 8 and last_seq == 0 and not data:
                    code = struct.unpack_from("<I", segment.data, 4)[0]  # an abort instead of the first segment
                    raise SdoAbort(code, index, sub, list(self.frames))
                if seq != last_seq + 1:
                    raise SdoProtocolError(f"0x{index:04X}:{sub:02X}: block upload segment with sequence number "
                                           f"{seq}, expected {last_seq + 1}", list(self.frames))
                last_seq = seq
                data += segment.data[1:8]
                if segment.data[0] & 0x80:
                    done = True
                    break
                if seq == block_size:
                    break
            self.frames.append(self.log.send(self.request_id, bytes([0xA2, last_seq, block_size]).ljust(8, b"\0")))
            if done:
                break
        end = self.log.wait_for(lambda f: f.can_id == self.response_id, self.timeout)
        if end is None:
            raise SdoTimeout(f"0x{index:04X}:{sub:02X}: block upload: no end frame", list(self.frames))
        self.frames.append(end)
        self._check_answer(end, index, sub, 6, mux=False)
        if end.data[0] & 0x03 != 0x01:
            raise SdoProtocolError(f"0x{index:04X}:{sub:02X}: block upload end with ss {end.data[0] & 0x03}, not 1",
                                   list(self.frames))
        unused = (end.data[0] >> 2) & 7
        if unused:
            del data[-unused:]
        self.frames.append(self.log.send(self.request_id, bytes([0xA1]).ljust(8, b"\0")))
        if size is not None and size != len(data):
            raise SdoProtocolError(f"0x{index:04X}:{sub:02X}: block upload of {len(data)} bytes, {size} indicated",
                                   list(self.frames))
        if crc_used:
            crc = struct.unpack_from("<H", end.data, 1)[0]
            if crc != sdo_crc(bytes(data)):
                raise SdoProtocolError(f"0x{index:04X}:{sub:02X}: block upload CRC 0x{crc:04X}, the data's is "
                                       f"0x{sdo_crc(bytes(data)):04X}", list(self.frames))
        return bytes(data), crc_used

    def start_block_download(self, index: int, sub: int, size: int) -> Tuple[int, bool]:
        """The initiate of an SDO block download alone (§7.2.4.3.9-16: ccs 6, client CRC, size indicated): the block
        size the server asks for and whether it supports the CRC. SdoAbort when it refuses (0x05040001: it has no
        block transfer); SdoProtocolError for an answer that is no initiate confirmation or a block size not 1..127."""
        self.frames = []
        answer = self.request(struct.pack("<BHBI", 0xC6, index, sub, size))
        self._check_answer(answer, index, sub, 5)
        if answer.data[0] & 0x03:
            raise SdoProtocolError(f"0x{index:04X}:{sub:02X}: block download initiate answered with ss "
                                   f"{answer.data[0] & 0x03}, not 0", list(self.frames))
        block_size = answer.data[4]
        if not 1 <= block_size <= 127:
            raise SdoProtocolError(f"0x{index:04X}:{sub:02X}: block size {block_size}, not 1..127", list(self.frames))
        return block_size, bool(answer.data[0] & 0x04)

    def block_download(self, index: int, sub: int, data: bytes) -> bool:
        """Writes an entry by SDO block download (§7.2.4.3.9-16) with the size indicated and the CRC where the
        server supports it (then returns True): blocks of the size the server asks for, sequence numbers 1.. in
        each, c=1 on the last segment; a block confirmed short of its end (ackseq) goes on after the last segment
        the server took. SdoAbort when the server refuses or aborts; SdoProtocolError for a wrong answer."""
        block_size, crc_used = self.start_block_download(index, sub, len(data))
        segments = [data[i:i + 7] for i in range(0, len(data), 7)] or [b""]
        sent, stalled = 0, 0  # segments the server confirmed; blocks in a row it confirmed none of
        while sent < len(segments):
            block = segments[sent:sent + block_size]
            for seq, chunk in enumerate(block, 1):
                last = sent + seq == len(segments)
                segment = bytes([int(last) << 7 | seq]) + chunk.ljust(7, b"\0")
                self.frames.append(self.log.send(self.request_id, segment))
            answer = self.log.wait_for(lambda f: f.can_id == self.response_id and not f.rtr, self.timeout)
            if answer is None:
                raise SdoTimeout(f"0x{index:04X}:{sub:02X}: block download: no confirmation of the block within "
                                 f"{self.timeout} s", list(self.frames))
            self.frames.append(answer)
            self._check_answer(answer, index, sub, 5, mux=False)
            ackseq, block_size = answer.data[1], answer.data[2]
            if answer.data[0] & 0x03 != 2 or ackseq > len(block) or not 1 <= block_size <= 127:
                raise SdoProtocolError(f"0x{index:04X}:{sub:02X}: block confirmation {answer.data[:3].hex(' ')} after "
                                       f"{len(block)} segments: expected A2, ackseq 0..{len(block)}, a block size "
                                       "1..127", list(self.frames))
            sent += ackseq
            stalled = stalled + 1 if ackseq == 0 else 0
            if stalled == 3:
                raise SdoProtocolError(f"0x{index:04X}:{sub:02X}: three blocks in a row confirmed with ackseq 0",
                                       list(self.frames))
        unused = 7 - len(segments[-1])
        answer = self.request(struct.pack("<BH", 0xC1 | unused << 2, sdo_crc(data) if crc_used else 0))
        self._check_answer(answer, index, sub, 5, mux=False)
        if answer.data[0] & 0x03 != 1:
            raise SdoProtocolError(f"0x{index:04X}:{sub:02X}: block download end answered with ss "
                                   f"{answer.data[0] & 0x03}, not 1", list(self.frames))
        return crc_used

    def _check_answer(self, answer: Frame, index: int, sub: int, scs: int, mux: bool = True) -> None:
        if len(answer.data) != 8:
            raise SdoProtocolError(f"0x{index:04X}:{sub:02X}: an SDO answer of {len(answer.data)} bytes, not 8 "
                                   "(CiA 301 §7.2.4.3: SDO frames have 8 data bytes)", list(self.frames))
        command = answer.data[0]
        if command >> 5 == 4:
            code = struct.unpack_from("<I", answer.data, 4)[0]
            raise SdoAbort(code, index, sub, list(self.frames))
        if command >> 5 != scs:
            raise SdoProtocolError(f"0x{index:04X}:{sub:02X}: answer with server command specifier "
                                   f"{command >> 5}, expected {scs}", list(self.frames))
        if mux:
            got_index, got_sub = struct.unpack_from("<HB", answer.data, 1)
            if (got_index, got_sub) != (index, sub):
                raise SdoProtocolError(f"0x{index:04X}:{sub:02X}: the answer names 0x{got_index:04X}:{got_sub:02X}",
                                       list(self.frames))
