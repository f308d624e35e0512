"""A web session's WebSocket (GET /api/session/ID/socket, docs/web.md): the handshake's checks (Origin, token as the
subprotocol, version, session), request lines in and answers and events out as messages, batches, keep-alive
messages, backpressure (a page that does not read loses nothing and holds no work), the bounds (a message over
16 KiB, a binary one), a second socket and a stream ending each other, the program ending with a socket open.
Against canopen-emu-fakecan, in the plain and in the ASan+UBSan build (test_web_native.py's program); the client is
websocket-client (tests/requirements.txt).

Environment (tests/native/CMakeLists.txt): CO_SOURCE_DIR, CO_EMU_FAKECAN, CO_SANITIZED.
"""

import json
import random
import threading
import time

import pytest
import websocket

from test_web_native import NO_SESSION, WebEmulator
from test_web_stream_native import Stream, events

BATCH_S = 0.050  # WEB_STREAM_BATCH_US
KEEPALIVE_S = 5.0  # WEB_STREAM_KEEPALIVE_US


@pytest.fixture
def emu(tmp_path):
    e = WebEmulator(tmp_path)
    yield e
    if e.proc.poll() is None:
        assert e.quit() == 0, e.log()[-3000:]


class Socket:
    """The page's WebSocket: its messages, each with the time it came, read by a thread."""

    def __init__(self, emu, session, origin=None, token=None, **options):
        self.ws = websocket.create_connection(
            f"ws://127.0.0.1:{emu.port}/api/session/{session}/socket", timeout=30,
            origin=origin or f"http://127.0.0.1:{emu.port}",
            subprotocols=[f"canopen-emu.{token or emu.token()}"], **options)
        self.messages = []  # (time, text)
        self.closed = None  # (status code, reason) once the emulator closed it
        self.lock = threading.Lock()
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self):
        try:
            while True:
                opcode, data = self.ws.recv_data(control_frame=True)
                if opcode == websocket.ABNF.OPCODE_CLOSE:
                    code = int.from_bytes(data[:2], "big") if len(data) >= 2 else None
                    self.closed = (code, data[2:].decode())
                    return
                if opcode == websocket.ABNF.OPCODE_TEXT:
                    with self.lock:
                        self.messages.append((time.monotonic(), data.decode()))
        except (websocket.WebSocketException, OSError):
            if self.closed is None:
                self.closed = (None, "connection ended")

    def send(self, *lines):
        self.ws.send("\n".join(lines))

    def lines(self):
        with self.lock:
            text = "".join(m for _, m in self.messages)
        return [json.loads(line) if line.startswith("{") else line for line in text.split("\n")[:-1]]

    def wait(self, predicate, timeout=10.0, what="lines"):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            lines = self.lines()
            if predicate(lines):
                return lines
            time.sleep(0.01)
        raise AssertionError(f"no {what} on the socket in {timeout} s: {self.lines()[-20:]!r}")

    def wait_closed(self, timeout=10.0):
        end = time.monotonic() + timeout
        while self.closed is None and time.monotonic() < end:
            time.sleep(0.01)
        return self.closed

    def close(self):
        """As a page closes it: a close frame, then the connection ends (websocket-client's close() leaves the
        connection open when its reader saw the emulator's close frame first)."""
        try:
            self.ws.close(timeout=1)
        except (websocket.WebSocketException, OSError):
            pass
        self.ws.shutdown()


def answered(lines, ident):
    return [m for m in lines if isinstance(m, dict) and m.get("id") == ident]


def refused(emu, session, **options):
    with pytest.raises(websocket.WebSocketBadStatusException) as e:
        Socket(emu, session, **options)
    return e.value.status_code, json.loads(e.value.resp_body)


def test_requests_answers_and_events_go_over_the_socket(emu):
    session = emu.open_session()
    socket = Socket(emu, session)
    assert socket.ws.getsubprotocol() == f"canopen-emu.{emu.token()}"
    socket.send('{"id":1,"cmd":"subscribe","events":["nmt"]}', '{"id":2,"cmd":"hello"}')
    lines = socket.wait(lambda ls: answered(ls, 2), what="the answers")
    assert [(m["id"], m["ok"]) for m in lines if isinstance(m, dict)] == [(1, True), (2, True)]
    emu.bus.send(0x000, bytes([0x01, 16]))  # NMT start node 16
    lines = socket.wait(lambda ls: events(ls, "nmt"), what="the nmt event")
    assert [(e["node"], e["to"]) for e in events(lines, "nmt")] == [(16, "OPERATIONAL")]
    socket.send("get 16 0x1017")  # the command language too; a last line without newline is one
    socket.wait(lambda ls: any(isinstance(m, str) and m.startswith("node 16: 0x1017:00 = ") for m in ls),
                what="the text answer")
    answer = emu.exchange(session)  # an exchange of the session meanwhile: everything goes on the socket
    assert (answer.status, answer.body) == (200, b"")
    assert emu.quit() == 0, emu.log()[-3000:]  # with the socket open: closed, nothing leaks (ASan build)
    assert socket.wait_closed() is not None


