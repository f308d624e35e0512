"""Malformed input on a real SocketCAN bus (issue 7): frames of every DLC 0-8, data and remote, on every COB-ID
an emulated node listens to, in Pre-operational, Operational and Stopped; 29-bit frames, CAN error frames and
CAN FD frames on the same IDs; and a few thousand seeded random frames. Each case checks the exact frames the
emulator sends back (an answer, an EMCY, or nothing) and the effect on the node (NMT state, object values).

One canopen-emu process per test runs one node of each device: pro-ionizer 0x11, sds 0x12, buerkert 0x13. The
COB-IDs each node listens to are read from its EDS (SDO 0x1200:01, RPDOs 0x1400+n:01 with their mappings, SYNC
0x1005, node guarding where 0x100C/0x100D exist, heartbeat consumer where 0x1016 exists); NMT 0x000 and LSS
0x7E5 are fixed by CiA 301/305.

Prescribed outcomes (RULES below carries the same text into every failure message). "Op" = Operational.

| frame                              | state        | outcome                                  | source             |
|------------------------------------|--------------|------------------------------------------|--------------------|
| NMT 000, DLC 2                     | any          | command executed, never answered         | §2.2               |
| NMT 000, DLC 0-1                   | any          | ignored                                  | §2.7, dec. 1       |
| NMT 000, DLC 3-8                   | any          | ignored; Eltex profiles: executed        | decision 1         |
| NMT 000, remote frame              | any          | ignored                                  | architecture.md    |
| SDO 600+id, DLC 8                  | Pre-op, Op   | answered: 43 00 10 00 + 0x1000           | §4.4, v18          |
| SDO 600+id, DLC 8                  | Stopped      | no answer                                | §2.4, v11          |
| SDO 600+id, DLC 0-7, remote        | any          | no answer, nothing written               | §1, §4.4, v35      |
| RPDO, DLC = mapped length          | Op           | applied; clears length error (EMCY 0000) | §5.5, v51          |
| RPDO, DLC < mapped length          | Op           | discarded, EMCY 8210                     | §5.5, v49          |
| RPDO, DLC > mapped length          | Op           | first mapped bytes applied, EMCY 8220    | §5.5, v50          |
| RPDO, any DLC                      | Pre-op, Stop | dropped, no EMCY (none queued either)    | §5.6, v47          |
| RPDO, remote frame                 | any          | ignored                                  | architecture.md    |
| SYNC 0x1005, DLC 0 (no 0x1019)     | Op           | synchronous TPDO (set to type 1)         | §6, §5.2           |
| SYNC, DLC 0                        | Pre-op       | nothing sent (no PDOs)                   | §2.4, §6           |
| SYNC, DLC 1-8                      | Pre-op, Op   | EMCY 8240, not processed (then 0000)     | §6, v53            |
| SYNC, any; remote frame            | Stopped; any | ignored                                  | §2.4; architecture |
| guard RTR, 0x100C/D, 0x1017 = 0    | any          | 700+id [1] toggle + state, any DLC       | §3.3, v12-15       |
| guard RTR, 0x1017 != 0             | any          | ignored                                  | decisions, v17     |
| guard RTR, no 0x100C/D in the OD   | any          | ignored (no guarding service)            | §3.3               |
| data frame on the own 700+id       | any          | ignored                                  | §1                 |
| heartbeat 700+n, DLC 1 (consumer)  | any          | starts/feeds monitoring; timeout: 8130   | §3.2, v54          |
| heartbeat DLC != 1, remote, 29-bit | any          | not a heartbeat (starts/clears nothing)  | §1, architecture   |
| LSS 7E5, DLC 8                     | any          | processed (inquiry answered)             | §9, v57-59         |
| LSS 7E5, DLC 0-7, remote           | any          | ignored                                  | §1, v79            |
| 29-bit frame with a listened ID    | any          | ignored                                  | §1, architecture   |
| CAN error frame                    | any          | ignored by every node, logged            | emulator.md        |
| CAN FD frame                       | any          | ignored (classic CAN only)               | emulator.md        |

"§" and "v" (test vectors, §11) refer to the CiA facts sheet canopen-facts.md, "decisions" to docs/decisions.md.

How a case is observed: the emulator handles the frames of its one socket in order, so after a case frame the
test waits for the frames the case must cause, then sends a "barrier" (an SDO upload of 0x1018:02 to a node that
answers SDO, or a guard request to the Bürkert node where SDO cannot answer) and waits for its answer, pauses a few
ms and does it once more. The first answer proves the case frame was handled; the pause and the second one let the
emulator run its process step, where EMCYs leave (it reads a burst of frames before it processes the nodes, so an
EMCY can follow a later frame's direct answer). Every frame the emulator sent in between, except the barrier
answers, is the case's outcome and must equal the expected list exactly; the order between a node's direct answer
and its EMCY is not prescribed, so lists are compared as multisets. Heartbeats are off during the cases (Eltex
0x1017 = 60000 ms, Bürkert 0 so that it answers guard requests), so any boot-up or state frame is unexpected. The
Eltex TPDOs are not compared: they are cyclic on the device's own grid (0x2002:01, docs/devices/eltex.md).
"""
import os
import random
import re
import socket
import struct
import subprocess
import time
from functools import lru_cache
from pathlib import Path

import canopen
import msgpack
import pytest

from conftest import BUS_KIND, EDS, IFACE, Deadline, LoopbackUdpBus

PREOP, OP, STOPPED = "PRE-OPERATIONAL", "OPERATIONAL", "STOPPED"
NMT_CMD = {OP: 0x01, STOPPED: 0x02, PREOP: 0x80}
STATE_BYTE = {STOPPED: 0x04, OP: 0x05, PREOP: 0x7F}
SPECS = (("pro-ionizer", 0x11), ("sds", 0x12), ("buerkert", 0x13))
# Decision 1: the Eltex device classes set CO_OPT_NMT_ACCEPT_LONG (their manuals draw 8-byte NMT frames). It is a
# property of the device model, not of the EDS, so it is the one fact here that cannot be read from the OD.
NMT_ACCEPTS_LONG = {"pro-ionizer": True, "sds": True, "buerkert": False}
HB_PRODUCER = 0x05      # the node-ID this test plays for the Bürkert heartbeat consumer (not an emulated node)
HB_CONSUMER_MS = 250    # its consumer time
# The Eltex devices send their TPDOs on their own cycle only (CO_OPT_TPDO_NO_COS, 0x2002:01 grid); those frames are
# left out of every outcome.
CYCLIC_TPDOS = {"pro-ionizer", "sds"}
SEED_ENV = "CO_MALFORMED_SEED"
FRAMES_ENV = "CO_MALFORMED_FRAMES"

