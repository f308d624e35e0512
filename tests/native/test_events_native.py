"""Events of every kind the emulator can give without a real interface, as a control-socket client gets them
(docs/control-protocol.md "Events"): each JSON line is what the schema says (docs/control-protocol.schema.json) and
byte for byte what Jansson's compact ASCII dump of the same object writes (the events are written by code of our own,
emu/runtime/emu_event_writer.c: docs/decisions.md); a text session gets an `event ...` line of each kind, escaped as
the log escapes. A node whose device name (an EDS file's name) holds a quote, a backslash, an escape byte and a byte
that is not UTF-8 shows it as jstr() makes it in JSON, and escaped in text. `interface` events need an interface that
goes down: integration/control_socket (test_interface_troubles_are_events). canopen-emu-fakecan, also under
ASan+UBSan."""
import json
import os
import re
import shutil
import socket
import sys
import time
from pathlib import Path

from test_control_native import Program, connect
from test_emulator_native import SRC, download, upload

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "support"))
from control_schema import check_schema  # noqa: E402

HOSTILE_NAME = b'we"ird\\\x1b\xff name.eds'  # a quote, a backslash, ESC, a byte that is not UTF-8


def jansson_form(obj):
    """The object as json_dumps(JSON_COMPACT | JSON_ENSURE_ASCII) writes it: Python's compact ASCII dump with the
    hex digits of \\uXXXX in upper case, and DEL as it is (Jansson escapes code points from U+0080 only)."""
    text = json.dumps(obj, separators=(",", ":"), ensure_ascii=True)

    def escape(m):
        if m.group(1) is None:
            return m.group(0)
        return "\x7f" if m.group(1) == "007f" else "\\u" + m.group(1).upper()
    return re.sub(r"\\(?:u([0-9a-f]{4})|.)", escape, text)


