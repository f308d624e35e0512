"""The ends of bench/scale_cost.py's runs (issue 36): the fake CAN bus that canopen-emu-fakecan connects to
(tests/native/socketcan_unix.c: one struct can_frame per SOCK_SEQPACKET packet each way), and the two watchers: a
control-socket client subscribed to every frame, and a web session with the trace's subscription
(docs/control-protocol.md, docs/web.md). Standard library only.
"""
import base64
import http.client
import json
import os
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
    session's WebSocket as the page takes them (docs/web.md): a thread reads it; tick() has nothing to do.
    request(): a request over the socket, its answer awaited; exchange(): an HTTP exchange of the session."""

    def __init__(self, port):
        self.port = port
        self.lock = threading.Condition()
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
        self.answered = set()  # ids of the answers that came on the socket
        answer = self.exchange('{"id":1,"cmd":"subscribe","events":["frame"],'
                               '"frames":["0x000/0x000","0x00000000x/0x0"]}')
        while '"id":1' not in answer:
            answer = self.exchange("")
        if '"ok":true' not in answer:
            raise BenchError(f"web subscribe refused: {answer}")
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=600)
        key = base64.b64encode(os.urandom(16)).decode()
        self.sock.sendall(f"GET /api/session/{self.session}/socket HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n"
                          f"Upgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Version: 13\r\n"
                          f"Sec-WebSocket-Key: {key}\r\nOrigin: http://127.0.0.1:{port}\r\n"
                          f"Sec-WebSocket-Protocol: canopen-emu.{self.token}\r\n\r\n".encode())
        head = b""
        while b"\r\n\r\n" not in head:
            piece = self.sock.recv(1)  # byte by byte: the frames after the head are the reader's
            if not piece:
                raise BenchError("web: the socket closed during its handshake")
            head += piece
        if not head.startswith(b"HTTP/1.1 101 "):
            raise BenchError(f"web: the socket was refused: {head[:200]!r}")
        self.reader = threading.Thread(target=self._read_socket, daemon=True)
        self.reader.start()

    def _recv_exact(self, n):
        data = b""
        while len(data) < n:
            piece = self.sock.recv(n - len(data))
            if not piece:
                raise EOFError
            data += piece
        return data

    def _read_socket(self):
        """The server's frames (RFC 6455, never masked): text messages counted and their answers noted."""
        text = b""
        try:
            while True:
                b0, b1 = self._recv_exact(2)
                n = b1 & 0x7F
                if n == 126:
                    n = struct.unpack(">H", self._recv_exact(2))[0]
                elif n == 127:
                    n = struct.unpack(">Q", self._recv_exact(8))[0]
                payload = self._recv_exact(n)
                opcode = b0 & 0x0F
                if opcode == 0x8:
                    return
                if opcode in (0x0, 0x1):
                    text += payload
                    if b0 & 0x80:
                        lines = text.split(b"\n")
                        text = b""
                        with self.lock:
                            self.events += sum(line.count(b'"event":"frame"') for line in lines)
                            self.answered.update(int(m.group(1)) for line in lines
                                                 for m in [re.match(rb'\{"id":(\d+),', line)] if m)
                            self.lock.notify_all()
        except (EOFError, OSError):
            return

    def send(self, text):
        """A text message as a browser sends it: masked."""
        data = text.encode()
        mask = os.urandom(4)
        n = len(data)
        head = bytes([0x81]) + (bytes([0x80 | n]) if n < 126 else bytes([0x80 | 126]) + struct.pack(">H", n))
        self.sock.sendall(head + mask + bytes(b ^ mask[k % 4] for k, b in enumerate(data)))

    def request(self, ident, line):
        """line (a JSON request with this id) over the socket; returns once its answer came on it."""
        self.send(line)
        with self.lock:
            if not self.lock.wait_for(lambda: ident in self.answered, timeout=120):
                raise BenchError(f"web: no answer to request {ident} on the socket")

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
        pass  # the events come on the socket: a page sends only when it asks something

    def close(self):
        """After the program ended: its socket has ended too, every event of it counted."""
        self.conn.close()
        self.reader.join(timeout=60)
        self.sock.close()


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]
