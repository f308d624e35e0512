"""The ends of bench/scale_cost.py's runs (issue 36): the fake CAN bus that canopen-emu-fakecan connects to
(tests/native/socketcan_unix.c: one struct can_frame per SOCK_SEQPACKET packet each way), and the two watchers: a
control-socket client subscribed to every frame, and a web session with the trace's subscription
(docs/control-protocol.md, docs/web.md). Standard library only.
"""
import http.client
import json
import queue
import re
import socket
import struct
import threading
import time

FRAME = struct.Struct("<IB3x8s")  # struct can_frame, as socketcan_unix.c sends and takes it


class BenchError(Exception):
    pass


def upload(index, sub):
    return bytes([0x40, index & 0xFF, index >> 8, sub, 0, 0, 0, 0])


def download_u16(index, sub, value):
    return bytes([0x2B, index & 0xFF, index >> 8, sub, value & 0xFF, value >> 8, 0, 0])


class FakeBus:
    """This script's end of the fake bus: SDO answers in a queue, every frame counted by COB-ID range."""

    def __init__(self, path):
        self.listener = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        self.listener.bind(path)
        self.listener.listen(1)
        self.conn = None
        self.answers = queue.Queue()
        self.heartbeats = 0  # 0x701..0x77F with a state byte other than boot-up
        self.boot_ups = set()
        self.reader = None

    def accept(self, timeout=120.0):
        self.listener.settimeout(timeout)
        self.conn, _ = self.listener.accept()
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self):
        while True:
            try:
                data = self.conn.recv(64)
            except OSError:
                return
            if not data:
                return
            can_id, dlc, payload = FRAME.unpack(data)
            if 0x581 <= can_id <= 0x5FF:
                self.answers.put((can_id - 0x580, bytes(payload[:dlc])))
            elif 0x701 <= can_id <= 0x77F:
                if payload[0] == 0:
                    self.boot_ups.add(can_id - 0x700)
                else:
                    self.heartbeats += 1

    def send(self, can_id, data):
        self.conn.send(FRAME.pack(can_id, len(data), bytes(data).ljust(8, b"\0")))

    def sdo(self, node, request, timeout=60.0):
        self.send(0x600 + node, request)
        while True:
            try:
                got, data = self.answers.get(timeout=timeout)
            except queue.Empty:
                raise BenchError(f"no SDO answer of node {node} to {request.hex()} in {timeout} s") from None
            if got == node and data[1:4] == request[1:4]:
                if data[0] == 0x80:
                    raise BenchError(f"node {node} aborted {request.hex()}: {data.hex()}")
                return data

    def close(self):
        for s in (self.conn, self.listener):
            if s is not None:
                s.close()


class ControlWatcher:
    """A control-socket client subscribed to every frame; a thread reads and counts the frame events."""

    def __init__(self, path):
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        deadline = time.monotonic() + 60
        while True:
            try:
                self.sock.connect(path)
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.1)
        self.events = 0
        self.lines = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()
        self.sock.sendall(b'{"id":1,"cmd":"subscribe","events":["frame"],"frames":"0x000/0x000"}\n')
        answer = self.lines.get(timeout=60)
        if '"ok":true' not in answer:
            raise BenchError(f"control subscribe refused: {answer}")

    def _read(self):
        rest = b""
        while True:
            try:
                data = self.sock.recv(1 << 16)
            except OSError:
                return
            if not data:
                return
            rest += data
            *lines, rest = rest.split(b"\n")
            for line in lines:
                if line.startswith(b'{"event":"frame"'):
                    self.events += 1
                else:
                    self.lines.put(line.decode())

    def tick(self):
        pass

    def close(self):
        self.sock.close()


class WebWatcher:
    """A web session with the trace's subscription (every 11-bit and 29-bit frame), its events taken from the
    session's stream as the page takes them (docs/web.md): a thread reads it; tick() has nothing to do."""

    def __init__(self, port):
        self.lock = threading.Lock()
        deadline = time.monotonic() + 60
        while True:
            try:
                self.conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
                self.conn.request("GET", "/")
                page = self.conn.getresponse().read().decode()
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.2)
        self.token = re.search(r'name="canopen-emu-token" content="([0-9a-f]+)"', page).group(1)
        self.session = json.loads(self.post("/api/session", ""))["session"]
        self.events = 0
        self.exchanges = 0
        answer = self.exchange('{"id":1,"cmd":"subscribe","events":["frame"],'
                               '"frames":["0x000/0x000","0x00000000x/0x0"]}')
        while '"id":1' not in answer:
            answer = self.exchange("")
        if '"ok":true' not in answer:
            raise BenchError(f"web subscribe refused: {answer}")
        self.stream = socket.create_connection(("127.0.0.1", port), timeout=600)
        self.stream.sendall(f"POST /api/session/{self.session}/stream HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n"
                            f"X-Canopen-Emu: {self.token}\r\nContent-Length: 0\r\n\r\n".encode())
        self.reader = threading.Thread(target=self._read_stream, daemon=True)
        self.reader.start()

    def _read_stream(self):
        """The chunked answer's body, counted: every frame event in it (a line is never split by the count)."""
        buf = b""
        try:
            while b"\r\n\r\n" not in buf:
                piece = self.stream.recv(65536)
                if not piece:
                    return
                buf += piece
            head, buf = buf.split(b"\r\n\r\n", 1)
            if not head.startswith(b"HTTP/1.1 200"):
                return
            body = b""
            while True:
                piece = self.stream.recv(65536)
                if not piece:
                    return
                buf += piece
                while b"\r\n" in buf:
                    size_line, rest = buf.split(b"\r\n", 1)
                    size = int(size_line.split(b";")[0], 16)
                    if len(rest) < size + 2:
                        break
                    body += rest[:size]
                    buf = rest[size + 2:]
                    if size == 0:
                        return
                *lines, body = body.split(b"\n")
                with self.lock:
                    self.events += sum(line.count(b'"event":"frame"') for line in lines)
        except OSError:
            return

    def post(self, path, body):
        self.conn.request("POST", path, body=body.encode(), headers={"X-Canopen-Emu": self.token})
        answer = self.conn.getresponse()
        data = answer.read()
        if answer.status != 200:
            raise BenchError(f"web: {path}: HTTP {answer.status}: {data[:200]!r}")
        return data.decode()

    def exchange(self, body=""):
        data = self.post(f"/api/session/{self.session}", body)
        self.exchanges += 1
        with self.lock:
            self.events += data.count('"event":"frame"')
        return data

    def tick(self):
        pass  # the events come on the stream: a page exchanges only when it asks something

    def close(self):
        """After the program ended: its stream has ended too, every event of it counted."""
        self.conn.close()
        self.reader.join(timeout=60)
        self.stream.close()


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]
