"""What a page of another origin, or a file:// page, can do to canopen-emu from the engineer's browser: nothing
(docs/robustness.md, "Who may connect"). Each page sends what a browser lets any page send without asking: "simple"
cross-origin POSTs (text/plain, no preflight, no-cors) whose bodies are control lines of its choosing, to
--control-tcp and to --web. Before the fix, --control-tcp ran the body's lines: 0x1017 set, an EMCY sent, `quit`
stopped the emulator."""
import http.server
import json
import socket
import threading

import pytest

from browser import wait_until

ATTACK = """<!doctype html>
<html><head><meta charset="utf-8"><title>waiting</title></head><body><script>
const lines = "set 17 0x1017 4000\\n" +
  '{"id":1,"cmd":"set","node":17,"object":"0x1017","value":3000}\\n' +
  '{"id":2,"cmd":"emcy","node":17,"args":["0x3210",5]}\\n' +
  '{"id":3,"cmd":"fault","node":17,"args":["heartbeat-stop"]}\\n' + "emcy 17 0x3210 5\\nquit\\n";
const post = (url) => fetch(url, {method: "POST", mode: "no-cors", headers: {"Content-Type": "text/plain"},
                                  body: lines}).then(() => "sent", (e) => "refused: " + e.message);
Promise.all([
  post("http://127.0.0.1:CONTROL_PORT/"),
  post("http://127.0.0.1:WEB_PORT/api/session"),
  fetch("http://127.0.0.1:WEB_PORT/api/session", {method: "POST", body: ""}).then((r) => "read " + r.status,
        (e) => "refused: " + e.message),
]).then((results) => { document.title = "done " + JSON.stringify(results); });
</script></body></html>
"""


def heartbeat_time(port):
    with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
        s.sendall(b'{"id":1,"cmd":"get","node":17,"object":"0x1017"}\n')
        s.shutdown(socket.SHUT_WR)
        got = b""
        while piece := s.recv(65536):
            got += piece
    return json.loads(got.splitlines()[0])["value"]


class AttackerPages(http.server.BaseHTTPRequestHandler):
    page = b""

    def do_GET(self):
        self.send_response(200)
        self.send_header("Content-Type", "text/html")
        self.send_header("Content-Length", str(len(self.page)))
        self.end_headers()
        self.wfile.write(self.page)

    def log_message(self, *args):
        pass


@pytest.fixture
def attacker():
    """An HTTP server of another origin (another port of 127.0.0.1) serving the attack page."""
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), AttackerPages)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    yield server
    server.shutdown()
    server.server_close()


@pytest.mark.parametrize("origin", ["http", "file"])
def test_a_page_of_another_origin_changes_nothing(driver, start_emulator, attacker, tmp_path, origin):
    emu = start_emulator("--control-tcp", "127.0.0.1:0", "sds:17")
    control = int(emu.wait_log("control: listening on tcp 127.0.0.1:").rsplit(":", 1)[1].split()[0])
    before = heartbeat_time(control)
    page = ATTACK.replace("CONTROL_PORT", str(control)).replace("WEB_PORT", str(emu.port)).encode()
    if origin == "http":
        AttackerPages.page = page
        url = f"http://127.0.0.1:{attacker.server_address[1]}/attack.html"
    else:
        path = tmp_path / "attack.html"
        path.write_bytes(page)
        url = path.as_uri()
    driver.get(url)
    title = wait_until(driver, "the attack page's requests settled", lambda d: d.title,
                       lambda t: t.startswith("done"), timeout=30)
    results = json.loads(title[len("done "):])
    assert results[2] == "refused: Failed to fetch", results  # a CORS read of the web API: refused by the browser
    emu.wait_log("(tcp) closed: its first line is an HTTP request")
    assert emu.proc.poll() is None, "the page stopped the emulator"
    assert heartbeat_time(control) == before
    log = emu.log()
    assert "EMCY" not in log and "fault" not in log, log[-3000:]
    assert "web: web session" not in log  # the web view opened no session for it (403 without the token)
    driver.get("about:blank")
