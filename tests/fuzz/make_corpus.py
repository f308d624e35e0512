#!/usr/bin/env python3
"""Writes the seed corpora of the fuzz targets (tests/fuzz/corpus/<target>/) in the harness's input format.
The Linux-side targets (nvm_file, script, control) have their own formats: see the head of each target_*.c and
nvm_file_seeds / script_seeds / control_seeds below.

Seeds: the 79 test vectors of the facts sheet (../shared/docs/canopen-facts.md, section 11) for every target
(node-ID 5, the vector's preconditions set up through the bus), plus device scenarios per device (HV release,
inputs and faults through control commands, stored parameters, power cycles, corrupted NVM, segmented SDO).

    tests/fuzz/make_corpus.py            rewrite the corpus directories (files not generated here are removed)
    tests/fuzz/make_corpus.py --check    exit 1 if the committed corpus differs from what this script writes

Input format (docs/fuzzing.md has the full table): 4 header bytes, then records. A record starts with a tag:
  0x00-0x9F frame: low nibble = identifier class (0 NMT, 1 SYNC 0x080, 2 TIME 0x100, 3-6 RPDO1-4 0x200-0x500+id,
            7-9 SDO 0x600+id, 10 0x700+id, 11 0x700+byte, 12-13 LSS 0x7E5, 14 0x080*byte+id, 15 raw u16),
            high nibble = time step before it (0-3 none, 4 u8 x 100 us, 5 u8 ms, 6 u16 ms, 7 u16 x 10 ms,
            8 u16 s, 9 u32 us); then the class's bytes, a flags byte (DLC 0-15 | 0x10 RTR | 0x20 EFF | 0x40 ERR
            | 0x80 no process call after it) and min(DLC, 8) data bytes.
  0xA0-0xBF time: bits 0-2 amount (u8 x 10 us, u8 ms, u16 ms, u16 x 100 ms, u16 s, u32 us, to the next deadline,
            u64 us), bit 3 jump (no process calls on the way), bit 4 no process call at the end.
  0xC0-0xCF process call (bit 0: co_node_process without the device model).
  0xD0-0xDF application call / control command (target-specific bytes).
  0xE0-0xE1 power cycle.   0xE2-0xE7 NVM corruption: area, mode, bytes.   0xE8-0xEB port faults.
  0xEC-0xEF LSS frame 0x7E5 [8].   0xF0-0xFF SDO request 0x600+id [8] (odd tag: no process call after it).
"""
import os
import re
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
OWN = 5


def u16(v):
    return struct.pack("<H", v & 0xFFFF)


def u32(v):
    return struct.pack("<I", v & 0xFFFFFFFF)


def load_command_table():
    """The device target's command templates, in order (indices go into the input)."""
    src = open(os.path.join(HERE, "target_device.c"), encoding="utf-8").read()
    body = re.search(r"static const char \*const commands\[\] = \{(.*?)\};", src, re.S).group(1)
    body = re.sub(r"/\*.*?\*/", "", body, flags=re.S)
    return [bytes(s, "utf-8").decode("unicode_escape") for s in re.findall(r'"((?:[^"\\]|\\.)*)"', body)]


COMMANDS = load_command_table()


