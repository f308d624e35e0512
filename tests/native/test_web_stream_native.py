"""A web session's stream (POST /api/session/ID/stream, docs/web.md): the session's events and answers pushed as
they come, in batches, with keep-alive lines while quiet; a streamed session does not expire, one whose stream went
away does; a second stream ends the first; the program ends cleanly with streams open. Against
canopen-emu-fakecan, in the plain and in the ASan+UBSan build (test_web_native.py's program).

Environment (tests/native/CMakeLists.txt): CO_SOURCE_DIR, CO_EMU_FAKECAN, CO_SANITIZED.
"""

import json
import socket
import threading
import time

import pytest

from test_web_native import CSP, NO_SESSION, WebEmulator

BATCH_S = 0.050  # WEB_STREAM_BATCH_US
KEEPALIVE_S = 5.0  # WEB_STREAM_KEEPALIVE_US


@pytest.fixture
def emu(tmp_path):
    e = WebEmulator(tmp_path)
    yield e
    if e.proc.poll() is None:
        assert e.quit() == 0, e.log()[-3000:]


class Stream:
    """The stream as a browser's fetch reads it: the status and headers, then the chunks of the chunked body, each
    with the time it came (a thread reads them)."""

    def __init__(self, emu, session, token=True):
        self.sock = socket.create_connection(("127.0.0.1", emu.port), timeout=30)
        tok = f"X-Canopen-Emu: {emu.token()}\r\n" if token else ""
        self.sock.sendall(f"POST /api/session/{session}/stream HTTP/1.1\r\nHost: 127.0.0.1:{emu.port}\r\n{tok}"
                          "Content-Length: 0\r\n\r\n".encode())
        self.buf = b""
        head = self._until(b"\r\n\r\n")
        status_line, *header_lines = head.decode().split("\r\n")
        self.status = int(status_line.split()[1])
        self.headers = {k.strip().lower(): v.strip() for k, v in (h.split(":", 1) for h in header_lines)}
        self.chunks = []  # (time, bytes)
        self.ended = False  # the terminating chunk came
        self.closed = False  # the connection ended
        self.lock = threading.Lock()
        if self.status == 200:
            self.reader = threading.Thread(target=self._read_chunks, daemon=True)
            self.reader.start()
        else:
            length = int(self.headers.get("content-length", "0"))
            while len(self.buf) < length:
                self._more()
            self.body = self.buf[:length]

    def _more(self):
        piece = self.sock.recv(65536)
        if not piece:
            raise EOFError
        self.buf += piece

    def _until(self, mark):
        while mark not in self.buf:
            self._more()
        head, self.buf = self.buf.split(mark, 1)
        return head

    def _read_chunks(self):
        try:
            while True:
                size = int(self._until(b"\r\n").split(b";")[0], 16)
                while len(self.buf) < size + 2:
                    self._more()
                data, self.buf = self.buf[:size], self.buf[size + 2:]
                if size == 0:
                    self.ended = True
                    return
                with self.lock:
                    self.chunks.append((time.monotonic(), data))
        except (EOFError, OSError):
            pass
        finally:
            self.closed = True

    def text(self):
        with self.lock:
            return b"".join(data for _, data in self.chunks).decode()

    def lines(self):
        """Whole lines so far, JSON ones as dicts; keep-alive lines ("") included."""
        text = self.text()
        return [json.loads(line) if line.startswith("{") else line for line in text.split("\n")[:-1]]

    def wait(self, predicate, timeout=10.0, what="lines"):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            lines = self.lines()
            if predicate(lines):
                return lines
            time.sleep(0.01)
        raise AssertionError(f"no {what} on the stream in {timeout} s: {self.lines()!r}")

    def close(self):
        self.sock.close()


def events(lines, kind):
    return [m for m in lines if isinstance(m, dict) and m.get("event") == kind]


def test_events_and_answers_come_on_the_stream_and_exchanges_answer_empty(emu):
    session = emu.open_session()
    subscribed = emu.exchange(session, '{"id":1,"cmd":"subscribe","events":["nmt"]}').lines()
    assert subscribed == [{"id": 1, "ok": True, "events": ["nmt"]}]  # no stream yet: with the exchange
    stream = Stream(emu, session)
    assert stream.status == 200
    assert stream.headers["transfer-encoding"] == "chunked"
    assert stream.headers["content-type"] == "application/x-ndjson"
    assert stream.headers["cache-control"] == "no-store"
    assert stream.headers["content-security-policy"] == CSP
    assert stream.headers["x-content-type-options"] == "nosniff"
    emu.bus.send(0x000, bytes([0x01, 16]))  # NMT start node 16: an event nobody asks for
    lines = stream.wait(lambda ls: events(ls, "nmt"), what="the nmt event")
    assert [(e["node"], e["to"]) for e in events(lines, "nmt")] == [(16, "OPERATIONAL")]
    answer = emu.exchange(session, '{"id":2,"cmd":"hello"}', "get 16 0x1017")
    assert (answer.status, answer.body) == (200, b"")  # the answers go on the stream, in order with the events
    lines = stream.wait(lambda ls: any(isinstance(m, str) and m.startswith("node 16: 0x1017:00 = ") for m in ls),
                        what="the answers")
    json_answers = [m for m in lines if isinstance(m, dict) and "id" in m]
    assert [(m["id"], m["ok"], m["program"]) for m in json_answers] == [(2, True, "canopen-emu")]
    assert lines.index(json_answers[0]) > lines.index(events(lines, "nmt")[0])
    emu.bus.send(0x000, bytes([0x80, 16]))  # to Pre-operational
    lines = stream.wait(lambda ls: len(events(ls, "nmt")) == 2, what="the second nmt event")
    assert events(lines, "nmt")[1]["to"] == "PRE-OPERATIONAL"
    assert emu.quit() == 0, emu.log()[-3000:]  # with the stream open: it ends, nothing leaks (ASan build)
    end = time.monotonic() + 5.0
    while not stream.closed and time.monotonic() < end:
        time.sleep(0.01)
    assert stream.closed
    stream.close()