def test_the_handshake_is_checked(emu):
    session = emu.open_session()
    forbidden_origin = {"error": "the Origin is not this server's page"}
    assert refused(emu, session, origin="http://evil.example") == (403, forbidden_origin)
    assert refused(emu, session, origin=f"http://localhost:{emu.port}") == (403, forbidden_origin)  # not the Host
    assert refused(emu, session, token="0" * 32) == \
        (403, {"error": "missing or wrong token: the subprotocol is canopen-emu.TOKEN (load the page again)"})
    assert refused(emu, "0" * 32) == (404, NO_SESSION)
    handshake = {"Upgrade": "websocket", "Connection": "Upgrade", "Sec-WebSocket-Version": "8",
                 "Sec-WebSocket-Key": "dGhlIHNhbXBsZSBub25jZQ==", "Origin": f"http://127.0.0.1:{emu.port}",
                 "Sec-WebSocket-Protocol": f"canopen-emu.{emu.token()}"}
    old = emu.request("GET", f"/api/session/{session}/socket", headers=handshake)
    assert (old.status, old.json()) == (400, {"error": "WebSocket version 13 only (Sec-WebSocket-Version: 13)"})
    keyless = emu.request("GET", f"/api/session/{session}/socket",
                          headers=dict(handshake, **{"Sec-WebSocket-Version": "13", "Sec-WebSocket-Key": "short"}))
    assert (keyless.status, keyless.json()) == (400, {"error": "no Sec-WebSocket-Key of 24 characters"})
    plain = emu.request("GET", f"/api/session/{session}/socket")
    assert (plain.status, plain.json()) == \
        (400, {"error": "the socket is a WebSocket: Upgrade: websocket and Connection: Upgrade"})
    posted = emu.request("POST", f"/api/session/{session}/socket", token=emu.token())
    assert (posted.status, posted.headers["Allow"]) == (405, "GET")
    socket = Socket(emu, session)  # and a right one still opens
    socket.send('{"id":1,"cmd":"hello"}')
    socket.wait(lambda ls: answered(ls, 1), what="the answer")
    socket.close()


def test_a_busy_trace_comes_in_batches_and_in_order(emu):
    session = emu.open_session()
    socket = Socket(emu, session)
    socket.send('{"id":1,"cmd":"subscribe","events":["frame"],"frames":"0x7E0/0x7FF"}')
    socket.wait(lambda ls: answered(ls, 1), what="the subscription")
    start = time.monotonic()
    for k in range(400):
        time.sleep(max(0.0, start + k * 0.002 - time.monotonic()))
        emu.bus.send(0x7E0, k.to_bytes(4, "little"))
    took = time.monotonic() - start
    lines = socket.wait(lambda ls: len(events(ls, "frame")) == 400, what="400 frame events")
    assert [bytes.fromhex(e["data"]) for e in events(lines, "frame")] == [k.to_bytes(4, "little") for k in range(400)]
    with socket.lock:
        times = [t for t, _ in socket.messages]
    assert len(times) <= took / BATCH_S + 10, (len(times), took)  # one write per frame would be 400
    socket.close()


def test_keepalive_messages_keep_the_session_and_a_closed_socket_lets_it_expire(emu):
    kept, gone = emu.open_session(), emu.open_session()
    socket = Socket(emu, kept)
    opened = time.monotonic()
    Socket(emu, gone).close()  # the page closed it: the session lives on without (exchanges), and expires
    time.sleep(11.0)
    with socket.lock:
        messages = list(socket.messages)
    assert [text for _, text in messages] == ["\n", "\n"], messages
    assert KEEPALIVE_S - 0.2 <= messages[0][0] - opened <= KEEPALIVE_S + 1.5
    emu.wait_log("web: web session 2 removed: no exchange for 10 s", timeout=5.0)
    assert "web session 1 removed" not in emu.log()
    socket.send('{"id":1,"cmd":"hello"}')
    socket.wait(lambda ls: answered(ls, 1), what="the answer")
    socket.close()