RULES = {
    "nmt": "NMT: DLC 2 executed; DLC < 2 ignored; DLC > 2 executed only by the Eltex profiles; remote ignored "
           "(facts §2.2/§2.7, decision 1)",
    "sdo": "SDO: only DLC-8 data frames answered, and only in Pre-op/Operational (facts §1, §2.4, §4.4)",
    "rpdo": "RPDO in Operational: short -> EMCY 8210 + discarded, long -> EMCY 8220 + first bytes applied, equal -> "
            "applied and clears the error; Pre-op/Stopped and remote frames: dropped (facts §5.5/§5.6)",
    "sync": "SYNC: DLC must be 0 (no 0x1019), else EMCY 8240 and not processed; TPDO only in Operational; "
            "Stopped/remote ignored (facts §6, decisions)",
    "guard": "guard RTR on 700+id: answered with toggle|state when 0x100C/0x100D exist and 0x1017 = 0, in every "
             "state and for any DLC; data frames ignored (facts §3.3, decisions)",
    "hbc": "heartbeat consumer: only 11-bit DLC-1 data frames are heartbeats (facts §1, §3.2)",
    "lss": "LSS: only DLC-8 data frames on 7E5 are processed, in every NMT state (facts §1, §9)",
    "eff": "29-bit frames are ignored whatever their ID (facts §1, architecture.md)",
    "err": "CAN error frames are ignored by the nodes and logged (emulator.md)",
    "fd": "CAN FD frames are ignored: classic CAN only (emulator.md)",
}

CAN_EFF_FLAG, CAN_RTR_FLAG, CAN_ERR_FLAG = 0x80000000, 0x40000000, 0x20000000
SOL_CAN_RAW = getattr(socket, "SOL_CAN_RAW", 101)
CAN_RAW_FD_FRAMES = 5
CANFD_BRS = 0x01
UPLOAD_1000 = bytes([0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0])
LSS_TO_CONFIG = bytes([0x04, 0x01, 0, 0, 0, 0, 0, 0])
LSS_TO_WAITING = bytes([0x04, 0x00, 0, 0, 0, 0, 0, 0])
LSS_INQUIRE_ID = bytes([0x5E, 0, 0, 0, 0, 0, 0, 0])