def test_a_busy_trace_comes_in_batches_and_in_order(emu):
    """400 frames 2 ms apart (0.8 s): every event comes, in order, in batches of about WEB_STREAM_BATCH_US (one
    write per frame would be 400 chunks)."""
    session = emu.open_session()
    emu.exchange(session, '{"id":1,"cmd":"subscribe","events":["frame"],"frames":"0x7E0/0x7FF"}')
    stream = Stream(emu, session)
    time.sleep(0.1)
    start = time.monotonic()
    for k in range(400):
        time.sleep(max(0.0, start + k * 0.002 - time.monotonic()))
        emu.bus.send(0x7E0, k.to_bytes(4, "little"))
    took = time.monotonic() - start
    lines = stream.wait(lambda ls: len(events(ls, "frame")) == 400, what="400 frame events")
    data = [bytes.fromhex(e["data"]) for e in events(lines, "frame")]
    assert data == [k.to_bytes(4, "little") for k in range(400)]
    with stream.lock:
        times = sorted({round(t, 3) for t, _ in stream.chunks})
    # A batch may take more than one chunk (4 KiB each); the writes are about BATCH_S apart.
    assert len(times) <= took / BATCH_S + 10, (len(times), took)
    gaps = [b - a for a, b in zip(times, times[1:])]
    assert sorted(gaps)[len(gaps) // 2] >= BATCH_S * 0.8, gaps
    stream.close()


def test_a_quiet_stream_keeps_its_session_alive_with_keepalive_lines_and_one_gone_lets_it_expire(emu):
    """Two sessions with streams and no exchanges: the one whose stream stays open gets an empty line each 5 s of
    silence and is kept past the 10 s a session lives without exchanges; the one whose stream is closed at once is
    removed 10 s after a keep-alive's write found the connection gone (the first write to a closed connection may
    still succeed: at most two)."""
    kept, gone = emu.open_session(), emu.open_session()
    stream = Stream(emu, kept)
    opened = time.monotonic()
    Stream(emu, gone).close()
    time.sleep(11.0)  # longer than a session lives without exchanges (10 s)
    with stream.lock:
        chunks = list(stream.chunks)
    assert [data for _, data in chunks] == [b"\n", b"\n"], chunks  # one empty line each 5 s of silence
    assert KEEPALIVE_S - 0.2 <= chunks[0][0] - opened <= KEEPALIVE_S + 1.5, chunks[0][0] - opened
    assert KEEPALIVE_S - 0.5 <= chunks[1][0] - chunks[0][0] <= KEEPALIVE_S + 1.5
    assert "removed" not in emu.log()
    emu.wait_log("web: web session 2 removed: no exchange for 10 s", timeout=2 * KEEPALIVE_S + 10.0 + 5.0 - 11.0)
    assert "web session 1 removed" not in emu.log()
    assert emu.exchange(kept, '{"id":1,"cmd":"hello"}').status == 200  # the session is there
    stream.wait(lambda ls: any(isinstance(m, dict) and m.get("id") == 1 for m in ls), what="the hello answer")
    stream.close()


def test_a_second_stream_of_a_session_ends_the_first(emu):
    session = emu.open_session()
    emu.exchange(session, '{"id":1,"cmd":"subscribe","events":["nmt"]}')
    first = Stream(emu, session)
    second = Stream(emu, session)
    end = time.monotonic() + 5.0
    while not first.ended and time.monotonic() < end:
        time.sleep(0.01)
    assert first.ended, first.lines()
    emu.bus.send(0x000, bytes([0x01, 17]))
    second.wait(lambda ls: events(ls, "nmt"), what="the nmt event on the second stream")
    assert events(first.lines(), "nmt") == []
    first.close()
    second.close()


def test_a_stream_needs_the_token_and_a_session(emu):
    session = emu.open_session()
    no_token = Stream(emu, session, token=False)
    assert no_token.status == 403
    unknown = Stream(emu, "0" * 32)
    assert (unknown.status, json.loads(unknown.body)) == (404, NO_SESSION)
    assert emu.request("POST", f"/api/session/{session}/streams", token=emu.token()).status == 404
    assert emu.request("POST", f"/api/session/{session}/stream/", token=emu.token()).status == 404
    for s in (no_token, unknown):
        s.close()