class Seq:
    """One input: header + records, with helpers named after what they do on the bus."""

    def __init__(self, hdr=(0, OWN, 0, 0), own=OWN):
        self.b = bytearray(hdr)
        self.own = own

    # ---- frames ----
    def rx(self, cid, data=b"", dt_us=0, rtr=False, eff=False, err=False, dlc=None, process=True):
        data = bytes(data)
        dlc = len(data) if dlc is None else dlc
        dtc, dtb = 0, b""
        if dt_us:
            if dt_us % 1000 == 0 and dt_us // 1000 < 256:
                dtc, dtb = 5, bytes([dt_us // 1000])
            elif dt_us % 1000 == 0 and dt_us // 1000 < 65536:
                dtc, dtb = 6, u16(dt_us // 1000)
            elif dt_us % 1000000 == 0 and dt_us // 1000000 < 65536:
                dtc, dtb = 8, u16(dt_us // 1000000)
            elif dt_us < 2**32:
                dtc, dtb = 9, u32(dt_us)
            else:
                self.advance(dt_us)
        o = self.own
        if cid == 0x000:
            cls, extra = 0, b""
        elif cid == 0x080:
            cls, extra = 1, b""
        elif cid == 0x100:
            cls, extra = 2, b""
        elif cid in (0x200 + o, 0x300 + o, 0x400 + o, 0x500 + o):
            cls, extra = 3 + (cid - 0x200 - o) // 0x100, b""
        elif cid == 0x600 + o:
            cls, extra = 7, b""
        elif cid == 0x700 + o:
            cls, extra = 10, b""
        elif 0x701 <= cid <= 0x77F:
            cls, extra = 11, bytes([cid - 0x700])
        elif cid == 0x7E5:
            cls, extra = 12, b""
        elif (cid - o) % 0x80 == 0 and 0 <= (cid - o) // 0x80 < 16:
            cls, extra = 14, bytes([(cid - o) // 0x80])
        else:
            cls, extra = 15, u16(cid)
        flags = (dlc & 0x0F) | (0x10 if rtr else 0) | (0x20 if eff else 0) | (0x40 if err else 0)
        flags |= 0 if process else 0x80
        payload = (data + bytes(8))[: min(dlc, 8)]
        self.b += bytes([(dtc << 4) | cls]) + dtb + extra + bytes([flags]) + payload
        return self

    def sdo(self, *data, dt_us=0):
        return self.rx(0x600 + self.own, bytes(data), dt_us=dt_us)

    def sdo_write(self, index, sub, value, size):
        cmd = 0x23 | ((4 - size) << 2)
        return self.sdo(cmd, index & 0xFF, index >> 8, sub, *u32(value))

    def sdo_read(self, index, sub):
        return self.sdo(0x40, index & 0xFF, index >> 8, sub, 0, 0, 0, 0)

    def nmt(self, cs, node=None):
        return self.rx(0x000, bytes([cs, self.own if node is None else node]))

    def lss(self, *data):
        self.b += bytes([0xEC]) + (bytes(data) + bytes(8))[:8]
        return self

    def rtr(self, cid, dt_us=0):
        return self.rx(cid, b"", dt_us=dt_us, rtr=True)

    # ---- time ----
    def advance(self, us, jump=False):
        mode = 0x08 if jump else 0
        if us % 1000000 == 0 and us // 1000000 < 65536:
            self.b += bytes([0xA4 | mode]) + u16(us // 1000000)
        elif us % 1000 == 0 and us // 1000 < 65536:
            self.b += bytes([0xA2 | mode]) + u16(us // 1000)
        elif us < 2**32:
            self.b += bytes([0xA5 | mode]) + u32(us)
        else:
            self.b += bytes([0xA7 | mode]) + struct.pack("<Q", us)
        return self

    def ms(self, n):
        return self.advance(n * 1000)

    def to_deadline(self):
        self.b += bytes([0xA6])
        return self

    def process(self, direct=False):
        self.b += bytes([0xC1 if direct else 0xC0])
        return self

    # ---- power, NVM, port ----
    def power(self):
        self.b += bytes([0xE0])
        return self

    def nvm_flip(self, area, offset, xor):
        self.b += bytes([0xE2, area, 0]) + u16(offset) + bytes([xor])
        return self

    def nvm_truncate(self, area, length):
        self.b += bytes([0xE2, area, 1]) + u16(length)
        return self

    def nvm_reseal(self, area, own_signature=True):
        self.b += bytes([0xE2, area, 3, 1 if own_signature else 0])
        return self

    def nvm_param_record(self, index, sub, value_bytes):
        self.b += bytes([0xE2, 0, 4, 1]) + u16(index) + bytes([sub, len(value_bytes)]) + bytes(value_bytes)
        return self

    def nvm_lss(self, node_id, bit_timing):
        self.b += bytes([0xE2, 1, 4, node_id, bit_timing])
        return self

    def nvm_erase(self, area):
        self.b += bytes([0xE2, area, 5])
        return self

    def port_busy(self, n):
        self.b += bytes([0xE8, n])
        return self

    def port_io_error(self):
        self.b += bytes([0xE9])
        return self

    def nvm_fail_write(self):
        self.b += bytes([0xEA])
        return self

    # ---- device control commands (device targets) ----
    def cmd(self, template, *args):
        """A command of target_device.c's table; args fill its placeholders in order."""
        self.b += bytes([0xD0, 0x00, COMMANDS.index(template)])
        kinds = re.findall(r"\{(.)\}", template)
        assert len(kinds) == len(args), template
        for k, v in zip(kinds, args):
            if k == "i":
                self.b += bytes([0xFF]) + u16(v)
            elif k == "u":
                self.b += bytes([0xFF, v & 0xFF])
            elif k == "x":
                self.b += bytes([v & 0xFF])
            elif k == "X":
                self.b += bytes([0xFF]) + u16(v)
            elif k == "f":
                whole, tenth = v
                self.b += bytes([whole & 0xFF, tenth])
            else:
                self.b += bytes([v])
        return self

    # ---- core target application calls ----
    def app_emcy(self, code, reg=0x01, msef=None):
        self.b += bytes([0xD0, 0]) + u16(code) + bytes([reg, 1 if msef else 0]) + bytes(msef or bytes(5))
        return self

    def app_emcy_clear(self, code, msef=None):
        self.b += bytes([0xD0, 1]) + u16(code) + bytes([1 if msef else 0]) + bytes(msef or bytes(5))
        return self

    def app_input(self, sub, value):
        self.b += bytes([0xD0, 2, sub - 1, value])
        return self

    def app_trigger(self, n):
        self.b += bytes([0xD0, 6, n])
        return self

    def app_lss(self, how, value=0):
        """how: 0 pending node-ID, 1 pending bit timing, 2 store, 3 apply the pending bit timing."""
        self.b += bytes([0xD0, 7, how, value])
        return self

    def data(self):
        return bytes(self.b)


# ---- The facts sheet's vectors (section 11), node-ID 5 ------------------------------------------------------

def guarding(s):
    return s.sdo_write(0x100C, 0, 100, 2).sdo_write(0x100D, 0, 3, 1)


def hb(s, ms):
    return s.sdo_write(0x1017, 0, ms, 2)


def vectors(hdr):
    V = {}

    def v(n, name):
        def deco(fn):
            s = Seq(hdr)
            fn(s)
            V["v%02d-%s" % (n, name)] = s.data()
            return fn
        return deco

    @v(1, "power-on")
    def _(s): s.ms(10)

    @v(2, "start-heartbeats")
    def _(s): hb(s, 100).nmt(0x01).ms(250)

    @v(3, "stop-broadcast")
    def _(s): hb(s, 100).nmt(0x01).ms(150).nmt(0x02, 0).ms(250)

    @v(4, "stopped-to-preop")
    def _(s): hb(s, 100).nmt(0x02).ms(150).nmt(0x80).ms(250)

    @v(5, "nmt-other-node")
    def _(s): s.nmt(0x01, 6).ms(10)

    @v(6, "nmt-dlc1")
    def _(s): s.rx(0x000, [0x01]).ms(10)

    @v(7, "nmt-dlc3")
    def _(s): s.rx(0x000, [0x01, 0x05, 0x00]).ms(10)

    @v(8, "reset-comm")
    def _(s): s.nmt(0x01).nmt(0x82).ms(10)

    @v(9, "reset-node-broadcast")
    def _(s): s.nmt(0x01).nmt(0x81, 0).ms(10)

    @v(10, "write-heartbeat")
    def _(s): s.sdo(0x2B, 0x17, 0x10, 0x00, 0xE8, 0x03, 0, 0).ms(3500)

    @v(11, "sdo-in-stopped")
    def _(s): s.nmt(0x02).sdo(0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0).ms(10)

    @v(12, "guard-first")
    def _(s): guarding(s).rtr(0x705)

    @v(13, "guard-toggle")
    def _(s): guarding(s).rtr(0x705).rtr(0x705, dt_us=50000)

    @v(14, "guard-operational")
    def _(s): guarding(s).rtr(0x705).rtr(0x705, dt_us=50000).nmt(0x01).rtr(0x705, dt_us=50000)

    @v(15, "guard-stopped")
    def _(s):
        guarding(s).rtr(0x705).rtr(0x705, dt_us=50000).nmt(0x01).rtr(0x705, dt_us=50000).nmt(0x02)
        s.rtr(0x705, dt_us=50000)

    @v(16, "life-guarding-timeout")
    def _(s): guarding(s).rtr(0x705).ms(400).rtr(0x705).ms(50)

    @v(17, "guard-with-heartbeat")
    def _(s): guarding(s); hb(s, 1000).rtr(0x705).ms(1100)

    @v(18, "read-device-type")
    def _(s): s.sdo_read(0x1000, 0)

    @v(19, "read-vendor")
    def _(s): s.sdo_read(0x1018, 1)

    @v(20, "read-identity-count")
    def _(s): s.sdo_read(0x1018, 0)

    @v(21, "read-heartbeat")
    def _(s): hb(s, 1000).sdo_read(0x1017, 0)

    @v(22, "read-no-object")
    def _(s): s.sdo_read(0x2100, 0)

    @v(23, "read-no-subindex")
    def _(s): s.sdo_read(0x1018, 5)

    @v(24, "write-read-only")
    def _(s): s.sdo(0x23, 0x00, 0x10, 0x00, 0x01, 0, 0, 0)

    @v(25, "read-write-only")
    def _(s): s.sdo_read(0x6200, 1)

    @v(26, "length-too-high")
    def _(s): s.sdo(0x23, 0x17, 0x10, 0x00, 0xE8, 0x03, 0, 0)

    @v(27, "length-too-low")
    def _(s): s.sdo(0x2F, 0x17, 0x10, 0x00, 0xE8, 0, 0, 0)

    @v(28, "size-not-indicated-u16")
    def _(s): s.sdo(0x22, 0x17, 0x10, 0x00, 0xE8, 0x03, 0, 0)

    @v(29, "size-not-indicated-u8")
    def _(s): s.sdo(0x22, 0x19, 0x10, 0x00, 0x05, 0, 0, 0).sdo_read(0x1019, 0)

    @v(30, "unknown-command")
    def _(s): s.sdo(0xE0, 0x00, 0x10, 0x00, 0, 0, 0, 0)

    @v(31, "segmented-initiate")
    def _(s): s.sdo(0x21, 0x17, 0x10, 0x00, 0x02, 0, 0, 0).ms(1200)

    @v(32, "block-download")
    def _(s): s.sdo(0xC6, 0x17, 0x10, 0x00, 0x02, 0, 0, 0)

    @v(33, "segment-idle")
    def _(s): s.sdo(0x60, 0, 0, 0, 0, 0, 0, 0)

    @v(34, "client-abort")
    def _(s): s.sdo(0x80, 0x00, 0x10, 0x00, 0, 0, 0, 0)

    @v(35, "sdo-dlc4")
    def _(s): s.rx(0x605, [0x40, 0x00, 0x10, 0x00])

    @v(36, "clear-history")
    def _(s): s.sdo(0x2F, 0x03, 0x10, 0x00, 0, 0, 0, 0)

    @v(37, "history-nonzero")
    def _(s): s.sdo(0x2F, 0x03, 0x10, 0x00, 0x01, 0, 0, 0)

    @v(38, "history-empty-read")
    def _(s): s.sdo_read(0x1003, 1)

    @v(39, "store")
    def _(s): s.sdo(0x23, 0x10, 0x10, 0x01, 0x73, 0x61, 0x76, 0x65).power().sdo_read(0x1017, 0)

    @v(40, "store-bad-signature")
    def _(s): s.sdo(0x23, 0x10, 0x10, 0x01, 0, 0, 0, 0)

    @v(41, "restore")
    def _(s):
        hb(s, 500).sdo(0x23, 0x10, 0x10, 0x01, 0x73, 0x61, 0x76, 0x65)
        s.sdo(0x23, 0x11, 0x10, 0x01, 0x6C, 0x6F, 0x61, 0x64).nmt(0x81).sdo_read(0x1017, 0)

    @v(42, "sync-overflow-1")
    def _(s): s.sdo(0x2F, 0x19, 0x10, 0x00, 0x01, 0, 0, 0)

    @v(43, "upload-eight-bytes")
    def _(s): s.sdo_read(0x2006, 0)

    @v(44, "sdo-other-node")
    def _(s): s.rx(0x606, [0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0])

    def pdo_setup(s):
        s.sdo_write(0x1800, 5, 100, 2)   # TPDO1 event timer 100 ms

    @v(45, "map-while-valid")
    def _(s): s.sdo(0x2F, 0x00, 0x16, 0x00, 0, 0, 0, 0)

    @v(46, "cob-id-restricted")
    def _(s): s.sdo_write(0x1400, 1, 0x80000205, 4).sdo(0x23, 0x00, 0x14, 0x01, 0x05, 0x07, 0, 0)

    @v(47, "rpdo-in-preop")
    def _(s): s.rx(0x205, [0x11, 0x22, 0x33, 0x44])

    @v(48, "tpdo-on-start")
    def _(s): pdo_setup(s); s.nmt(0x01).ms(350)

    @v(49, "rpdo-short")
    def _(s): s.nmt(0x01).rx(0x205, [0xAA, 0xBB]).ms(10)

    @v(50, "rpdo-long")
    def _(s): s.nmt(0x01).rx(0x205, [0x55, 0x66, 0x77, 0x88, 0x99]).ms(10)

    @v(51, "rpdo-length-recovered")
    def _(s): s.nmt(0x01).rx(0x205, [0xAA, 0xBB]).rx(0x205, [1, 2, 3, 4], dt_us=10000).ms(10)

    @v(52, "tpdo-sync-type2")
    def _(s):
        s.sdo_write(0x1800, 2, 2, 1).nmt(0x01)
        for _i in range(4):
            s.rx(0x080, b"", dt_us=10000)

    @v(53, "sync-wrong-length")
    def _(s): s.rx(0x080, [0x01]).ms(10)

    @v(54, "heartbeat-consumer-timeout")
    def _(s): s.sdo_write(0x1016, 1, 0x000A00C8, 4).rx(0x70A, [0x05]).ms(250).rx(0x70A, [0x05])

    @v(55, "eltex-warning")
    def _(s): s.nmt(0x01).ms(100)

    @v(56, "eltex-clear-warning")
    def _(s): s.sdo(0x22, 0x03, 0x20, 0x02, 0x12, 0, 0, 0).ms(10)

    @v(57, "lss-inquire-waiting")
    def _(s): s.lss(0x5E)

    @v(58, "lss-configuration")
    def _(s): s.lss(0x04, 0x01)

    @v(59, "lss-inquire-node-id")
    def _(s): s.lss(0x04, 0x01).lss(0x5E)

    @v(60, "lss-inquire-vendor")
    def _(s): s.lss(0x04, 0x01).lss(0x5A)

    @v(61, "lss-inquire-serial")
    def _(s): s.lss(0x04, 0x01).lss(0x5D)

    @v(62, "lss-configure-node-id")
    def _(s): s.lss(0x04, 0x01).lss(0x11, 0x0A)

    @v(63, "lss-node-id-invalid")
    def _(s): s.lss(0x04, 0x01).lss(0x11, 0x80)

    @v(64, "lss-bit-timing")
    def _(s): s.lss(0x04, 0x01).lss(0x13, 0x00, 0x04)

    @v(65, "lss-bit-timing-reserved")
    def _(s): s.lss(0x04, 0x01).lss(0x13, 0x00, 0x05)

    @v(66, "lss-bit-timing-selector")
    def _(s): s.lss(0x04, 0x01).lss(0x13, 0x01, 0x04)

    @v(67, "lss-activate")
    def _(s): s.lss(0x04, 0x01).lss(0x13, 0x00, 0x03).lss(0x15, 0x64, 0x00).ms(50).ms(100).ms(100)

    @v(68, "lss-store")
    def _(s): s.lss(0x04, 0x01).lss(0x11, 0x0A).lss(0x17).power()

    @v(69, "lss-new-id-after-reset")
    def _(s): s.lss(0x04, 0x01).lss(0x11, 0x0A).lss(0x04, 0x00).nmt(0x82).ms(10)

    def select(s, serial=0x00ABCDEF):
        s.lss(0x40, *u32(0x0000024E)).lss(0x41, *u32(0x00001234)).lss(0x42, *u32(0x00010002))
        s.lss(0x43, *u32(serial))

    @v(70, "lss-switch-selective")
    def _(s): select(s)

    @v(71, "lss-switch-selective-mismatch")
    def _(s): select(s, 0x01ABCDEF)

    @v(72, "lss-identify-non-configured")
    def _(s): s.lss(0x4C)

    @v(73, "lss-identify-remote")
    def _(s):
        s.lss(0x46, *u32(0x24E)).lss(0x47, *u32(0x1234)).lss(0x48, *u32(0)).lss(0x49, *u32(0xFFFFFFFF))
        s.lss(0x4A, *u32(0)).lss(0x4B, *u32(0xFFFFFFFF))

    def fastscan(s):
        s.lss(0x51, 0, 0, 0, 0, 0x80, 0, 0)
        s.lss(0x51, *u32(0x0000024E), 0, 0, 1).lss(0x51, *u32(0x00001234), 0, 1, 2)
        s.lss(0x51, *u32(0x00010002), 0, 2, 3).lss(0x51, *u32(0x00ABCDEF), 0, 3, 0)

    @v(74, "fastscan-reset")
    def _(s): s.lss(0x51, 0, 0, 0, 0, 0x80, 0, 0)

    @v(75, "fastscan-full")
    def _(s): fastscan(s); s.lss(0x5E)

    @v(76, "fastscan-configure-start")
    def _(s): fastscan(s); s.lss(0x11, 0x0A).lss(0x04, 0x00).ms(10)

    @v(77, "unconfigured-ignores-nmt-sdo")
    def _(s): s.nmt(0x01, 0).rx(0x67F, [0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0]).ms(10)

    @v(78, "fastscan-configured")
    def _(s): s.lss(0x51, 0, 0, 0, 0, 0x80, 0, 0)

    @v(79, "lss-dlc2")
    def _(s): s.rx(0x7E5, [0x5E, 0x00])

    return V


UNCONFIGURED = {72, 74, 75, 76, 77}


def vector_seeds(base_hdr, unconfigured_hdr):
    out = {}
    for name, data in vectors(base_hdr).items():
        if int(name[1:3]) not in UNCONFIGURED:
            out[name] = data
    for name, data in vectors(unconfigured_hdr).items():
        if int(name[1:3]) in UNCONFIGURED:
            out[name] = data
    return out


# ---- Core scenarios beyond the vectors ------------------------------------------------------------------------

def core_scenarios():
    S = {}
    # Segmented SDO on (option bit 1): upload of a 24-byte string, download of a 20-byte one, then a timeout.
    s = Seq((0x02, OWN, 0, 0))
    s.sdo_read(0x1009, 0).sdo(0x60, 0, 0, 0, 0, 0, 0, 0).sdo(0x70, 0, 0, 0, 0, 0, 0, 0)
    s.sdo(0x60, 0, 0, 0, 0, 0, 0, 0).sdo(0x70, 0, 0, 0, 0, 0, 0, 0)
    s.sdo(0x21, 0x05, 0x20, 0x00, 20, 0, 0, 0).sdo(0x00, *b"abcdefg").sdo(0x10, *b"hijklmn").sdo(0x05, *b"opqrst\0")
    s.sdo(0x21, 0x05, 0x20, 0x00, 20, 0, 0, 0).sdo(0x00, *b"abcdefg").ms(1500)
    S["segmented-sdo"] = s.data()
    # Block SDO on (option bit 7, with segmented): upload of the 24-byte string in blocks of 2 with a lost segment,
    # a download with CRC, one with a lost segment, a protocol switch, and a timeout in the middle of a block.
    s = Seq((0x82, OWN, 0, 0))
    s.sdo(0xA4, 0x09, 0x10, 0x00, 2, 0, 0, 0).sdo(0xA3, 0, 0, 0, 0, 0, 0, 0).sdo(0xA2, 1, 3, 0, 0, 0, 0, 0)
    s.sdo(0xA2, 3, 127, 0, 0, 0, 0, 0).sdo(0xA1, 0, 0, 0, 0, 0, 0, 0)
    s.sdo(0xC6, 0x05, 0x20, 0x00, 9, 0, 0, 0).sdo(0x01, *b"1234567").sdo(0x82, *b"89\0\0\0\0\0")
    s.sdo(0xD5, 0xC3, 0x31, 0, 0, 0, 0, 0)
    s.sdo(0xC4, 0x05, 0x20, 0x00, 0, 0, 0, 0).sdo(0x01, *b"abcdefg").sdo(0x03, *b"XXXXXXX").sdo(0x84, *b"YYY\0\0\0\0")
    s.sdo(0x01, *b"hijklmn").sdo(0x82, *b"opq\0\0\0\0").sdo(0xD1, 0xD2, 0x10, 0, 0, 0, 0, 0)
    s.sdo(0xA4, 0x00, 0x10, 0x00, 127, 4, 0, 0).port_busy(3).sdo(0xA4, 0x09, 0x10, 0x00, 127, 0, 0, 0)
    s.sdo(0xA3, 0, 0, 0, 0, 0, 0, 0).ms(5).ms(1500)
    S["block-sdo"] = s.data()
    # MPDO: RPDO1 becomes a DAM consumer (mapping sub 0 = 0xFF), TPDO1 a SAM producer without a scanner list; DAM
    # frames to this node, to all, to another node, to a missing object, and a short one.
    s = Seq()
    s.sdo_write(0x1400, 1, 0x80000205, 4).sdo_write(0x1600, 0, 0xFF, 1).sdo_write(0x1400, 1, 0x205, 4)
    s.sdo_write(0x1800, 1, 0x80000185, 4).sdo_write(0x1A00, 0, 0xFE, 1).sdo_write(0x1800, 1, 0x185, 4).nmt(0x01)
    s.rx(0x205, [0x85, 0x00, 0x20, 0x00, 0xE8, 0x03, 0, 0]).rx(0x205, [0x80, 0x00, 0x63, 0x01, 1, 2, 3, 4])
    s.rx(0x205, [0x86, 0x00, 0x20, 0x00, 1, 0, 0, 0]).rx(0x205, [0x85, 0x00, 0x30, 0x00, 1, 0, 0, 0])
    s.rx(0x205, [0x85, 0x00, 0x20]).app_trigger(0).ms(50)
    S["mpdo"] = s.data()
    # TPDO timing: event timer 100 ms, inhibit 20 ms, then 50 ms inhibit (> ... timer) on a re-validated PDO.
    s = Seq()
    s.sdo_write(0x1800, 1, 0x80000185, 4).sdo_write(0x1800, 3, 200, 2).sdo_write(0x1800, 5, 100, 2)
    s.sdo_write(0x1800, 1, 0x185, 4).nmt(0x01).ms(450)
    s.app_emcy(0x1234).ms(5).app_emcy_clear(0x1234).ms(300)
    s.sdo_write(0x1800, 1, 0x80000185, 4).sdo_write(0x1800, 3, 2000, 2).sdo_write(0x1800, 1, 0x185, 4)
    s.nmt(0x80).nmt(0x01).ms(1000).advance(3_600_000_000, jump=True).ms(500)
    S["tpdo-inhibit-event-timer"] = s.data()
    # Mapping procedure on TPDO2 (0x1801 invalid by default): map 0x6000:01 + 0x6401:01, validate, inputs move.
    s = Seq()
    s.sdo_write(0x1A01, 0, 0, 1).sdo_write(0x1A01, 1, 0x60000108, 4).sdo_write(0x1A01, 2, 0x64010110, 4)
    s.sdo_write(0x1A01, 0, 2, 1).sdo_write(0x1801, 1, 0x285, 4).nmt(0x01).ms(10)
    s.app_input(1, 7).process().app_input(2, 9).process().app_trigger(1).process().ms(10)
    S["tpdo-mapping-procedure"] = s.data()
    # RPDO mapping to the REAL32 setpoint and the write-only output, synchronous type, deadline monitoring.
    s = Seq()
    s.sdo_write(0x1401, 1, 0x80000305, 4).sdo_write(0x1601, 0, 0, 1).sdo_write(0x1601, 1, 0x20040020, 4)
    s.sdo_write(0x1601, 2, 0x62000108, 4).sdo_write(0x1601, 0, 2, 1).sdo_write(0x1401, 2, 1, 1)
    s.sdo_write(0x1401, 5, 50, 2).sdo_write(0x1401, 1, 0x305, 4).nmt(0x01)
    s.rx(0x305, [0, 0, 0x80, 0x3F, 1]).rx(0x080, b"", dt_us=10000).ms(200)
    S["rpdo-sync-deadline"] = s.data()
    # SYNC consumer: cycle period, window, counter overflow, timeout and recovery.
    s = Seq()
    s.sdo_write(0x1019, 0, 4, 1).sdo_write(0x1006, 0, 10000, 4).sdo_write(0x1007, 0, 5000, 4).nmt(0x01)
    for i in range(1, 6):
        s.rx(0x080, [i], dt_us=10000)
    s.ms(100).rx(0x080, [1])
    S["sync-counter-timeout"] = s.data()
    # Heartbeat consumer with two producers, boot-up pause, timeout and recovery; 0x1016 duplicate refused.
    s = Seq()
    s.sdo_write(0x1016, 1, 0x000A0064, 4).sdo_write(0x1016, 2, 0x000B0064, 4).sdo_write(0x1016, 3, 0x000A0032, 4)
    s.rx(0x70A, [0x05]).rx(0x70B, [0x7F]).ms(50).rx(0x70A, [0x00]).ms(200).rx(0x70B, [0x05]).ms(150)
    S["heartbeat-consumer"] = s.data()
    # EMCY: inhibit time, queue while Stopped (more than the queue holds), history overflow.
    s = Seq()
    s.sdo_write(0x1015, 0, 100, 2).nmt(0x02)
    for code in range(0x1000, 0x100A):
        s.app_emcy(code)
    s.nmt(0x01).ms(20)
    for code in range(0x1000, 0x100A):
        s.app_emcy_clear(code)
    s.ms(50).sdo_read(0x1003, 8).sdo(0x2F, 0x03, 0x10, 0x00, 0, 0, 0, 0)
    S["emcy-inhibit-stopped-history"] = s.data()
    # Store, corrupt, power cycle; store, restore, reset; a stored record of another length.
    s = Seq()
    hb(s, 300).sdo_write(0x2000, 0, 1000, 2).sdo(0x23, 0x10, 0x10, 0x01, 0x73, 0x61, 0x76, 0x65)
    s.nvm_flip(0, 20, 0x40).power().ms(400).sdo(0x23, 0x10, 0x10, 0x02, 0x73, 0x61, 0x76, 0x65)
    s.nvm_param_record(0x1017, 0, [0x10]).power().nvm_reseal(0, False).power()
    s.sdo(0x23, 0x11, 0x10, 0x04, 0x6C, 0x6F, 0x61, 0x64).nmt(0x81).ms(10)
    s.nvm_param_record(0x1A00, 0, [9]).nvm_param_record(0x1600, 1, [0x20, 0x01, 0x00, 0x62]).power().nmt(0x01)
    S["store-restore-corrupt"] = s.data()
    # LSS: stored node-ID and bit timing, switch with a busy port, store failure.
    s = Seq()
    s.nvm_lss(0x21, 3).power().lss(0x04, 0x01).lss(0x13, 0x00, 0x02).port_busy(3).lss(0x15, 0x0A, 0x00)
    s.ms(5).ms(10).ms(10).nvm_fail_write().lss(0x17).nvm_fail_write()
    s.lss(0x17).lss(0x11, 0xFF).lss(0x04, 0x00).nmt(0x82, 0x21).ms(10).lss(0x4C)
    S["lss-stored-busy"] = s.data()
    # LSS configuration through the API (a device's own menu): pending bit timing, store, apply, node-ID.
    s = Seq()
    s.app_lss(1, 3).app_lss(1, 5).app_lss(2).app_lss(3).app_lss(0, 0x30).app_lss(2).power().nmt(0x82, 0x30).ms(10)
    S["lss-api"] = s.data()
    # Port busy: frames wait in the TX queue, overflow it, then go out.
    s = Seq()
    hb(s, 10).nmt(0x01).port_busy(20).ms(100).process().ms(5)
    s.port_io_error().ms(30).port_io_error().ms(30)
    S["port-busy-io-error"] = s.data()
    # Hooks: writes refused, reads hidden, EMCY from hooks (header byte 2: actions 0x0F, preset 1).
    s = Seq((0x00, OWN, 0x2F, 0x00))
    s.sdo_write(0x2004, 0, 0x3F800000, 4).sdo_write(0x2003, 0, 1, 4).sdo_read(0x2005, 0).nmt(0x01).ms(100)
    s.nmt(0x82).ms(10)
    S["hooks-actions"] = s.data()
    # Late wake-ups: hours and a huge jump with heartbeat, guarding, consumer and SYNC all armed.
    s = Seq()
    hb(s, 100).sdo_write(0x1016, 1, 0x000A0064, 4).sdo_write(0x1006, 0, 100000, 4).rx(0x70A, [0x05]).rx(0x080, b"")
    s.nmt(0x01).advance(7_200_000_000).advance(10**15, jump=True).ms(250).to_deadline().to_deadline()
    S["late-wakeups"] = s.data()
    return S


# ---- Device scenarios -------------------------------------------------------------------------------------------

def device_common(hdr):
    S = {}
    s = Seq(hdr)
    s.cmd("show").cmd("get 0x1017").cmd("set 0x1017 {i}", 1000).ms(1100).cmd("emcy {X}", 0x3210)
    s.nmt(0x01).ms(50).cmd("emcy-clear {X}", 0x3210).ms(50).cmd("power-cycle").ms(10)
    s.cmd("set 0x1010:01 1702257011").cmd("power-cycle").cmd("set 0x1011:01 1684107116").nmt(0x81).ms(10)
    S["common-commands"] = s.data()
    s = Seq(hdr)
    s.sdo(0x23, 0x10, 0x10, 0x01, 0x73, 0x61, 0x76, 0x65).nvm_flip(0, 18, 0x01).power().ms(10)
    s.nvm_reseal(0, True).power().nvm_truncate(2, 3).power().nvm_erase(2).power().ms(10)
    s.nvm_lss(0x22, 4).power().lss(0x04, 0x01).lss(0x5E).lss(0x17).ms(10)
    S["nvm-corruption"] = s.data()
    s = Seq(hdr)
    hb(s, 100).nmt(0x01).ms(500).advance(3_600_000_000).advance(86_400_000_000, jump=True).ms(300)
    s.nmt(0x02).ms(200).nmt(0x80).ms(200)
    S["hours-running"] = s.data()
    return S


def pro_ionizer_scenarios(hdr):
    S = device_common(hdr)
    s = Seq(hdr)   # HV release by RPDO, loads, warnings, clearing through 0x2003
    s.nmt(0x01).rx(0x205, [0x01]).ms(500).cmd("load {u} {i}", 1, 2000).cmd("load 1 short").ms(300)
    s.cmd("temperature {i}", 65).ms(200).cmd("temperature {i}", 80).ms(200).cmd("temperature {i}", 25).ms(200)
    s.sdo(0x22, 0x03, 0x20, 0x02, 0x12, 0, 0, 0).sdo(0x22, 0x03, 0x20, 0x01, 0x01, 0, 0, 0)
    s.sdo_read(0x6401, 1).sdo_read(0x2001, 3).rx(0x205, [0x00]).ms(200)
    S["pi-release-loads-faults"] = s.data()
    s = Seq(hdr)   # inputs of every variant group, keypad, bit-timing menu
    s.cmd("hw-release on").cmd("keypad release on").cmd("speed {u} {i}", 2, 300).cmd("efield 1 {i} {i}", 500, 20)
    s.cmd("sensor A1 3").cmd("supply {i}", 19000).ms(300).cmd("supply {i}", 24000).cmd("bit-timing {u}", 3)
    s.power().ms(10).cmd("bit-timing 9").power().ms(10).cmd("bit-timing 4").power().nmt(0x01).ms(1000)
    S["pi-inputs-bit-timing"] = s.data()
    for i, variant in enumerate(["monitor", "speed", "efield", "extbox", "basic", "module"], start=2):
        s = Seq((i, OWN, 0, 0))
        s.nmt(0x01).rx(0x205, [0x01]).ms(300).sdo_read(0x2001, 0x0E).sdo_read(0x6401, 5).cmd("status")
        S["pi-variant-%s" % variant] = s.data()
    return S


def sds_scenarios(hdr):
    S = device_common(hdr)
    s = Seq(hdr)   # release with the 10 s timeout, pollution, load, faults
    s.nmt(0x01).rx(0x205, [0x01]).ms(2000).cmd("pollution {u}", 85).ms(500).cmd("load {i}", 300).ms(500)
    s.ms(9000).rx(0x205, [0x01]).cmd("supply {f}", (18, 5)).ms(300).cmd("supply 24.0").ms(300)
    s.cmd("error {x}", 0x01).cmd("warning {x}", 0x12).ms(100).sdo(0x22, 0x03, 0x20, 0x02, 0x12, 0, 0, 0)
    s.cmd("faults").cmd("model").sdo_read(0x6401, 1).sdo_read(0x2001, 9).ms(100)
    S["sds-release-pollution-faults"] = s.data()
    s = Seq((2, OWN, 0, 0))   # variant E
    s.nmt(0x01).sdo(0x22, 0x00, 0x62, 0x01, 0x01, 0, 0, 0).ms(1500).cmd("temperature {i}", 72).ms(400)
    s.cmd("air {u}", 40).cmd("conductance {i}", 9000).ms(400).sdo_read(0x6000, 2)
    S["sds-variant-e"] = s.data()
    return S


def buerkert_scenarios(hdr):
    S = device_common(hdr)
    s = Seq(hdr)   # set-point by SDO (REAL32 50.0) and RPDO, flow follows, faults, NAMUR, mode hand
    s.sdo_write(0x2540, 1, 0x42480000, 4).nmt(0x01).ms(3000).rx(0x205, [0, 0, 0xC8, 0x42]).ms(2000)
    s.cmd("flow-fault on").ms(500).cmd("flow-fault off").cmd("valve-fault on").ms(500).cmd("valve-fault off")
    s.cmd("mode hand").sdo_write(0x2540, 1, 0x41200000, 4).cmd("setpoint {f}", (25, 5)).cmd("mode auto")
    s.cmd("supply {f}", (20, 0)).cmd("temperature {i}", 80).ms(1000).cmd("status")
    S["bk-setpoint-faults-modes"] = s.data()
    s = Seq(hdr)   # segmented SDO upload of the 32-byte device name and a download into it
    s.sdo_read(0x2002, 1)
    for t in range(5):
        s.sdo(0x60 | (0x10 if t % 2 else 0), 0, 0, 0, 0, 0, 0, 0)
    s.sdo(0x21, 0x02, 0x20, 0x01, 10, 0, 0, 0).sdo(0x00, *b"flow-co").sdo(0x17, *b"ntrl\0\0\0").sdo_read(0x2002, 1)
    s.sdo(0x21, 0x02, 0x20, 0x01, 40, 0, 0, 0).sdo(0x21, 0x02, 0x20, 0x01, 10, 0, 0, 0).ms(1500)
    S["bk-segmented-sdo"] = s.data()
    s = Seq(hdr)   # block SDO: upload of the device name in blocks of 3, a download into it with CRC
    s.sdo(0xA4, 0x02, 0x20, 0x01, 3, 0, 0, 0).sdo(0xA3, 0, 0, 0, 0, 0, 0, 0).sdo(0xA2, 3, 3, 0, 0, 0, 0, 0)
    s.sdo(0xA2, 2, 127, 0, 0, 0, 0, 0).sdo(0xA2, 2, 127, 0, 0, 0, 0, 0).sdo(0xA1, 0, 0, 0, 0, 0, 0, 0)
    s.sdo(0xC6, 0x02, 0x20, 0x01, 9, 0, 0, 0).sdo(0x01, *b"1234567").sdo(0x82, *b"89\0\0\0\0\0")
    s.sdo(0xD5, 0xC3, 0x31, 0, 0, 0, 0, 0).sdo_read(0x2002, 1).ms(1500)
    S["bk-block-sdo"] = s.data()
    s = Seq(hdr)   # TPDOs with inhibit 500 ms / event 1000 ms, other TPDOs enabled, late wake-up
    s.sdo_write(0x1801, 1, 0x285, 4).nmt(0x01).ms(1200).advance(1_700_000, jump=True).ms(100).ms(1000)
    S["bk-tpdo-timers"] = s.data()
    return S


# ---- The Linux side: NVM files, scripts, control lines (target_nvm_file.c, target_script.c, target_control.c) ----

# target_nvm_file.c: names (low nibble of a file record) and kinds (bits 4-6).
A_PARAMS, A_LSS, A_DEVICE, T_PARAMS, T_LSS, T_DEVICE, J_JOURNAL, J_TMP, F_OTHER, F_OLD = range(10)
RAW, SEALED, PARAMS, EMPTY, DIR, DIR_FULL, FIFO, LINK = range(8)
LINK_OTHER, LINK_OLD, LINK_MISSING, LINK_PARAMS = range(4)
DEVICE_BLOB = {0: b"PIC2\x02" + bytes(15), 1: b"SDSM\x02" + bytes(15), 2: b"BKF1\x02" + bytes(31)}
LSS_OK = {0: (0x20, 3), 1: (0x20, 3), 2: (0x20, 2)}   # node-ID 32 and a bit timing of each device's table


class NvmSeq:
    """One input of fuzz_nvm_file: header (class, node-ID), then file records and steps."""

    def __init__(self, cls, node_id=0):
        self.b = bytearray([cls, node_id])
        self.cls = cls

    def file(self, name, kind, data=b""):
        self.b.append((kind << 4) | name)
        if kind in (RAW, SEALED):
            self.b += u16(len(data)) + data
        return self

    @staticmethod
    def obj(index, sub, value):
        """An object and value: explicit index/sub (selector bit 15), length, bytes."""
        return u16(0x8000) + u16(index) + bytes([sub, len(value)]) + bytes(value)

    def params(self, name, records):
        """A parameter blob of (index, sub, value bytes) records."""
        self.b.append((PARAMS << 4) | name)
        self.b.append(len(records))
        for index, sub, value in records:
            self.b += self.obj(index, sub, value)
        return self

    def lss(self, name, node_id, bit_timing):
        return self.file(name, SEALED, bytes([0, 0, 0, 0, node_id, bit_timing]))

    def device(self, name):
        return self.file(name, SEALED, DEVICE_BLOB[self.cls])

    def journal(self, name, areas):
        return self.file(name, SEALED, b"CONVJ1" + bytes(areas) + b"\n")

    def link(self, name, target):
        self.b += bytes([(LINK << 4) | name, target])
        return self

    def write(self, index, sub, value):
        self.b += bytes([0x80]) + self.obj(index, sub, value)
        return self

    def save(self, sdo=False, edit=0, param=0, restart=False):
        self.b += bytes([0xA0, (1 if sdo else 0) | (edit << 1) | (8 if restart else 0)]) + u16(param)
        return self

    def time(self, tens_of_seconds):
        self.b += bytes([0xB0, tens_of_seconds - 1])
        return self

    def power(self, restart=False):
        self.b.append(0xC1 if restart else 0xC0)
        return self

    def data(self):
        return bytes(self.b)


def nvm_file_seeds():
    S = {}
    # Heartbeat 1000 ms (every device), an Eltex TPDO period of 500 ms, an unknown object, a wrong length.
    stored = [(0x1017, 0, u16(1000)), (0x2002, 1, u16(500)), (0x5FFF, 1, b"\x01"), (0x1017, 0, b"\x01")]
    for c, name in ((0, "pi"), (1, "sds"), (2, "bk")):
        bt = LSS_OK[c][1]
        S[name + "-nothing-stored"] = NvmSeq(c).data()
        S[name + "-stored-areas"] = (NvmSeq(c).params(A_PARAMS, stored).lss(A_LSS, 0x20, bt).device(A_DEVICE)
                                     .save(sdo=True).data())
        S[name + "-crash-after-journal"] = (NvmSeq(c).file(A_PARAMS, RAW, b"old")
                                            .params(T_PARAMS, stored).lss(T_LSS, 0x21, bt).device(T_DEVICE)
                                            .journal(J_JOURNAL, [1, 1, 1]).save().data())
        S[name + "-crash-before-journal"] = (NvmSeq(c).params(T_PARAMS, stored).lss(T_LSS, 0x21, bt)
                                             .journal(J_TMP, [1, 1, 0]).save(restart=True).data())
        S[name + "-journal-byte-2"] = (NvmSeq(c).params(T_PARAMS, stored).lss(T_LSS, 0x23, bt)
                                       .file(J_JOURNAL, RAW, b"CONVJ1\x02\x01\x00\n").save().data())
        S[name + "-journal-partly-done"] = (NvmSeq(c).params(A_PARAMS, stored).lss(T_LSS, 0x22, bt).device(T_DEVICE)
                                            .journal(J_JOURNAL, [1, 1, 0]).save().data())
        S[name + "-directories"] = (NvmSeq(c).file(A_PARAMS, DIR).file(T_LSS, DIR_FULL).file(J_JOURNAL, DIR)
                                    .save(sdo=True).power(restart=True).data())
        S[name + "-fifos"] = (NvmSeq(c).file(A_PARAMS, FIFO).file(A_DEVICE, FIFO).file(J_JOURNAL, FIFO)
                              .file(T_PARAMS, FIFO).save().data())
        S[name + "-links"] = (NvmSeq(c).params(F_OTHER, stored).link(A_PARAMS, LINK_OTHER).link(T_PARAMS, LINK_OLD)
                              .link(J_JOURNAL, LINK_MISSING).link(A_LSS, LINK_PARAMS).save(restart=True).data())
        S[name + "-damaged"] = (NvmSeq(c).file(A_PARAMS, EMPTY).file(A_LSS, RAW, b"COL1\x20")
                                .file(A_DEVICE, RAW, DEVICE_BLOB[c]).save().data())
        S[name + "-writes-edits"] = (NvmSeq(c).write(0x1017, 0, u16(2000)).write(0x2002, 1, u16(300))
                                     .save(sdo=True).save(edit=1).save(edit=2, param=20).save(edit=3, param=5)
                                     .save(restart=True).data())
        S[name + "-time-and-edits"] = (NvmSeq(c).save().time(7).file(A_DEVICE, SEALED, DEVICE_BLOB[c])
                                       .file(T_PARAMS, RAW, b"x").power().time(13).power(restart=True).data())
        S[name + "-forged-lss"] = NvmSeq(c).lss(A_LSS, 0xFF, 5).save().lss(A_LSS, 0x20, 9).power().data()
    return S


def text_seeds(pairs):
    return {name: text.encode("latin-1") if isinstance(text, str) else text for name, text in pairs}


def script_seeds():
    return text_seeds([
        ("faults-example", "# faults.script\n@1000 show 16\n@+500 emcy 16 0x3210 0x05 0x01 0x07\n"
                           "@+2000 emcy-clear 16 0x3210 0x01 0x07\n@+100 quit\n"),
        ("times-every-form", "@0 list\n@+500 show 16\nhelp\n  # comment\n\n\t@0010\tget 16 0x1017\r\n@+0 list\n"
                             "@7\n@3 set 16 0x1017 500\n"),
        ("limit-exactly", "@999999999 show 16\n@+1 quit\n@1000000000 list"),
        ("limit-sum-beyond", "@600000000 show 16\n@+400000001 quit\n"),
        ("limit-beyond", "@1000000001 quit\n"),
        ("huge-time", "@99999999999999999999999 quit\n"),
        ("bad-fraction", "@5 list\n@1.5 show 16\n"),
        ("bad-forms", "@inf quit\n@0x10 show\n@-1 x\n@ 5 x\n@1e300 x\n@+ x\n@5x\n"),
        ("no-newline", "@5 show 16"),
        ("line-2047", "@1 " + "x" * 2044 + "\n@2 quit\n"),
        ("line-2048", "@1 list\n@2 " + "x" * 2045 + "\n@3 quit\n"),
        ("nul-byte", "@5 list\n@6 show\x0016\n"),
        ("empty", ""),
    ])


def control_seeds():
    return text_seeds([
        ("common-commands", "list\nshow 16\nget 16 0x1017\nset 16 0x1017 500\nemcy 17 0x3210 0x05 1 2 3 4 5\n"
                            "emcy-clear 17 0x3210 1 2 3 4 5\npower-cycle 18\nhelp\nhelp 16\nshow all\nget 18 2002:1\n"),
        ("device-commands", "status 16\nload 16 1 2000\ntemperature 20 70\npollution 17 80\nfaults 21\nmodel 17\n"
                            "setpoint 18 50.5\nmode 22 hand\nflow-fault 18 on\nerror 16 0x05\nclear-error 16 0x05\n"),
        ("store-power-cycle", "set 16 0x1017 1000\nset 16 0x1010:01 0x65766173\npower-cycle 16\nget 16 0x1017\n"
                              "set 18 0x2001:02 0x30\nset 18 0x2001:04 1\nlist\n"),
        ("errors", "frobnicate 16\nshow 99\nshow\nshow 0x10\nshow 010\nset 16 0x1017 70000\nget 16 zz\n"
                   "emcy 16 0\nshow \"16\"\n\"show\" 17\n# comment\n   \t\r\n"),
        ("quit-in-the-middle", "show 16\nquit\nshow 17\n"),
        ("quit-forms", "  quit   # bye\n"),
        ("quit-quoted", "\"quit\" 16\nlist\n"),
        ("exit", "exit\nlist\n"),
        ("quit-too-many-words", "quit " + " ".join(["a"] * 16) + "\nlist\n"),
        ("quit-without-newline", "list\nquit"),
        ("long-line-ending-in-quit", "x" * 2100 + "quit\nshow 16\n"),
        ("long-last-line-without-newline", "show 16\n" + "x" * 2100),
        ("line-2047-then-2048", "#" + " " * 2046 + "\n#" + " " * 2047 + "\nlist\n"),
        ("nul-then-quit", "show 16\x00quit\nlist\n\x00\nquit\n"),
        ("crlf", "show 16\r\nquit\r\n"),
        # the JSON framing (docs/control-protocol.md) and the subscriptions
        ("json-requests", '{"id":1,"cmd":"hello"}\n{"id":2,"cmd":"list"}\n{"id":3,"cmd":"get","node":16,"object":"0x1018:04"}\n'
                          '{"id":"a","cmd":"set","node":"16","object":"0x1017","value":700}\n'
                          '{"id":4,"cmd":"set","node":20,"object":4119,"sub":0,"value":70000}\n'
                          '{"id":5,"cmd":"show","node":"all@vcan1"}\n{"id":6,"cmd":"power-cycle","node":17}\n'
                          '{"id":7,"cmd":"status","node":16}\n{"id":8,"cmd":"emcy","node":18,"args":["0x3210",5,1,2,3,4,5]}\n'
                          '{"id":9,"cmd":"help"}\n{"id":10,"cmd":"get","node":"16@vcan1","object":"1017"}\n'),
        ("json-subscribe", '{"id":1,"cmd":"subscribe","events":"all","nodes":[16,"18@vcan1"]}\npower-cycle 16\n'
                           'set 16 0x1010:01 0x65766173\n{"id":2,"cmd":"subscribe","events":["frame"],"frames":"0x700/0x780"}\n'
                           '{"id":3,"cmd":"unsubscribe","events":["nmt"]}\nsubscribe nmt,boot-up,store 17 21@vcan1\n'
                           'power-cycle 17\nunsubscribe\n'),
        ("json-errors", '{bad\n[1,2]\n{"id":1.5,"cmd":"list"}\n{"cmd":3}\n{"cmd":"get","node":16}\n'
                        '{"cmd":"get","node":16,"object":"0x1017","nod":1}\n{"cmd":"list","cmd":"quit"}\n'
                        '{"cmd":"set","node":"all","object":"0x1017","value":1}\n{"cmd":"quit","node":16}\nlist\n'),
        ("json-objects", '{"id":1,"cmd":"objects","node":16}\n{"id":2,"cmd":"objects","node":"17","values":true}\n'
                         '{"id":3,"cmd":"objects","node":20,"values":false}\n{"id":4,"cmd":"objects","node":"all"}\n'
                         '{"id":5,"cmd":"objects","node":16,"values":1}\n{"id":6,"cmd":"objects"}\n'),
        ("json-get-many", '{"id":1,"cmd":"get","node":16,"objects":["0x1017","0x1016:05","0x5555","1008"]}\n'
                          '{"id":2,"cmd":"get","node":17,"objects":[]}\n{"id":3,"cmd":"get","node":16,"objects":[4119]}\n'
                          '{"id":4,"cmd":"get","node":16,"objects":["0x1017"],"object":"0x1017"}\n'),
        ("json-frame-filters", '{"id":1,"cmd":"subscribe","events":["frame"],"frames":["0x000","0x080/0x780","0x711"]}\n'
                               '{"id":2,"cmd":"subscribe","events":["frame"],"frames":[]}\n'
                               'subscribe frame 0x700/0x780 0x591 0x000 0x080 0x100\nsubscribe frame 0x580/0x780 bad\n'
                               '{"id":3,"cmd":"subscribe","events":["frame"],"frames":["0x181x","0x18FF0000x/0x1FFF0000",'
                               '"0x00000000x/0x0","0x0x"]}\n{"id":4,"cmd":"subscribe","events":["frame"],"frames":"0x800"}\n'
                               'subscribe frame 0x181x 0x1FFFFFFFx 0x181/0x7FFx\nsubscribe frame x 0xx 0x20000000x\n'),
        ("json-help-commands", '{"id":1,"cmd":"help","node":16}\n{"id":2,"cmd":"help","node":"all"}\n{"id":3,"cmd":"help"}\n'),
        ("json-quit", '{"id":"q","cmd":"quit"}\nlist\n'),
        ("protocol-faults", "fault 16 sdo-ignore 2\nfault 17 sdo-ignore 30% 7\nfault 18 sdo-delay 100\n"
                            "fault 20 sdo-abort 0x1017 0x08000020\nfault 21 heartbeat-stop\nfault 22 heartbeat-jitter 50\n"
                            "fault 16 heartbeat-state 0x04\nfault 18 tpdo-freeze 1\nfault 22 tpdo-drop 1 2\n"
                            "fault 18 tpdo-length 1 3\nfault 17 emcy-burst 3 0x5000\nfault 20 reboot\nfault 21 bus-off 50\n"
                            "fault 16 lss-silent\nfaults 16\nfaults all\nfault-clear 16 sdo-ignore\nfault-clear all\n"
                            "fault 16 weather\nfault 16 tpdo-freeze 9\n"
                            '{"id":1,"cmd":"fault","node":17,"args":["sdo-delay",20]}\n{"id":2,"cmd":"faults","node":17}\n'),
        ("json-exit-in-blanks", ' \t {"cmd":"exit","id":null}  \nlist\n'),
        ("json-long-line", '{"cmd":"list","x":"' + "y" * 2100 + '"}\n{"cmd":"quit"}\n'),
        # a restricted (web) session: the first byte 0x01 (target_control.c); quit, exit, export-dcf refused
        ("restricted-refusals", "\x01show 16\nquit\nexit # bye\nexport-dcf 16 x.dcf\n\"quit\" 16\nlist\n"
                                '{"id":1,"cmd":"quit"}\n{"id":2,"cmd":"exit","id":3}\n'
                                '{"id":4,"cmd":"export-dcf","node":16,"args":["x.dcf"]}\n{"id":5,"cmd":"list"}\n'),
        ("restricted-commands", "\x01set 16 0x1017 500\nfault 17 heartbeat-stop\npower-cycle 18\nhelp 16\n"
                                '{"id":1,"cmd":"subscribe","events":"all"}\n{"id":2,"cmd":"objects","node":17}\n'
                                "quit " + " ".join(["a"] * 16) + "\nquit"),
        # a line server's session (a control socket's client): the first byte 0x02 (target_control.c); a first line
        # that is an HTTP request line ends it with nothing run, a browser's cross-origin POST of control lines
        ("http-post", "\x02POST /x HTTP/1.1\r\nHost: 127.0.0.1:5020\r\nContent-Type: text/plain\r\n"
                      "Content-Length: 40\r\n\r\nset 16 0x1017 1234\n{\"cmd\":\"quit\"}\nquit\n"),
        ("http-get-no-cr", "\x02GET / HTTP/1.0\nlist\nquit\n"),
        ("http-like-lines", "\x02list HTTP/1.1\nGET / HTTP/1.1\n{\"id\":\"GET / HTTP/1.1\",\"cmd\":\"hello\"}\nquit\n"),
        ("http-long-first-line", "\x02GET /" + "a" * 2100 + " HTTP/1.1\r\nquit\n"),
    ])


def eds_seeds():
    """The reader's feature files (tests/eds/files/) and small fragments of the forms real files use."""
    files = os.path.join(HERE, "..", "eds", "files")
    seeds = {name: open(os.path.join(files, name), "rb").read() for name in sorted(os.listdir(files))}
    device = ("[DeviceInfo]\nVendorNumber=1\nNrOfRXPDO=1\nNrOfTXPDO=1\n[DummyUsage]\nDummy0005=1\n"
              "[MandatoryObjects]\nSupportedObjects=3\n1=0x1000\n2=0x1001\n3=0x1018\n"
              "[1000]\nParameterName=t\nDataType=7\nAccessType=ro\nDefaultValue=0\n"
              "[1001]\nParameterName=e\nDataType=5\nAccessType=ro\n"
              "[1018]\nParameterName=id\nObjectType=9\nSubNumber=2\n"
              "[1018sub0]\nParameterName=n\nDataType=5\nAccessType=ro\nDefaultValue=1\n"
              "[1018sub1]\nParameterName=v\nDataType=7\nAccessType=ro\nDefaultValue=1\n")
    seeds["fragment-pdos"] = (device + "[OptionalObjects]\nSupportedObjects=4\n1=0x1400\n2=0x1600\n3=0x1800\n4=0x1A00\n"
        "[1400]\nParameterName=r\nObjectType=9\nSubNumber=2\n[1400sub0]\nParameterName=n\nDataType=5\nAccessType=ro\n"
        "DefaultValue=1\n[1400sub1]\nParameterName=c\nDataType=7\nAccessType=rw\nDefaultValue=$NODEID+0x200\n"
        "[1600]\nParameterName=m\nObjectType=8\nSubNumber=3\n[1600sub0]\nParameterName=n\nDataType=5\nAccessType=rw\n"
        "DefaultValue=2\n[1600sub1]\nParameterName=a\nDataType=7\nAccessType=rw\nDefaultValue=0x00050008\n"
        "[1600sub2]\nParameterName=b\nDataType=7\nAccessType=rw\nDefaultValue=0x10010008\nParameterValue=0x00050008\n"
        "[1800]\nParameterName=t\nObjectType=9\nSubNumber=2\n[1800sub0]\nParameterName=n\nDataType=5\nAccessType=ro\n"
        "DefaultValue=1\n[1800sub1]\nParameterName=c\nDataType=7\nAccessType=rw\nDefaultValue=0x80000000+$NODEID+0x180\n"
        "[1A00]\nParameterName=m\nCompactSubObj=2\nObjectType=8\nDataType=7\nAccessType=rw\nDefaultValue=0x10010008\n"
        "[1A00Value]\nNrOfEntries=1\n2=0x10180120\n").encode()
    seeds["fragment-values"] = (device + "[ManufacturerObjects]\nSupportedObjects=3\n1=0x2000\n2=0x2001\n3=0x2002\n"
        "[2000]\nParameterName=r\nDataType=8\nAccessType=rw\nDefaultValue=0x3F800000\nLowLimit=-1e38\nHighLimit=3.5\n"
        "[2001]\nParameterName=u\nDataType=0x0B\nAccessType=rw\nDefaultValue=\xc3\xa4\xf0\x9f\x98\x80 ;x\n"
        "[2002]\nParameterName=i\nDataType=0x12\nAccessType=rw\nDefaultValue=-010 ; c\nLowLimit=-0x8000000000\n"
        "[DeviceComissioning]\nNodeID=0x7F\nBaudrate=1000\n").encode()
    # A DCF whose string value held line breaks when written raw: [2006] defined twice, a key repeated.
    seeds["duplicate-section"] = (device + "[ManufacturerObjects]\nSupportedObjects=2\n1=0x2005\n2=0x2006\n"
        "[2005]\nParameterName=s\nDataType=9\nAccessType=rw\nDefaultValue=a\nParameterValue=x\n[2006]\n"
        "ParameterValue=7\n[2006]\nParameterName=n\nDataType=5\nAccessType=rw\nDefaultValue=3\nParameterValue=3\n"
        "[DeviceComissioning]\nNodeID=255\n").encode()
    # Size cases (target_eds.c: 0x01, K, HEAD, 0x02, UNIT, 0x02, TAIL; UNIT 2^K times, '@' the copy's number):
    # 65536 named sections; 65536 objects (the 2048 PDO ones left out, their types wrong); a CompactSubObj=254
    # object with a default of 4 MiB. Each took seconds to hours, or gigabytes, before the reader was linear.
    size = lambda k, head, unit, tail="": bytes([1, k]) + head.encode() + b"\x02" + unit + b"\x02" + tail.encode()  # noqa: E731
    seeds["size-named-sections"] = size(16, device, b"[N@]\nK=1\n")
    seeds["size-objects"] = size(16, device, b"[@]\nParameterName=o\nDataType=7\nAccessType=rw\nDefaultValue=0x@\n")
    seeds["size-compact-default"] = size(16, device + "[ManufacturerObjects]\nSupportedObjects=1\n1=0x2000\n[2000]\n"
                                         "ParameterName=c\nObjectType=8\nCompactSubObj=254\nDataType=9\n"
                                         "AccessType=rw\nDefaultValue=", b"x" * 64, "\n")
    return seeds


def rules_seeds():
    """The rules of tests/eds/rules/drive.yaml and small ones, each with records that drive the CiA 402 drive."""
    import struct
    drive = open(os.path.join(HERE, "..", "eds", "rules", "drive.yaml"), "rb").read()
    wait = lambda ms: bytes([0x00, min(255, ms // 10 - 1), 0, 0, 0])                     # noqa: E731  10 ms units
    control = lambda cw: bytes([0x40]) + struct.pack("<H", cw) + b"\0\0"              # noqa: E731
    write = lambda sel, v: bytes([0x80, sel]) + struct.pack("<i", v)[:3]               # noqa: E731
    pp = (write(4, 50000) + write(2, 4000) + control(0x06) + control(0x0F) + control(0x1F) + wait(200)
          + control(0x0F) + control(0x02) + wait(50))
    velocity = write(1, 3) + write(5, 1500) + control(0x06) + control(0x0F) + wait(300) + bytes([0xE0, 0x10, 0, 0, 0])
    return {
        "drive-position": drive + b"\0" + pp,
        "drive-velocity": drive + b"\0" + velocity + wait(1000),
        "walk-counter": b'objects:\n  "0x2002": {random_walk: {start: 480, step: 2, min: 470, max: 490, seed: 3, '
                        b'every_ms: 1}}\n  "0x2001": {counter: {start: 5, step: 2, every_ms: 10, wrap: 40}}\n'
                        b"\0" + wait(500) + bytes([0xE0, 0xFF, 0xFF, 0, 0]) + wait(20),
        "follow-steps-alarm": b'objects:\n  "0x2006": {follow: {object: "0x2005", lag_ms: 50, gain: 2}}\n'
                              b'  "0x2004": {steps: [[1, 5], [7, 10]]}\nalarms:\n  - {object: "0x2006", above: 5, '
                              b'hysteresis: 1, emcy: 0x2310}\n\0' + write(0, 0x410000) + wait(400),
        "bad-yaml": b"objects: [\n",
        "bad-keys": b'profile: cia402\nobjects:\n  "0x6064": {sine: {amplitude: x}}\n',
        # what the YAML reader refuses as it reads (devices/eds_class/rules_yaml.c): anchors and aliases, nesting past 16
        # levels (flow and block), a key twice, a second document, a NUL in a value; and one object spelled twice
        "anchor-alias": b'objects:\n  "0x2000": &w {sine: {amplitude: 5, period_ms: 100}}\n  "0x2003": *w\n\0'
                        + wait(100),
        "alias-alone": b'objects:\n  "0x2004": {steps: [*s, [1, 5]]}\n',
        "deep-flow": b'objects:\n  "0x2004": {steps: ' + b"[" * 40 + b"]" * 40 + b"}\n",
        "deep-block": b"".join(b" " * i + b"a:\n" for i in range(20)) + b" " * 20 + b"1\n",
        "duplicate-key": b'tick_ms: 5\nobjects:\n  "0x2001": {counter: {step: 1, step: 2}}\ntick_ms: 7\n',
        "second-document": b'objects:\n  "0x2001": {constant: 1}\n---\nobjects:\n  "0x2002": {constant: 2}\n',
        "nul-in-value": b'objects:\n  "0x2001\\0x": {constant: 1}\n',
        "same-object-twice": b'objects:\n  "0x2001": {constant: 1}\n  "0x2001:0": {constant: 2}\n',
        # a long steps list on a 1 ms tick (a step's value is found by bisection): near the 4 kB of a fuzz input
        "many-steps": b'tick_ms: 1\nobjects:\n  "0x2004": {steps: ['
                      + b", ".join(b"[%d, %d]" % (i % 9, 1 + i % 3) for i in range(360)) + b"]}\n\0"
                      + wait(300) + bytes([0xC0, 0, 0, 0, 0]) + wait(50),
    }


def msgpack(v):
    """The msgpack bytes of v (str keys, bool, None, int, float, bytes, list, dict), as python-can's packb writes them."""
    if v is None:
        return b"\xc0"
    if isinstance(v, bool):
        return b"\xc3" if v else b"\xc2"
    if isinstance(v, int):
        if 0 <= v < 0x80:
            return bytes([v])
        if -32 <= v < 0:
            return struct.pack(">b", v)
        if 0 <= v < 0x100:
            return b"\xcc" + bytes([v])
        if 0 <= v < 0x10000:
            return b"\xcd" + struct.pack(">H", v)
        if 0 <= v < 0x100000000:
            return b"\xce" + struct.pack(">I", v)
        return b"\xd3" + struct.pack(">q", v)
    if isinstance(v, float):
        return b"\xcb" + struct.pack(">d", v)
    if isinstance(v, str):
        b = v.encode()
        return (bytes([0xA0 | len(b)]) if len(b) < 32 else b"\xd9" + bytes([len(b)])) + b
    if isinstance(v, bytes):
        return b"\xc4" + bytes([len(v)]) + v
    if isinstance(v, list):
        return bytes([0x90 | len(v)]) + b"".join(msgpack(x) for x in v)
    return bytes([0x80 | len(v)]) + b"".join(msgpack(k) + msgpack(x) for k, x in v.items())


def udp_datagram_seeds():
    """python-can's udp_multicast datagrams: frames of each kind, FD and error frames, and ones it refuses."""
    def message(**over):
        m = {"timestamp": 1767225600.5, "arbitration_id": 0x612, "is_extended_id": False, "is_remote_frame": False,
             "is_error_frame": False, "channel": None, "dlc": 8, "data": bytes([0x40, 0x18, 0x10, 1, 0, 0, 0, 0]),
             "is_fd": False, "bitrate_switch": False, "error_state_indicator": False}
        m.update(over)
        return msgpack(m)
    return {
        "sdo-request": message(),
        "heartbeat": message(arbitration_id=0x710, dlc=1, data=b"\x05"),
        "dlc0": message(arbitration_id=0x080, dlc=0, data=b""),
        "extended": message(arbitration_id=0x18FF0001, is_extended_id=True, dlc=3, data=b"\x01\x02\x03"),
        "remote": message(arbitration_id=0x711, is_remote_frame=True, dlc=1, data=b""),
        "fd": message(is_fd=True, bitrate_switch=True, dlc=12, data=bytes(12)),
        "error-frame": message(is_error_frame=True, dlc=0, data=b""),
        "defaults": msgpack({}),
        "channel-and-is_rx": message(channel="vcan0", is_rx=True),
        "dlc-none": message(dlc=None),
        "wrong-types": message(arbitration_id="0x612", is_fd=0),
        "dlc-mismatch": message(dlc=2),
        "list": msgpack([1, 2, 3]),
        "map32-claims-4G": b"\xdf\xff\xff\xff\xff",
        "nested": b"\x91" * 40 + b"\xc0",
    }


def socketcand_seeds():
    """A socketcand client's bytes (byte 0: the piece size, 0 all at once): python-can's session, socketcand's own
    commands, and what a hostile client sends."""
    def conn(text, piece=0):
        return bytes([piece]) + (text if isinstance(text, bytes) else text.encode())
    session = "< open plant >< rawmode >< send 612 8 40 18 10 1 0 0 0 0 >< send 1ABCDEF0 3 1 2 3 >"
    return {
        "python-can-session": conn(session),
        "python-can-session-bytewise": conn(session, 1),
        "python-can-remote": conn("< open plant >< rawmode >< send 712 1  >"),
        "python-can-fd": conn("< open plant >< send 321 C " + "0 " * 12 + ">"),
        "sendrtr-and-echo": conn("< open plant >< sendrtr 1FFFFFFF 8 >< echo >< bcmmode >"),
        "dlc0-and-max-ids": conn("<open plant>\n<send 7FF 0>\n<send 1FFFFFFF 8 ff ff ff ff ff ff ff ff>\n", 7),
        "fdsend": conn("< open p >< fdsend 123 01 16 " + "aa " * 16 + ">"),
        "unsupported": conn("< open p >< subscribe 0 0 123 >< add 1 0 123 8 11 22 33 44 55 66 77 88 >"),
        "bad-sends": conn("< open p >< send 800 0 >< send 123 9 >< send 123 2 1 >< send xyz 1 1 >< send 123 1 100 >"),
        "http-post": conn("POST / HTTP/1.1\r\nHost: 127.0.0.1:29536\r\nContent-Type: text/plain\r\n\r\n"
                          "< open plant >< rawmode >< send 000 2 1 0 >"),
        "junk-between": conn("< open p > junk < echo >" + "x" * 300 + "< echo >", 5),
        "overlong": conn("< open p ><" + "a" * 600 + "> < echo >", 64),
        "nested-open": conn("< < open p > > <>< >"),
        "control-bytes": conn(b"< open p\x00 >< send 123\x01 0 >\xff\xfe< echo >"),
    }


def targets():
    out = {}
    out["core"] = vector_seeds((0, OWN, 0, 0), (0, 0xFF, 0, 0))
    out["core"].update(core_scenarios())
    dev = {"pro_ionizer": pro_ionizer_scenarios, "sds": sds_scenarios, "buerkert": buerkert_scenarios}
    for t, fn in dev.items():
        seeds = vector_seeds((0, OWN, 0, 0), (0, 0xFF, 0, 0))
        seeds.update(fn((0, OWN, 0, 0)))
        out[t] = seeds
    out["nvm_file"] = nvm_file_seeds()
    out["script"] = script_seeds()
    out["control"] = control_seeds()
    out["eds"] = eds_seeds()
    out["rules"] = rules_seeds()
    out["udp_datagram"] = udp_datagram_seeds()
    out["socketcand"] = socketcand_seeds()
    return out


def main():
    check = "--check" in sys.argv[1:]
    differ = []
    for target, seeds in targets().items():
        d = os.path.join(HERE, "corpus", target)
        os.makedirs(d, exist_ok=True)
        present = set(os.listdir(d))
        for name, data in sorted(seeds.items()):
            path = os.path.join(d, name)
            old = open(path, "rb").read() if name in present else None
            if old != data:
                differ.append(path)
                if not check:
                    with open(path, "wb") as f:
                        f.write(data)
            present.discard(name)
        for stale in sorted(present):
            differ.append(os.path.join(d, stale))
            if not check:
                os.remove(os.path.join(d, stale))
    if check:
        for p in differ:
            print("make_corpus.py: out of date: %s" % os.path.relpath(p, HERE), file=sys.stderr)
        return 1 if differ else 0
    print("make_corpus.py: %d files written or removed" % len(differ))
    return 0


if __name__ == "__main__":
    sys.exit(main())