class Node:
    """What one emulated node listens to and answers, read from its EDS."""

    def __init__(self, device, node_id):
        od = canopen.import_od(str(EDS[device]), node_id=node_id)
        self.device, self.id, self.od = device, node_id, od
        self.sdo_rx = od[0x1200][1].default if 0x1200 in od else 0x600 + node_id
        self.sdo_tx = od[0x1200][2].default if 0x1200 in od else 0x580 + node_id
        self.emcy = (od[0x1014].default if 0x1014 in od else 0x80 + node_id) & 0x7FF
        self.sync = od[0x1005].default & 0x7FF if 0x1005 in od else None
        self.sync_len = 1 if 0x1019 in od and od[0x1019].default else 0
        self.guarding = 0x100C in od and 0x100D in od
        self.hb_consumer = 0x1016 in od
        self.accepts_long_nmt = NMT_ACCEPTS_LONG[device]
        self.device_type = od[0x1000].default
        self.product = od[0x1018][2].default
        self.rpdos = [self._pdo(od, 0x1400 + n, 0x1600 + n) for n in range(512) if 0x1400 + n in od]
        self.rpdos = [p for p in self.rpdos if p is not None]
        self.tpdos = [self._pdo(od, 0x1800 + n, 0x1A00 + n) for n in range(512) if 0x1800 + n in od]
        self.tpdos = [p for p in self.tpdos if p is not None]

    @staticmethod
    def _pdo(od, comm, mapping):
        cob = od[comm][1].default
        if cob & 0x80000000:
            return None  # not valid: the node does not listen to / send it
        entries = []
        for s in range(1, od[mapping][0].default + 1):
            v = od[mapping][s].default
            entries.append((v >> 16, (v >> 8) & 0xFF, (v & 0xFF) // 8))
        return {"cob": cob & 0x7FF, "len": sum(e[2] for e in entries), "entries": entries, "comm": comm}

    def __repr__(self):
        return f"{self.device}:0x{self.id:02X}"


@lru_cache(maxsize=None)
def nodes():
    return tuple(Node(device, node_id) for device, node_id in SPECS)


def frame_text(cob, data, rtr=False, eff=False):
    return f"{cob:0{8 if eff else 3}X} [{len(data)}]{' RTR' if rtr else ''} {bytes(data).hex(' ')}"


class Rig:
    """The emulator with the three nodes, a raw socket to send any frame, and the capture to see the answers."""

    def __init__(self, emu, capture):
        self.emu, self.capture, self.nodes = emu, capture, nodes()
        if BUS_KIND == "socketcan":
            self.tx = socket.socket(socket.PF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
            self.tx.bind((IFACE,))
        else:  # datagrams packed here: python-can's Message would refuse some of the frames sent
            self.tx = LoopbackUdpBus()
        self.state = {n.id: PREOP for n in self.nodes}
        self.own = []  # (capture length when sent, cob, data) of data frames this test sent on an output COB-ID
        self.stopped = False
        self.guard = next(n for n in self.nodes if n.guarding)  # the barrier of last resort (every node Stopped)
        # Emulator output: SDO answers, EMCY, NMT error control, LSS answers, the Bürkert TPDOs. The Eltex TPDOs
        # are cyclic on the device's own grid and not part of any outcome here.
        self.out_ids = {0x7E4}
        for n in self.nodes:
            self.out_ids |= {n.sdo_tx, n.emcy, 0x700 + n.id}
            if n.device not in CYCLIC_TPDOS:
                self.out_ids |= {p["cob"] for p in n.tpdos}

    def close(self):
        if BUS_KIND == "socketcan":
            self.tx.close()
        else:
            self.tx.shutdown()

    # ---- sending ----
    def send(self, cob, data=b"", rtr=False, eff=False, dlc=None):
        """A classic frame; a remote frame carries data bytes too (the kernel passes them), so that a receiver
        that ignored the RTR bit would act on them."""
        data = bytes(data)
        dlc = len(data) if dlc is None else dlc
        can_id = (cob & 0x1FFFFFFF) | (CAN_EFF_FLAG if eff else 0) | (CAN_RTR_FLAG if rtr else 0)
        if cob in self.out_ids and not (rtr or eff):
            self.own.append((self.mark(), cob, data[:dlc]))
        if BUS_KIND == "socketcan":
            self.tx.send(struct.pack("=IBBBB8s", can_id, dlc, 0, 0, 0, data.ljust(8, b"\0")[:8]))
            return
        # python-can's map; a remote frame's data bytes go along as on SocketCAN (the receiver drops them)
        self.tx.send_datagram(msgpack.packb({
            "timestamp": time.time(), "arbitration_id": cob & 0x1FFFFFFF, "is_extended_id": eff,
            "is_remote_frame": rtr, "is_error_frame": False, "channel": None, "dlc": dlc,
            "data": data[:8] if rtr else data.ljust(dlc, b"\0")[:dlc], "is_fd": False, "bitrate_switch": False,
            "error_state_indicator": False}, use_bin_type=True))

    def send_error_frame(self, can_id_bits, data):
        self.tx.send(struct.pack("=IBBBB8s", CAN_ERR_FLAG | can_id_bits, 8, 0, 0, 0, bytes(data).ljust(8, b"\0")))

    # ---- observing ----
    def mark(self):
        with self.capture.lock:
            return len(self.capture.frames)

    def frames_since(self, mark):
        with self.capture.lock:
            return list(self.capture.frames[mark:])

    def outputs(self, mark):
        """(cob, data) of every frame the emulator sent since mark (the capture also sees this test's frames)."""
        out = [(m.arbitration_id, bytes(m.data)) for m in self.frames_since(mark)
               if not (m.is_error_frame or m.is_extended_id or m.is_remote_frame or m.is_fd)
               and m.arbitration_id in self.out_ids]
        for at, cob, data in self.own:
            if at >= mark and (cob, data) in out:
                out.remove((cob, data))
        return out

    def wait(self, mark, pred, what, timeout=5.0):
        def match():
            return next((m for m in self.frames_since(mark)
                         if not (m.is_error_frame or m.is_extended_id or m.is_remote_frame)
                         and pred(m.arbitration_id, bytes(m.data))), None)
        deadline = Deadline(timeout)
        found = deadline.until(match, 0.001)
        if found is None:
            raise AssertionError(f"no {what} within {deadline}; emulator alive: {self.emu.proc.poll() is None}; "
                                 f"seen: {[frame_text(c, d) for c, d in self.outputs(mark)][-12:]}")
        return found

    def barrier(self, via_guard=False):
        """Waits until the emulator has handled every frame sent so far (a round trip) and run its process step
        (a short pause, then a second round trip; see the module docstring). Returns the (cob, data) answers it
        caused, to be left out of outcomes."""
        answers = []
        for i in range(2):
            if i:
                time.sleep(0.003)
            mark = self.mark()
            witness = None if via_guard else next((n for n in self.nodes if self.state[n.id] in (PREOP, OP)), None)
            if witness is not None:
                ans = bytes([0x43, 0x18, 0x10, 0x02]) + struct.pack("<I", witness.product)
                self.send(witness.sdo_rx, bytes([0x40, 0x18, 0x10, 0x02, 0, 0, 0, 0]))
                self.wait(mark, lambda c, d: c == witness.sdo_tx and d == ans, f"barrier answer from {witness}")
                answers.append((witness.sdo_tx, ans))
            else:
                g = self.guard
                self.send(0x700 + g.id, rtr=True, dlc=1)
                m = self.wait(mark, lambda c, d: c == 0x700 + g.id and len(d) == 1 and d[0] != 0,
                              f"guard reply (barrier) from {g}")
                answers.append((m.arbitration_id, bytes(m.data)))
        return answers

    def outcome(self, mark, via_guard=False):
        """Everything the emulator sent since mark, once it has handled all of it; barrier answers removed."""
        barrier = self.barrier(via_guard)
        out = self.outputs(mark)
        for b in barrier:
            out.remove(b)
        return out

    @staticmethod
    def compare(got, expected):
        """(missing, unexpected) between frames sent and expected ones, as multisets."""
        rest = list(got)
        missing = []
        for cob, data in expected:
            hit = next((g for g in rest
                        if g[0] == cob and (len(g[1]) == data if isinstance(data, int) else g[1] == data)), None)
            if hit is None:
                missing.append((cob, data))
            else:
                rest.remove(hit)
        return missing, rest

    def check(self, case, rule, mark, expected, via_guard=False):
        """The case's outcome is exactly expected: a list of (cob, data), or (cob, int length) where the content is
        a live value (TPDO). Expected frames are waited for first (an EMCY leaves in the emulator's process step,
        which may run only after a burst of frames has been read), then the barrier shows nothing else came."""
        Deadline(5.0).until(lambda: not self.compare(self.outputs(mark), expected)[0], 0.001)
        got = self.outcome(mark, via_guard)
        missing, rest = self.compare(got, expected)
        bus = [frame_text(m.arbitration_id, m.data, m.is_remote_frame, m.is_extended_id)
               for m in self.frames_since(mark)]
        assert not missing and not rest, (
            f"{case}: expected {[fmt(e) for e in expected]}, emulator sent {[frame_text(c, d) for c, d in got]}\n"
            f"  rule: {RULES[rule]}\n  everything on the bus since: {bus}")

    # ---- SDO with exact frames ----
    def sdo_read(self, node, index, sub):
        mark = self.mark()
        mux = struct.pack("<HB", index, sub)
        self.send(node.sdo_rx, b"\x40" + mux + bytes(4))
        m = self.wait(mark, lambda c, d: c == node.sdo_tx and d[1:4] == mux,
                      f"SDO answer {index:04X}:{sub:02X} from {node}")
        d = bytes(m.data)
        if d[0] == 0x80:
            raise AssertionError(f"{node} {index:04X}:{sub:02X}: abort 0x{struct.unpack('<I', d[4:])[0]:08X}")
        assert d[0] & 0xF3 == 0x43, f"{node} {index:04X}:{sub:02X}: not an expedited upload answer: {d.hex(' ')}"
        return d[4:8 - ((d[0] >> 2) & 3)]

    def sdo_write(self, node, index, sub, value):
        mark = self.mark()
        mux = struct.pack("<HB", index, sub)
        self.send(node.sdo_rx, bytes([0x23 | ((4 - len(value)) << 2)]) + mux + value.ljust(4, b"\0"))
        m = self.wait(mark, lambda c, d: c == node.sdo_tx and d[1:4] == mux,
                      f"SDO answer {index:04X}:{sub:02X} from {node}")
        assert bytes(m.data) == b"\x60" + mux + bytes(4), \
            f"{node} write {index:04X}:{sub:02X}: {bytes(m.data).hex(' ')}"

    def value(self, node, index, sub):
        """An object's value: by SDO where it is readable, by the emulator's get command where it is write-only
        (the Eltex HV release 0x6200:01) or the node is Stopped."""
        obj = node.od[index]
        var = obj[sub] if isinstance(obj, (canopen.objectdictionary.Record, canopen.objectdictionary.Array)) else obj
        if var.access_type != "wo" and self.state[node.id] != STOPPED:
            return int.from_bytes(self.sdo_read(node, index, sub), "little")
        address = f"0x{index:04X}:{sub:02X}"
        line = self.emu.command(f"get {node.id} {address}", expect=f"node {node.id}: {address}")
        m = re.search(r"= (\S+)(?: \(0x([0-9A-Fa-f]+)\))?", line)
        if m.group(2) is not None:
            return int(m.group(2), 16)
        return struct.unpack("<I", struct.pack("<f", float(m.group(1))))[0]  # REAL32 printed with %g

    # ---- NMT ----
    def listed_states(self):
        start = len(self.emu.out_lines)
        last = self.nodes[-1]
        self.emu.command("list", expect=f"node {last.id}: {last.device} (started as")
        states = {}
        for line in self.emu.out_lines[start:]:
            m = re.match(r"node (\d+): \S+ \(started as \d+\) (\S+)", line)
            if m:
                states[int(m.group(1))] = m.group(2)
        return states

    def set_state(self, state, only=None):
        """Valid NMT commands (broadcast, or addressed to the nodes in only); checks the result with the emulator's
        list command, and that the transition sent nothing (e.g. no EMCY queued while Stopped)."""
        mark = self.mark()
        if only is None:
            self.send(0x000, bytes([NMT_CMD[state], 0]))
            targets = self.nodes
        else:
            targets = only
            for n in only:
                self.send(0x000, bytes([NMT_CMD[state], n.id]))
        for n in targets:
            self.state[n.id] = state
        out = self.outcome(mark)
        assert self.listed_states() == self.state
        assert out == [], f"entering {state}: unexpected frames {[frame_text(c, d) for c, d in out]}"


def fmt(e):
    cob, data = e
    return f"{cob:03X} [{data}] (live value)" if isinstance(data, int) else frame_text(cob, data)


def emcy(node, code, register, msef):
    """An EMCY frame of a node. The errors the core raises set error register 0x11 (communication + generic bit,
    decision 4) and carry their source in msef byte 0 (1 guarding, 2 heartbeat consumer + node-ID, 3 SYNC, 4 RPDO:
    decisions.md, EMCY); the error reset (code 0000) carries the register of what remains."""
    return node.emcy, struct.pack("<HB", code, register) + bytes(msef).ljust(5, b"\0")


@pytest.fixture
def rig(emulator, capture):
    emu = emulator(*(f"{d}:{i}" for d, i in SPECS))
    for n in nodes():
        capture.wait_for(0x700 + n.id, data=b"\x00", timeout=5)
    r = Rig(emu, capture)
    for n in r.nodes:
        # No heartbeats during the cases (any 700+id frame is then an outcome); the guarding device at 0 so that it
        # answers guard requests (the barrier when every node is Stopped).
        r.sdo_write(n, 0x1017, 0, struct.pack("<H", 0 if n.guarding else 60000))
    for n in r.nodes:
        if n.sync is not None:
            # The SYNC consumer's TPDOs synchronous (type 1, every SYNC): makes SYNC processing visible in
            # Operational, and keeps its event-driven transmissions (Bürkert: type 0xFE, event timer) out of outcomes.
            for p in n.tpdos:
                r.sdo_write(n, p["comm"], 2, b"\x01")
    r.barrier()
    yield r
    r.close()
    assert r.stopped or emu.proc.poll() is None, "canopen-emu died"


# ---------------------------------------------------------------------------------------------------------------

def test_nmt_of_every_dlc_and_remote_frames(rig):
    """Commands in all three states: start from Pre-op, stop from Operational, enter Pre-op from Stopped."""
    for before, after in ((PREOP, OP), (OP, STOPPED), (STOPPED, PREOP)):
        cmd = NMT_CMD[after]
        for rtr in (False, True):
            for dlc in range(9):
                rig.set_state(before)
                mark = rig.mark()
                frame = bytes([cmd, 0x00, 0xA5, 0xA5, 0xA5, 0xA5, 0xA5, 0xA5])  # broadcast; the rest is filler
                rig.send(0x000, frame[:dlc] if not rtr else frame, rtr=rtr, dlc=dlc)
                for n in rig.nodes:
                    executed = not rtr and (dlc == 2 or (dlc > 2 and n.accepts_long_nmt))
                    rig.state[n.id] = after if executed else before
                case = f"{before}: {frame_text(0, frame[:dlc], rtr)}"
                # NMT is never answered. The barrier is a guard request: it is answered in every NMT state.
                rig.check(case, "nmt", mark, [], via_guard=True)
                assert rig.listed_states() == rig.state, f"{case}\n  rule: {RULES['nmt']}"


def test_sdo_requests_of_every_dlc(rig):
    for state in (PREOP, OP, STOPPED):
        for n in rig.nodes:
            rig.set_state(PREOP if state == STOPPED else state)
            if state == STOPPED:
                rig.set_state(STOPPED, only=[n])  # the others stay in Pre-op and answer the barrier
            answer = bytes([0x43, 0x00, 0x10, 0x00]) + struct.pack("<I", n.device_type)
            for rtr in (False, True):
                for dlc in range(9):
                    mark = rig.mark()
                    rig.send(n.sdo_rx, UPLOAD_1000[:dlc] if not rtr else UPLOAD_1000, rtr=rtr, dlc=dlc)
                    expected = [(n.sdo_tx, answer)] if not rtr and dlc == 8 and state != STOPPED else []
                    rig.check(f"{n} {state}: {frame_text(n.sdo_rx, UPLOAD_1000[:dlc], rtr)}", "sdo", mark, expected)


def test_sdo_download_shorter_than_8_is_not_applied(rig):
    """DLC 5-7 downloads that carry a complete expedited write of 0x1017: no answer and the value stays."""
    for n in rig.nodes:
        before = rig.value(n, 0x1017, 0)
        for dlc, frame in ((5, b"\x2F\x17\x10\x00\x64"), (6, b"\x2B\x17\x10\x00\xC8\x00"),
                           (7, b"\x2B\x17\x10\x00\x2C\x01\x00")):
            mark = rig.mark()
            rig.send(n.sdo_rx, frame)
            rig.check(f"{n}: {frame_text(n.sdo_rx, frame)}", "sdo", mark, [])
            assert rig.value(n, 0x1017, 0) == before, f"{n}: DLC {dlc} download was applied\n  rule: {RULES['sdo']}"


def rpdo_values(node, pdo, k):
    """The k-th fresh value for an RPDO's (single) mapped object, as wire bytes, and its integer value."""
    index, sub, size = pdo["entries"][0]
    var = node.od[index][sub]
    if var.data_type == canopen.objectdictionary.REAL32:
        raw = struct.pack("<f", 10.0 + k)  # a valid set-point (the Bürkert device refuses non-finite values)
    else:
        raw = bytes([(0x0F, 0x00)[k % 2]]).ljust(size, b"\0")  # the Eltex HV release: 0x0F release, 0x00 off
    return raw, int.from_bytes(raw, "little")


def test_rpdo_of_every_dlc(rig):
    for state in (OP, PREOP, STOPPED):
        rig.set_state(PREOP if state == STOPPED else state)
        for n in rig.nodes:
            if state == STOPPED:
                rig.set_state(STOPPED, only=[n])
            for pdo in n.rpdos:
                assert len(pdo["entries"]) == 1, "the devices map one object per RPDO"
                index, sub, _ = pdo["entries"][0]
                k = 0
                for rtr in (False, True):
                    for dlc in range(9):
                        current = rig.value(n, index, sub)
                        k += 1
                        raw, value = rpdo_values(n, pdo, k)
                        if value == current:
                            k += 1
                            raw, value = rpdo_values(n, pdo, k)
                        frame = (raw + bytes([0xEE] * 8))[:8]  # a long frame: the first mapped bytes, then filler
                        mark = rig.mark()
                        rig.send(pdo["cob"], frame[:dlc] if not rtr else frame, rtr=rtr, dlc=dlc)
                        case = f"{n} {state}: {frame_text(pdo['cob'], frame[:dlc], rtr)}"
                        applies = state == OP and not rtr and dlc >= pdo["len"]
                        expected = []
                        if state == OP and not rtr and dlc < pdo["len"]:
                            expected = [emcy(n, 0x8210, 0x11, [0x04])]
                        elif state == OP and not rtr and dlc > pdo["len"]:
                            expected = [emcy(n, 0x8220, 0x11, [0x04])]
                        rig.check(case, "rpdo", mark, expected)
                        assert rig.value(n, index, sub) == (value if applies else current), \
                            f"{case}: value {'not ' if applies else ''}applied\n  rule: {RULES['rpdo']}"
                        if expected:
                            # The next correct RPDO is applied and resets the error (EMCY 0000, register 0).
                            k += 1
                            raw, value = rpdo_values(n, pdo, k)
                            mark = rig.mark()
                            rig.send(pdo["cob"], raw)
                            rig.check(f"{case}, then a correct one", "rpdo", mark, [emcy(n, 0x0000, 0x00, [0x04])])
                            assert rig.value(n, index, sub) == value
            if state == STOPPED:
                rig.set_state(PREOP, only=[n])  # no EMCY may have been queued while Stopped


def test_sync_of_every_dlc(rig):
    consumers = [n for n in rig.nodes if n.sync is not None]
    assert consumers, "no device with 0x1005"
    cobs = sorted({n.sync for n in consumers})
    for state in (OP, PREOP, STOPPED):
        rig.set_state(state)
        for cob in cobs:
            for rtr in (False, True):
                for dlc in range(9):
                    frame = bytes(range(1, 9))  # byte 0 = a valid counter value 1
                    mark = rig.mark()
                    rig.send(cob, frame[:dlc] if not rtr else frame, rtr=rtr, dlc=dlc)
                    expected, recover = [], []
                    for n in consumers:
                        if n.sync != cob or rtr or state == STOPPED:
                            continue
                        tpdo = [(p["cob"], p["len"]) for p in n.tpdos] if state == OP else []
                        if dlc == n.sync_len:
                            expected += tpdo
                        else:
                            expected.append(emcy(n, 0x8240, 0x11, [0x03]))
                            recover += tpdo + [emcy(n, 0x0000, 0x00, [0x03])]
                    case = f"{state}: {frame_text(cob, frame[:dlc], rtr)}"
                    rig.check(case, "sync", mark, expected)
                    if recover:
                        mark = rig.mark()
                        rig.send(cob, frame[:consumers[0].sync_len])
                        rig.check(f"{case}, then a correct SYNC", "sync", mark, recover)
    rig.set_state(PREOP)  # nothing queued while Stopped


def test_node_guarding_requests_of_every_dlc(rig):
    g = rig.guard
    toggle = 0x00  # first reply after the boot-up (reset communication) has toggle 0 (facts §3.3, vector 12)
    for state in (PREOP, OP, STOPPED):
        rig.set_state(state, only=[g])  # the other nodes stay in Pre-op and answer the barrier
        for rtr in (True, False):
            for dlc in range(9):
                mark = rig.mark()
                rig.send(0x700 + g.id, bytes(8), rtr=rtr, dlc=dlc)
                expected = [(0x700 + g.id, bytes([toggle | STATE_BYTE[state]]))] if rtr else []
                case = f"{g} {state} 0x1017=0: {frame_text(0x700 + g.id, bytes(dlc), rtr)}"
                rig.check(case, "guard", mark, expected)
                if rtr:
                    toggle ^= 0x80
    rig.set_state(PREOP, only=[g])
    rig.sdo_write(g, 0x1017, 0, struct.pack("<H", 60000))  # heartbeat on (its first one in 60 s): guarding off
    for dlc in range(9):
        mark = rig.mark()
        rig.send(0x700 + g.id, rtr=True, dlc=dlc)
        rig.check(f"{g} 0x1017=60000: {frame_text(0x700 + g.id, bytes(dlc), True)}", "guard", mark, [])


def test_guard_request_to_a_device_without_node_guarding_is_ignored(rig):
    """The Eltex devices have heartbeat only (no 0x100C/0x100D in their EDS, their manuals know no guarding). With
    0x1017 = 0 they must still not answer a guard request: they do not offer the service."""
    eltex = [n for n in rig.nodes if not n.guarding]
    assert eltex
    for n in eltex:
        rig.sdo_write(n, 0x1017, 0, b"\x00\x00")
        mark = rig.mark()
        rig.send(0x700 + n.id, rtr=True, dlc=1)
        rig.check(f"{n} 0x1017=0: {frame_text(0x700 + n.id, b'', True)}", "guard", mark, [])


def test_heartbeat_consumer_counts_only_dlc1_frames(rig):
    c = next(n for n in rig.nodes if n.hb_consumer)
    cob = 0x700 + HB_PRODUCER
    rig.set_state(OP)
    rig.sdo_write(c, 0x1016, 1, struct.pack("<I", HB_PRODUCER << 16 | HB_CONSUMER_MS))
    timeout = emcy(c, 0x8130, 0x11, [0x02, HB_PRODUCER])
    reset = emcy(c, 0x0000, 0x00, [0x02, HB_PRODUCER])
    # (dlc, remote, 29-bit): data frames of every other DLC, remote frames of every DLC, a 29-bit DLC-1 frame
    not_heartbeats = ([(dlc, False, False) for dlc in range(9) if dlc != 1] + [(dlc, True, False) for dlc in range(9)]
                      + [(1, False, True)])
    # Monitoring starts with the first heartbeat. None of these is one (all carry state 05), so no timeout may follow.
    mark = rig.mark()
    for dlc, rtr, eff in not_heartbeats:
        rig.send(cob, bytes([0x05] * 8), rtr=rtr, eff=eff, dlc=dlc)
    time.sleep(3 * HB_CONSUMER_MS / 1000)
    rig.check(f"{c}: {len(not_heartbeats)} non-heartbeat frames on {cob:03X}, then 3 x consumer time", "hbc", mark, [])
    # A real one starts it: EMCY 8130 one consumer time later (msef: source 2, monitored node-ID).
    mark = rig.mark()
    rig.send(cob, b"\x05")
    sent = rig.wait(mark, lambda c_, d: c_ == cob and d == b"\x05", "own heartbeat in the capture")
    got = rig.wait(mark, lambda c_, d: (c_, d) == timeout, "EMCY 8130 (consumer timeout)", timeout=5.0)
    assert got.timestamp - sent.timestamp >= 0.9 * HB_CONSUMER_MS / 1000
    rig.check("consumer timeout", "hbc", mark, [timeout])
    # While timed out, none of the non-heartbeats clears the error.
    for dlc, rtr, eff in not_heartbeats:
        mark = rig.mark()
        rig.send(cob, bytes([0x05] * 8), rtr=rtr, eff=eff, dlc=dlc)
        rig.check(f"{c} timed out: {frame_text(cob, bytes([5] * dlc), rtr, eff)}", "hbc", mark, [])
    # A real heartbeat clears it; the consumer is switched off right behind it (processed in order, so before the
    # next timeout could come).
    mark = rig.mark()
    rig.send(cob, b"\x05")
    rig.sdo_write(c, 0x1016, 1, bytes(4))
    rig.check("a heartbeat after the timeout", "hbc", mark, [reset, (c.sdo_tx, b"\x60\x16\x10\x01" + bytes(4))])


def test_lss_of_every_dlc(rig):
    answers = [(0x7E4, bytes([0x5E, n.id, 0, 0, 0, 0, 0, 0])) for n in rig.nodes]
    for state in (PREOP, OP, STOPPED):
        rig.set_state(state)
        # Switch state global to configuration: only the DLC-8 data frame switches; proven by the inquiry after it
        # (a node in waiting state does not answer it, vector 57).
        for rtr in (False, True):
            for dlc in range(9):
                mark = rig.mark()
                rig.send(0x7E5, LSS_TO_CONFIG[:dlc] if not rtr else LSS_TO_CONFIG, rtr=rtr, dlc=dlc)
                rig.send(0x7E5, LSS_INQUIRE_ID)
                switched = not rtr and dlc == 8
                rig.check(f"{state}: {frame_text(0x7E5, LSS_TO_CONFIG[:dlc], rtr)}, then inquire node-ID", "lss", mark,
                          answers if switched else [])
                if switched:
                    rig.send(0x7E5, LSS_TO_WAITING)
        # Inquire node-ID in configuration state: only the DLC-8 data frame is answered.
        rig.send(0x7E5, LSS_TO_CONFIG)
        for rtr in (False, True):
            for dlc in range(9):
                mark = rig.mark()
                rig.send(0x7E5, LSS_INQUIRE_ID[:dlc] if not rtr else LSS_INQUIRE_ID, rtr=rtr, dlc=dlc)
                rig.check(f"{state}, configuration: {frame_text(0x7E5, LSS_INQUIRE_ID[:dlc], rtr)}", "lss", mark,
                          answers if not rtr and dlc == 8 else [])
        rig.send(0x7E5, LSS_TO_WAITING)


def listened(rig):
    """(cob, a payload that would have a visible effect, what it would do) for every COB-ID the nodes listen to."""
    out = [(0x000, bytes([0x02, 0x00]), "NMT stop all"), (0x7E5, LSS_TO_CONFIG, "LSS switch to configuration")]
    for n in rig.nodes:
        out.append((n.sdo_rx, UPLOAD_1000, f"SDO upload to {n}"))
        for p in n.rpdos:
            out.append((p["cob"], bytes(p["len"] + 1), f"too long RPDO to {n} (EMCY 8220)"))
        if n.sync is not None:
            out.append((n.sync, b"\x01\x02", f"SYNC of a wrong length to {n} (EMCY 8240)"))
        if n.hb_consumer:
            out.append((0x700 + HB_PRODUCER, b"\x05", f"heartbeat for the consumer in {n}"))
    return out


def test_extended_frames_are_ignored(rig):
    """29-bit frames whose ID equals a listened 11-bit COB-ID, or has it in its low 11 bits, with payloads that would
    act if the frame were taken as the 11-bit one: nothing is answered, no state or value changes."""
    rig.set_state(OP)
    values = {(n.id, p["cob"]): rig.value(n, *p["entries"][0][:2]) for n in rig.nodes for p in n.rpdos}
    hb = next((n for n in rig.nodes if n.hb_consumer), None)
    if hb is not None:  # a consumer waiting for the first heartbeat: a 29-bit one would start it (EMCY 8130 later)
        rig.sdo_write(hb, 0x1016, 1, struct.pack("<I", HB_PRODUCER << 16 | HB_CONSUMER_MS))
    cases = [(cob, data, what) for cob, data, what in listened(rig)]
    cases += [(0x700 + rig.guard.id, b"", f"guard request to {rig.guard}")]
    for cob, data, what in cases:
        for eff_id in (cob, (0x15555 << 11) | cob):
            mark = rig.mark()
            rtr = what.startswith("guard")
            rig.send(eff_id, data, eff=True, rtr=rtr, dlc=1 if rtr else None)
            if cob == 0x7E5:
                rig.send(0x7E5, LSS_INQUIRE_ID)  # answered only if the 29-bit frame had switched to configuration
            case = f"29-bit {frame_text(eff_id, data, rtr, True)} ({what})"
            rig.check(case, "eff", mark, [], via_guard=True)  # a guard request is answered in any NMT state
            assert rig.listed_states() == rig.state, f"{case}\n  rule: {RULES['eff']}"
    mark = rig.mark()
    time.sleep(2 * HB_CONSUMER_MS / 1000)
    rig.check("29-bit heartbeat: no consumer timeout afterwards", "eff", mark, [])
    assert rig.listed_states() == rig.state, RULES["eff"]
    for n in rig.nodes:
        for p in n.rpdos:
            assert rig.value(n, *p["entries"][0][:2]) == values[(n.id, p["cob"])], f"{n}: 29-bit RPDO applied"


@pytest.mark.socketcan
def test_error_frames_are_logged_and_ignored(rig):
    """CAN error frames whose class bits equal a listened COB-ID, carrying that service's payload: a port that took
    the 11-bit part of the ID would act on them. The kernel lets any raw socket send them on vcan."""
    rig.set_state(OP)
    cases = [(cob, data, what) for cob, data, what in listened(rig) if cob != 0x000]  # class 0 is no error frame
    for cob, data, what in cases:
        mark = rig.mark()
        rig.send_error_frame(cob, data)
        if cob == 0x7E5:
            rig.send(0x7E5, LSS_INQUIRE_ID)
        case = f"error frame class 0x{cob:03X} data {data.hex(' ')} ({what})"
        rig.check(case, "err", mark, [], via_guard=True)
        assert rig.listed_states() == rig.state, f"{case}\n  rule: {RULES['err']}"
        assert rig.emu.log_contains(f"CAN error frame (class 0x{cob:03X}"), f"error frame 0x{cob:03X} not logged"
    assert sum("CAN error frame" in line for line in rig.emu.err_lines) == len(cases)
    assert rig.listed_states() == rig.state


def iface_mtu():
    return int(Path(f"/sys/class/net/{IFACE}/mtu").read_text())


def set_mtu(mtu):
    cmd = f"ip link set {IFACE} down && ip link set {IFACE} mtu {mtu} && ip link set {IFACE} up"
    return subprocess.run(["sh", "-c", cmd], capture_output=True, text=True)


@pytest.fixture
def fd_capable_bus():
    """vcan0 with the CAN FD MTU (72). vcan interfaces are created with it on current kernels; where it is 16, it is
    raised (the interface must be down for that, so before any socket is opened) and put back afterwards."""
    before = iface_mtu()
    if before < 72:
        r = set_mtu(72)
        if r.returncode != 0:
            pytest.skip(f"{IFACE} has MTU {before} and cannot be switched to CAN FD here: {r.stderr.strip()}")
    yield
    if before < 72:
        assert set_mtu(before).returncode == 0 and iface_mtu() == before


@pytest.mark.socketcan
def test_can_fd_frames_are_ignored(fd_capable_bus, rig):
    """FD frames (BRS set) of length 8, 12 and 64 on every listened COB-ID, starting with a payload that acts as a
    classic frame would. An FD-enabled socket of the test sees them on the bus; the emulator must not."""
    rig.set_state(OP)
    fd_tx = socket.socket(socket.PF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
    fd_rx = socket.socket(socket.PF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
    try:
        for s in (fd_tx, fd_rx):
            s.setsockopt(SOL_CAN_RAW, CAN_RAW_FD_FRAMES, 1)
            s.bind((IFACE,))
        fd_rx.settimeout(2.0)
        sent = 0
        for cob, data, what in listened(rig):
            for length in (8, 12, 64):
                mark = rig.mark()
                fd_tx.send(struct.pack("=IBBBB64s", cob, length, CANFD_BRS, 0, 0, data.ljust(length, b"\0")))
                sent += 1
                if cob == 0x7E5:
                    rig.send(0x7E5, LSS_INQUIRE_ID)
                case = f"CAN FD {cob:03X} [{length}] {data.hex(' ')} ({what})"
                rig.check(case, "fd", mark, [], via_guard=True)  # a guard request is answered in any NMT state
                assert rig.listed_states() == rig.state, f"{case}\n  rule: {RULES['fd']}"
        seen = 0
        while seen < sent:  # the FD frames really were on the bus (the check above is not vacuous)
            f = fd_rx.recv(72)
            seen += len(f) == 72 and f[4] in (8, 12, 64) and (f[5] & CANFD_BRS) != 0
        assert seen == sent
    finally:
        fd_tx.close()
        fd_rx.close()
    assert rig.listed_states() == rig.state


# ---- random garbage -------------------------------------------------------------------------------------------

def read_only_values(rig):
    """Every read-only communication object of up to 4 bytes with a fixed value (not 0x1001/0x1003, which EMCYs
    change), read over SDO."""
    out = {}
    for n in rig.nodes:
        for index in range(0x1000, 0x2000):
            if index not in n.od or index in (0x1001, 0x1003):
                continue
            obj = n.od[index]
            compound = isinstance(obj, (canopen.objectdictionary.Record, canopen.objectdictionary.Array))
            subs = obj.values() if compound else [obj]
            for var in subs:
                if var.access_type in ("ro", "const") and var.data_type not in (canopen.objectdictionary.VISIBLE_STRING,
                                                                                  canopen.objectdictionary.DOMAIN):
                    out[(n.id, index, var.subindex)] = rig.sdo_read(n, index, var.subindex)
    return out


def garbage(rng, rig, count):
    """count random frames on the listened COB-IDs: random DLC, data, remote flag, sometimes 29-bit. Left out: the
    NMT commands addressed to the nodes (a stop or reset is a valid command, not garbage) and LSS switch-to-
    configuration (a random activate-bit-timing could then legitimately silence a node for minutes)."""
    cobs = sorted({c for c, _, _ in listened(rig)} | {0x700 + rig.guard.id})
    ids = {0} | {n.id for n in rig.nodes}
    for _ in range(count):
        cob = rng.choice(cobs)
        dlc = rng.randrange(9)
        data = bytearray(rng.randbytes(dlc))
        rtr = cob == 0x700 + rig.guard.id or rng.random() < 0.15
        eff = rng.random() < 0.05
        if cob == 0x000 and dlc >= 2 and data[0] in set(NMT_CMD.values()) | {0x81, 0x82} and data[1] in ids:
            data[0] ^= 0x40
        if cob == 0x7E5 and dlc >= 2 and data[0] == 0x04 and data[1] == 0x01:
            data[1] = 0x00
        yield cob, bytes(data), rtr, eff, dlc


def test_random_garbage_in_operational(rig):
    seed = int(os.environ.get(SEED_ENV, "20260707"), 0)
    count = int(os.environ.get(FRAMES_ENV, "3000"), 0)
    print(f"random garbage: {count} frames, seed {seed} (set {SEED_ENV} to repeat or change)")
    rig.set_state(OP)
    for n in rig.nodes:
        rig.sdo_write(n, 0x1017, 0, struct.pack("<H", 200))
    c = next((n for n in rig.nodes if n.hb_consumer), None)
    if c is not None:  # the consumer path too: the garbage on its producer's COB-ID starts and feeds it
        rig.sdo_write(c, 0x1016, 1, struct.pack("<I", HB_PRODUCER << 16 | 100))
    before = read_only_values(rig)
    assert len(before) > 30  # 0x1000, 0x1018, 0x1014, SDO/PDO parameters of all three nodes
    rng = random.Random(seed)
    start = rig.mark()
    for i, (cob, data, rtr, eff, dlc) in enumerate(garbage(rng, rig, count)):
        rig.send(cob, data, rtr=rtr, eff=eff, dlc=dlc)
        if i % 100 == 99:  # alive, and the emulator's receive queue stays short (nothing dropped by the kernel)
            n = rig.nodes[(i // 100) % len(rig.nodes)]
            try:
                assert rig.sdo_read(n, 0x1000, 0) == struct.pack("<I", n.device_type)
            except AssertionError as e:
                raise AssertionError(f"seed {seed}, after frame {i + 1}: {e}") from e
    for n in rig.nodes:  # every node answers SDO correctly (and every garbage frame has been handled)
        assert rig.sdo_read(n, 0x1000, 0) == struct.pack("<I", n.device_type), f"seed {seed}"
    end = rig.mark()
    assert rig.emu.proc.poll() is None, f"seed {seed}: canopen-emu died"
    boot_ups = [(c_, d) for c_, d in rig.outputs(start) if c_ in {0x700 + n.id for n in rig.nodes} and d == b"\x00"]
    assert boot_ups == [], f"seed {seed}: a node restarted during the garbage: {boot_ups}"
    assert rig.listed_states() == rig.state, f"seed {seed}"
    after = read_only_values(rig)
    changed = {k: (before[k].hex(), after[k].hex()) for k in before if before[k] != after[k]}
    assert not changed, f"seed {seed}: read-only objects changed: {changed}"
    for n in rig.nodes:
        serial = n.od[0x1018][4].default + n.id  # emulator.md: EDS serial + command-line node-ID
        assert after[(n.id, 0x1018, 4)] == struct.pack("<I", serial)
        assert after[(n.id, 0x1000, 0)] == struct.pack("<I", n.device_type)
    # Heartbeats go on: two more from every node, Operational, after the garbage (period 200 ms; bound generous).
    def heartbeats():
        return {n.id: [d for c_, d in rig.outputs(end) if c_ == 0x700 + n.id] for n in rig.nodes}
    Deadline(5.0).until(lambda: all(len(b) >= 2 for b in heartbeats().values()))
    beats = heartbeats()
    assert all(b[:2] == [bytes([STATE_BYTE[OP]])] * 2 for b in beats.values()), f"seed {seed}: heartbeats {beats}"
    rig.stopped = True
    assert rig.emu.stop() == 0, f"seed {seed}: canopen-emu did not exit cleanly"