def test_a_page_that_does_not_read_holds_no_work_and_loses_nothing(emu):
    """80 requests of ~25 kB answers and then 700 more requests, each its own message, while the page reads nothing
    for 2 s: the session pauses at its mark, its 16 KiB of waiting requests fill, the next message is held and the
    socket not read further (the rest wait in the kernel); then every answer comes, whole and in order; nobody is
    dropped."""
    session = emu.open_session()
    socket = Socket(emu, session)
    with socket.lock:  # the reader thread is held: the socket's receive buffer fills, then the emulator's send
        for k in range(80):
            socket.send(f'{{"id":{k + 1},"cmd":"objects","node":16,"values":true}}')
        for k in range(700):
            socket.send(f'{{"id":{k + 81},"cmd":"hello"}}')
        time.sleep(2.0)
    lines = socket.wait(lambda ls: answered(ls, 780), timeout=60.0, what="the last answer")
    ids = [m["id"] for m in lines if isinstance(m, dict) and "id" in m]
    assert ids == list(range(1, 781))
    assert all(m["ok"] for m in lines if isinstance(m, dict) and "id" in m)
    assert "dropped" not in emu.log()
    socket.close()


def test_a_message_over_16_kib_and_a_binary_one_close_the_socket_not_the_session(emu):
    session = emu.open_session()
    big = Socket(emu, session)
    big.ws.send("\n" * (16 * 1024 + 1))
    assert big.wait_closed()[0] == 1009  # message too big
    binary = Socket(emu, session)
    binary.ws.send_binary(b'{"id":1,"cmd":"hello"}')
    assert binary.wait_closed()[0] == 1003  # unsupported data
    fine = Socket(emu, session)
    fine.send('{"id":2,"cmd":"hello"}')
    assert [m["id"] for m in fine.wait(lambda ls: answered(ls, 2), what="the answer") if isinstance(m, dict)] == [2]
    fine.close()


def test_a_second_socket_ends_the_first_and_a_socket_ends_the_stream(emu):
    session = emu.open_session()
    stream = Stream(emu, session)
    first = Socket(emu, session)
    end = time.monotonic() + 5.0
    while not stream.ended and time.monotonic() < end:
        time.sleep(0.01)
    assert stream.ended
    second = Socket(emu, session)
    assert first.wait_closed()[0] == 1001  # going away
    second.send('{"id":1,"cmd":"hello"}')
    second.wait(lambda ls: answered(ls, 1), what="the answer on the second socket")
    assert answered(first.lines(), 1) == []
    for s in (stream, first, second):
        s.close()


def test_hostile_frames_close_that_socket_and_harm_nothing_else(emu):
    """Bytes that are no valid frames (random ones, an unmasked frame, a length of 2^63, a control frame of 200
    bytes, a fragment without its start, a reserved opcode), each after a good handshake: the socket is closed (or
    waits for more until the page closes it), the program goes on, no connection is left behind (afterwards 8
    sockets, the limit of one address, open at once) and a socket of the same session works (the ASan+UBSan build
    checks the memory)."""
    rng = random.Random(36)
    session = emu.open_session()
    blobs = [bytes(rng.randrange(256) for _ in range(rng.randrange(1, 300))) for _ in range(40)]
    blobs += [b"\x81\x05hello",  # unmasked: a client's frames must be masked
              b"\x81\xff" + (1 << 63).to_bytes(8, "big") + b"\x00" * 4,  # a length beyond any bound
              b"\x89\xfe\x00\xc8" + b"\x00" * 4 + b"p" * 200,  # a ping of 200 bytes (control frames: 125 at most)
              b"\x80\x85" + b"\x00" * 4 + b"x" * 5,  # a continuation without a start
              b"\x83\x80" + b"\x00" * 4]  # a reserved opcode
    for k in range(0, len(blobs), 4):  # four at a time: one address may hold 8 connections
        sockets = [Socket(emu, session) for _ in blobs[k:k + 4]]
        for socket, blob in zip(sockets, blobs[k:k + 4]):
            socket.ws.sock.sendall(blob)
        for socket in sockets:
            socket.wait_closed(timeout=0.3)  # closed, or still waiting for the rest of a frame
            socket.close()
        time.sleep(0.2)
    assert emu.proc.poll() is None
    sockets = [Socket(emu, emu.open_session()) for _ in range(7)] + [Socket(emu, session)]
    sockets[-1].send('{"id":1,"cmd":"hello"}')
    sockets[-1].wait(lambda ls: answered(ls, 1), what="the answer after the hostile frames")
    for socket in sockets:
        socket.close()