class Lines:
    """A control-socket connection's lines as they come."""

    def __init__(self, path):
        self.sock = connect(path)
        self.buf = b""

    def send(self, line):
        self.sock.sendall(line.encode() + b"\n")

    def take(self, timeout=0.2):
        """Every whole line that came within timeout (the frames of the nodes' heartbeats never stop coming)."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            self.sock.settimeout(max(end - time.monotonic(), 0.001))
            try:
                piece = self.sock.recv(65536)
            except socket.timeout:
                break
            if not piece:
                break
            self.buf += piece
        *lines, self.buf = self.buf.split(b"\n")
        return lines


def test_every_event_kind_is_as_the_schema_says_and_as_jansson_writes_it(tmp_path):
    hostile = tmp_path / os.fsdecode(HOSTILE_NAME)
    shutil.copy(SRC / "od" / "sds.eds", hostile)
    ctl = tmp_path / "ctl.sock"
    program = Program(tmp_path, "--control-socket", str(ctl), "pro-ionizer:16", "sds:17", "buerkert:18",
                      f"{hostile}:20")
    bus = program.bus
    try:
        program.wait_log(r"control: listening on unix")
        js, text = Lines(ctl), Lines(ctl)
        js.send('{"id":1,"cmd":"subscribe","events":"all"}')
        js.send('{"id":2,"cmd":"subscribe","events":["frame"],"frames":["0x000/0x000","0x00000000x/0x0"]}')
        text.send("subscribe all")
        text.send("subscribe frame 0x000/0x000 0x00000000x/0x0")
        answers = [a for a in map(json.loads, js.take(1.0)) if "event" not in a]  # frame events may come already
        assert [a["ok"] for a in answers] == [True, True], answers
        text.take(1.0)

        bus.send(0x000, bytes([0x81, 17]))                  # nmt, boot-up
        bus.send(0x000, bytes([0x81, 20]))                  # the same of the node with the hostile name
        assert bus.sdo(17, upload(0x5FFF, 0))[0] == 0x80    # sdo-abort
        assert bus.sdo(17, download(0x1010, 1, 0x65766173, 4))[0] == 0x60  # store ("save")
        bus.send(0x000, bytes([0x81, 17]))                  # nvm: its stored parameters loaded
        js.send('{"id":3,"cmd":"emcy","node":16,"args":["0x3210","0x05"]}')  # emcy
        assert bus.sdo(16, download(0x6200, 1, 0x0A, 1))[0] == 0x60  # message: the model's word on the release
        program.proc.stdin.write("fault 17 sdo-ignore\nfault-clear 17\n")  # fault: injected, cleared
        program.proc.stdin.flush()
        assert bus.sdo(18, download(0x1016, 1, (5 << 16) | 100, 4))[0] == 0x60
        bus.send(0x705, b"\x05")                            # heartbeat: node 5 once, then missing
        for index, sub, value, size in ((0x1017, 0, 0, 2), (0x100C, 0, 50, 2), (0x100D, 0, 2, 1)):
            assert bus.sdo(18, download(index, sub, value, size))[0] == 0x60
        bus.send(0x40000000 | 0x712, b"")                   # guarding: one guard request, then none
        time.sleep(0.4)
        bus.send(0x7E5, bytes([0x04, 0x01, 0, 0, 0, 0, 0, 0]))  # lss: every node in configuration state...
        bus.send(0x7E5, bytes([0x11, 0x30, 0, 0, 0, 0, 0, 0]))  # ...gets a pending node-ID
        bus.send(0x7E5, bytes([0x04, 0x00, 0, 0, 0, 0, 0, 0]))

        kinds, seen = {}, []
        end = time.monotonic() + 10.0
        wanted = {"nmt", "boot-up", "emcy", "sdo-abort", "store", "nvm", "lss", "heartbeat", "guarding", "fault",
                  "message", "frame"}
        while not wanted <= set(kinds) and time.monotonic() < end:
            for line in js.take():
                msg = json.loads(line)
                if "event" not in msg:
                    continue
                check_schema(msg, None)
                assert line.decode("ascii") == jansson_form(msg), line
                kinds.setdefault(msg["event"], msg)
                seen.append(msg)
        assert wanted <= set(kinds), (sorted(wanted - set(kinds)), program.log()[-3000:])

        # the members in the order Jansson's tree had them: the common ones, the kind's own, the text
        common = ["event", "time_us", "bus", "node", "device"]
        tx = next(m for m in seen if m["event"] == "frame" and m["dir"] == "tx")
        assert list(tx) == common + ["dir", "id", "data", "text"], tx
        assert list(kinds["nmt"]) == common + ["from", "to", "text"], kinds["nmt"]
        assert list(kinds["store"]) == common + ["what", "index", "sub", "ok", "abort_code", "text"], kinds["store"]
        assert list(kinds["emcy"]) == common + ["code", "register", "info", "text"], kinds["emcy"]
        weird = [m for m in seen if m.get("node") == 20]
        assert weird, "no event of node 20"
        # not UTF-8: each byte from 0x80 is '?', as jstr() writes any string (jansson refuses such a string)
        assert all(m["device"].endswith('we"ird\\\x1b? name.eds') for m in weird), weird[0]
        assert "\\u001B?" in jansson_form(weird[0])
        assert kinds["fault"]["fault"] == "sdo-ignore" and kinds["heartbeat"]["producer"] == 5, kinds

        text_lines = [line.decode() for line in text.take(1.0) if line.startswith(b"event ")]
        text_kinds = {line.split(" ")[1] for line in text_lines}
        assert wanted <= text_kinds, (sorted(wanted - text_kinds), text_lines[-5:])
        for line in text_lines:
            assert re.fullmatch(r"event [a-z-]+ \d+\.\d{6} (node \d+@\S+ \(.*\)|\S+): .*", line), line
            assert not re.search(r"[\x00-\x1f\x7f]", line), line
        # the name escaped as the log escapes it: the backslash as it is, ESC and the lone byte as \xNN
        assert any('we"ird\\\\x1b\\xff name.eds): ' in line for line in text_lines), \
            [line for line in text_lines if "node 20" in line][:3]
    finally:
        program.quit()
