"""The trace view of the web page in a browser (docs/web.md "The trace"): the frames the fake bus sends and sees,
decoded in CANopen terms in the page's table; its filter, pause, the frames recorded only while it is shown, and the
candump log it saves, compared line by line with the frames of the bus. Judged by the page's text: the cells of each
row (td[data-field]) and the status line of the view."""

import re
import time
from pathlib import Path

from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import Select

from browser import wait_until
from test_overview import command, drain, loaded

NODES = ("pro-ionizer:16", "sds:17", "buerkert:18")
CAN_RTR_FLAG = 0x40000000
CAN_EFF_FLAG = 0x80000000
COUNT = re.compile(r"(\d+) frames kept, (\d+) dropped \(at most 20000\)(.*)")

# The trace at one moment: its rows {field: text}, the status line's count and problem.
SNAPSHOT = """
const rows = [...document.querySelectorAll("#trace tbody tr")].map((tr) => {
  const cells = {};
  for (const td of tr.cells) { cells[td.dataset.field] = td.textContent; }
  return cells;
});
return {rows, count: document.getElementById("trace-count").textContent,
        problem: document.getElementById("trace-problem").textContent};
"""


def snapshot(driver):
    return driver.execute_script(SNAPSHOT)


def wait_for(driver, what, check, timeout):
    """The first snapshot for which check(snapshot) holds, polled every 50 ms; fails with the last one seen."""
    def describe(last):
        last = last or {}
        return (f"the trace showed {last.get('count')!r} {last.get('problem')!r}, last rows "
                f"{(last.get('rows') or [])[-12:]}")
    return wait_until(driver, what, snapshot, check, timeout, describe)


def row_with(text, **cells):
    """check() of a snapshot with a row whose decoded text is `text` and whose other cells are as given."""
    def check(shot):
        return any(r["text"] == text and all(r[f] == v for f, v in cells.items()) for r in shot["rows"])
    return check


def recording(shot):
    match = COUNT.fullmatch(shot["count"])
    return match is not None and match.group(3) == ""


def open_trace(page, emu, count=3):
    """The page of `emu` on its trace view, subscribed to the frames (the status line says so: every frame the bus
    sends from now on is in the trace)."""
    driver = loaded(page, emu, count)
    driver.find_element(By.ID, "tab-trace").click()
    wait_for(driver, "the frames subscribed", recording, 10.0)
    return driver


def sdo_text(data):
    """The decoded text of an expedited upload response of the bus."""
    size = 4 - ((data[0] >> 2) & 3)
    value = int.from_bytes(data[4:4 + size], "little")
    index, sub = int.from_bytes(data[1:3], "little"), data[3]
    return (f"SDO upload response 0x{index:04X}:{sub:02X} expedited {size} bytes = {value} "
            f"(0x{value:0{2 * size}X})")


def upload(index, sub):
    return bytes([0x40, index & 0xFF, index >> 8, sub, 0, 0, 0, 0])


def test_the_trace_shows_decoded_frames(page, start_emulator):
    emu = start_emulator(*NODES)
    driver = open_trace(page, emu)
    titles = driver.execute_script("return [...document.querySelectorAll('#trace thead th')].map((th) => th.textContent)")
    assert titles == ["time", "bus", "dir", "COB-ID", "node", "kind", "decoded", "data"]

    # An SDO upload the bus asks of node 17, and its answer with the value.
    drain(emu.bus)
    emu.bus.send(0x611, upload(0x1018, 1))
    _, _, answer = emu.bus.expect(lambda i, d: i == 0x591, 5.0, "the SDO answer of node 17")
    shot = wait_for(driver, "the SDO request and its answer", row_with(sdo_text(answer), id="591"), 5.0)
    request = [r for r in shot["rows"] if r["id"] == "611"]
    assert [{f: r[f] for f in ("bus", "dir", "node", "kind", "text", "data")} for r in request] == [
        {"bus": "fakecan0", "dir": "rx", "node": "17", "kind": "SDO", "text": "SDO upload request 0x1018:01",
         "data": "40 18 10 01 00 00 00 00"}]
    response = [r for r in shot["rows"] if r["id"] == "591"][0]
    assert (response["dir"], response["node"], response["kind"]) == ("tx", "17", "SDO")
    assert response["data"] == " ".join(f"{b:02X}" for b in answer)
    assert shot["rows"].index(request[0]) < shot["rows"].index(response)
    assert re.fullmatch(r"\d+\.\d{3}", response["time"]), response["time"]

    # Heartbeats: node 18 every 500 ms, pre-operational.
    wait_for(driver, "node 18's heartbeat", row_with("heartbeat: pre-operational", id="712", node="18", dir="tx",
                                                     kind="heartbeat", data="7F"), 3.0)

    # An EMCY raised through the emulator's command language.
    command(emu, "emcy 17 0x8130 0x11")
    _, _, emcy = emu.bus.expect(lambda i, d: i == 0x091, 5.0, "the EMCY of node 17")
    assert emcy == bytes([0x30, 0x81, 0x11, 0, 0, 0, 0, 0])
    wait_for(driver, "the EMCY decoded",
             row_with("EMCY 0x8130 life guard error or heartbeat error, register 0x11 (generic, communication), "
                      "info 0000000000", id="091", node="17", kind="EMCY"), 5.0)

    # After NMT start the TPDOs come, their values named by the nodes' mapping (read as they appear).
    emu.bus.send(0x000, bytes([0x01, 0x00]))
    wait_for(driver, "the NMT start", row_with("NMT start: all nodes", id="000", node="", dir="rx", kind="NMT"), 5.0)
    _, _, tpdo = emu.bus.expect(lambda i, d: i == 0x191, 5.0, "TPDO1 of node 17")
    sds = ["Read System Status", "Read High Voltage Balance", "Read Power Capacity", "Read Pollution",
           "Read Working Distance"]
    units = ["", " % (50 = balanced)", " %", " %", " cm"]
    expected = "TPDO1 " + ", ".join(f"{n}={v}{u}" for n, v, u in zip(sds, tpdo, units))
    wait_for(driver, "node 17's TPDO1 by its mapping", row_with(expected, id="191", node="17", kind="PDO"), 10.0)
    wait_for(driver, "node 18's TPDO1 by its mapping", row_with("TPDO1 Sensor Value=0 l/min", id="192", node="18"), 10.0)
    shot = snapshot(driver)
    assert shot["problem"] == ""
    # Newest at the bottom: the times never go back.
    times = [float(r["time"]) for r in shot["rows"]]
    assert times == sorted(times)


def rows_of(shot, field):
    return [r[field] for r in shot["rows"]]


def test_the_filter_narrows_the_rows(page, start_emulator):
    emu = start_emulator(*NODES)
    driver = open_trace(page, emu)
    emu.bus.send(0x611, upload(0x1018, 1))
    emu.bus.send(0x610, upload(0x1017, 0))
    wait_for(driver, "both SDO answers", lambda s: {"591", "590"} <= set(rows_of(s, "id")), 5.0)
    wait_for(driver, "heartbeats of nodes 16 and 18", lambda s: {"710", "712"} <= set(rows_of(s, "id")), 5.0)

    Select(driver.find_element(By.ID, "trace-kind")).select_by_visible_text("SDO")
    shot = wait_for(driver, "only SDO rows", lambda s: set(rows_of(s, "kind")) == {"SDO"}, 2.0)
    assert rows_of(shot, "id") == ["611", "591", "610", "590"]

    node = driver.find_element(By.ID, "trace-node")
    node.send_keys("17")
    shot = wait_for(driver, "node 17's SDO rows", lambda s: rows_of(s, "id") == ["611", "591"], 2.0)
    assert rows_of(shot, "text")[0] == "SDO upload request 0x1018:01"

    node.clear()
    wait_for(driver, "the SDO rows of all nodes again", lambda s: rows_of(s, "id") == ["611", "591", "610", "590"], 2.0)
    node.send_keys("x")  # not a node-ID: said so, the rows stay as they were
    shot = wait_for(driver, "the error of the node field",
                    lambda s: s["problem"] == 'node: "x" is not a node-ID (1 to 127)', 2.0)
    assert rows_of(shot, "id") == ["611", "591", "610", "590"]
    assert driver.execute_script("return document.getElementById('trace-node').validity.valid") is False
    node.send_keys("\b")
    wait_for(driver, "the error gone", lambda s: s["problem"] == "", 2.0)

    Select(driver.find_element(By.ID, "trace-kind")).select_by_visible_text("all")
    text = driver.find_element(By.ID, "trace-text")
    text.send_keys("0x1017")  # free text over the decoded line
    shot = wait_for(driver, "the rows about 0x1017", lambda s: rows_of(s, "id") == ["610", "590"] and s["problem"] == "",
                    2.0)
    assert shot["rows"][1]["text"] == "SDO upload response 0x1017:00 expedited 2 bytes = 1000 (0x03E8)"
    text.clear()
    text.send_keys("712#05")  # COB-ID#data as candump writes it: node 18's heartbeats only
    emu.bus.send(0x000, bytes([0x01, 0x00]))  # operational: its heartbeat says 05 from now on
    wait_for(driver, "node 18's operational heartbeats only",  # typed key by key: the filter of "712#05" at last
             lambda s: len(s["rows"]) > 0 and {(r["id"], r["text"]) for r in s["rows"]} == {("712", "heartbeat: operational")},
             5.0)
    text.clear()
    text.send_keys(" ")  # nothing but blanks: every row again
    wait_for(driver, "all kinds again", lambda s: {"SDO", "NMT", "heartbeat", "PDO"} <= set(rows_of(s, "kind")), 5.0)


def test_pause_stops_new_rows_and_resume_catches_up(page, start_emulator):
    emu = start_emulator(*NODES)
    driver = open_trace(page, emu)
    wait_for(driver, "a heartbeat", lambda s: "712" in rows_of(s, "id"), 5.0)
    driver.find_element(By.ID, "trace-pause").click()
    before = wait_for(driver, "paused", lambda s: s["count"].endswith("; paused: 0 new not shown"), 2.0)
    emu.bus.send(0x611, upload(0x1018, 1))
    emu.bus.expect(lambda i, d: i == 0x591, 5.0, "the SDO answer of node 17")
    # Received meanwhile (the count goes on), not drawn.
    shot = wait_for(driver, "the frames counted while paused",
                    lambda s: int(re.search(r"paused: (\d+) new", s["count"]).group(1)) >= 2, 5.0)
    assert shot["rows"] == before["rows"]
    assert "611" not in rows_of(shot, "id")
    assert driver.find_element(By.ID, "trace-pause").text == "Resume"
    driver.find_element(By.ID, "trace-pause").click()
    shot = wait_for(driver, "the SDO rows after resuming", lambda s: {"611", "591"} <= set(rows_of(s, "id")), 2.0)
    assert recording(shot), shot["count"]
    assert shot["rows"][:len(before["rows"])] == before["rows"]  # appended after what was shown


def test_frames_are_recorded_while_the_trace_is_shown_or_asked_to_record(page, start_emulator):
    emu = start_emulator(*NODES)
    driver = open_trace(page, emu)
    driver.find_element(By.ID, "tab-network").click()
    emu.bus.send(0x611, upload(0x1018, 1))  # not recorded: the view was left (unsubscribed, and dropped meanwhile)
    emu.bus.expect(lambda i, d: i == 0x591, 5.0, "the SDO answer of node 17")
    driver.find_element(By.ID, "tab-trace").click()
    shot = wait_for(driver, "recording again", recording, 5.0)
    assert "611" not in rows_of(shot, "id")

    driver.find_element(By.ID, "trace-background").click()  # record while hidden
    driver.find_element(By.ID, "tab-network").click()
    emu.bus.send(0x610, upload(0x1018, 1))
    emu.bus.expect(lambda i, d: i == 0x590, 5.0, "the SDO answer of node 16")
    driver.find_element(By.ID, "tab-trace").click()
    shot = wait_for(driver, "the SDO of node 16 recorded while hidden", lambda s: "610" in rows_of(s, "id"), 5.0)
    assert "611" not in rows_of(shot, "id")


def test_a_page_opened_on_the_trace_records_at_once(page, start_emulator):
    """The address names the view (#trace): the page starts on it, and subscribes with its first session."""
    emu = start_emulator(*NODES)
    driver = page(emu)
    driver.get(f"http://127.0.0.1:{emu.port}/#trace")  # the fragment only: the same page
    driver.refresh()  # loaded anew on the trace
    assert driver.find_element(By.ID, "view-trace").is_displayed()
    wait_for(driver, "the frames subscribed", recording, 10.0)
    emu.bus.send(0x611, upload(0x1018, 1))
    wait_for(driver, "the SDO request", row_with("SDO upload request 0x1018:01", id="611"), 5.0)


def test_clear_empties_the_trace(page, start_emulator):
    emu = start_emulator(*NODES)
    driver = open_trace(page, emu)
    wait_for(driver, "a heartbeat", lambda s: "712" in rows_of(s, "id"), 5.0)
    driver.find_element(By.ID, "trace-clear").click()
    # Empty, but for a heartbeat that may come at once; the count says what the rows show.
    wait_for(driver, "the trace cleared",
             lambda s: len(s["rows"]) <= 2 and int(COUNT.fullmatch(s["count"]).group(1)) == len(s["rows"]) and
             all(r["id"] in ("710", "712") for r in s["rows"]), 2.0)
    emu.bus.send(0x611, upload(0x1018, 1))
    wait_for(driver, "the SDO after clearing", lambda s: "591" in rows_of(s, "id"), 5.0)


def candump_lines(path):
    """(seconds, interface, frame) of each line of a candump -l log."""
    lines = []
    for line in path.read_text().splitlines():
        match = re.fullmatch(r"\((\d+\.\d{6})\) (\S+) (\S+)", line)
        assert match, line
        lines.append((float(match.group(1)), match.group(2), match.group(3)))
    return lines


def frame_text(can_id, data, rtr=False):
    return f"{can_id:03X}#" + ("R" if rtr else data.hex().upper())


def test_download_saves_the_frames_as_a_candump_log(page, start_emulator, tmp_path, driver):
    """Node 18 (the Bürkert device: it has node guarding) alone, its heartbeat off: the only frames are those the test
    sends and the node's answers, each waited for before the next, so the log must hold exactly them, in order."""
    emu = start_emulator("buerkert:18")
    command(emu, "set 18 0x1017 0")
    end = time.monotonic() + 10.0  # its answer on stdout: no heartbeat from now on
    while not any("0x1017" in line for line in list(emu.out_lines)):
        assert time.monotonic() < end, emu.out_lines
        time.sleep(0.02)
    downloads = tmp_path / "downloads"
    downloads.mkdir()
    driver.execute_cdp_cmd("Browser.setDownloadBehavior",
                           {"behavior": "allow", "downloadPath": str(downloads), "eventsEnabled": True})
    browser = open_trace(page, emu, count=1)
    drain(emu.bus)
    browser.find_element(By.ID, "trace-clear").click()
    expected = []
    started = time.time()
    for request in (upload(0x1018, 1), upload(0x1017, 0), upload(0x5FFF, 0),
                    bytes([0x2B, 0x17, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00])):
        emu.bus.send(0x612, request)
        _, can_id, data = emu.bus.expect(lambda i, d: i == 0x592, 5.0, "the SDO answer")
        expected += [frame_text(0x612, request), frame_text(can_id, data)]
    emu.bus.send(0x123, bytes.fromhex("DEADBEEF"))  # not CANopen: in the log all the same
    expected.append("123#DEADBEEF")
    emu.bus.send(0x181 | CAN_EFF_FLAG, bytes.fromhex("1122"))  # a 29-bit frame: 8 digits, so canplayer sends it so
    expected.append("00000181#1122")
    for _ in range(2):  # node guarding: a remote request, answered with the state and the toggle bit
        emu.bus.send(0x712 | CAN_RTR_FLAG, b"")
        _, can_id, data = emu.bus.expect(lambda i, d: i == 0x712, 5.0, "the node guarding answer")
        expected += ["712#R", frame_text(can_id, data)]
    emu.bus.send(0x080, b"")
    expected.append("080#")
    shot = wait_for(browser, "every frame in the trace", lambda s: len(s["rows"]) == len(expected), 5.0)
    assert drain(emu.bus) == []  # the bus saw nothing else
    extended = [r for r in shot["rows"] if r["kind"] == "extended"]  # never read as node 1's TPDO1
    assert [(r["id"], r["node"], r["text"], r["data"]) for r in extended] == [("00000181", "", "", "11 22")], shot
    assert [r["text"] for r in shot["rows"]][-6:] == [
        "", "node guarding request", "node guarding answer: pre-operational, toggle 0", "node guarding request",
        "node guarding answer: pre-operational, toggle 1", "SYNC"]
    browser.find_element(By.ID, "trace-download").click()
    end = time.monotonic() + 10.0
    while time.monotonic() < end and not [p for p in downloads.iterdir() if p.suffix == ".log"]:
        time.sleep(0.05)
    saved = [p for p in downloads.iterdir() if p.suffix == ".log"]
    assert len(saved) == 1, list(downloads.iterdir())
    assert re.fullmatch(r"canopen-emu-\d{8}-\d{6}\.log", saved[0].name), saved[0].name
    lines = candump_lines(saved[0])
    assert [frame for _, _, frame in lines] == expected
    assert {iface for _, iface, _ in lines} == {"fakecan0"}
    stamps = [t for t, _, _ in lines]
    assert stamps == sorted(stamps)
    assert started - 60 < stamps[0] <= stamps[-1] < time.time() + 60  # the wall clock, not the emulator's
    assert browser.execute_script("return document.getElementById('trace-problem').textContent") == ""


def download(browser, driver, directory):
    """Clicks Download and returns the path of the log saved in `directory` (the browser told to save there)."""
    driver.execute_cdp_cmd("Browser.setDownloadBehavior",
                           {"behavior": "allow", "downloadPath": str(directory), "eventsEnabled": True})
    before = set(directory.iterdir())
    browser.find_element(By.ID, "trace-download").click()
    end = time.monotonic() + 20.0
    while time.monotonic() < end:
        saved = [p for p in set(directory.iterdir()) - before if p.suffix == ".log"]
        if saved:
            return saved[0]
        time.sleep(0.05)
    raise AssertionError(f"no log saved in {directory}: {list(directory.iterdir())}")


def test_127_nodes_with_100_ms_heartbeats_the_trace_keeps_up(page, start_emulator, tmp_path, driver):
    """sds:1 ... sds:127 operational, heartbeats every 100 ms and their TPDOs: some 1,800 frames a second. The trace
    takes every one (its log between two marker frames sent 4 s apart is exactly the run of frames the bus got),
    keeps 500 rows, and reads the mapping of all 127."""
    emu = start_emulator(*[f"sds:{n}" for n in range(1, 128)])
    browser = open_trace(page, emu, count=127)
    command(emu, "set all 0x1017 100")
    emu.bus.send(0x000, bytes([0x01, 0x00]))
    text = browser.find_element(By.ID, "trace-text")
    text.send_keys("123#")  # the rows of the markers only (the trace keeps every frame all the same)
    browser.find_element(By.ID, "trace-clear").click()
    emu.bus.send(0x123, bytes([0xAA]))  # the first marker
    wait_for(browser, "the first marker", lambda s: rows_of(s, "data") == ["AA"], 10.0)
    time.sleep(4.0)
    emu.bus.send(0x123, bytes([0xBB]))
    shot = wait_for(browser, "the second marker", lambda s: rows_of(s, "data") == ["AA", "BB"], 10.0)
    kept, dropped = map(int, COUNT.fullmatch(shot["count"]).group(1, 2))
    assert dropped == 0 and kept > 127 * 10 * 4, shot["count"]
    # The bus goes quiet (no heartbeats, Stopped: no PDOs) until the log is saved: however long a loaded machine
    # takes to get there, the ring (some 11 s of this traffic) still holds both markers.
    command(emu, "set all 0x1017 0")
    emu.bus.send(0x000, bytes([0x02, 0x00]))
    text.clear()
    text.send_keys(" ")
    shot = wait_for(browser, "every frame's row again", lambda s: len(s["rows"]) > 1, 5.0)
    assert len(shot["rows"]) == 500  # the newest 500: the DOM is bounded
    lines = candump_lines(download(browser, driver, tmp_path))
    frames = [f for _, _, f in lines]
    first, last = frames.index("123#AA"), frames.index("123#BB")
    stamps = [t for t, _, _ in lines]
    assert stamps == sorted(stamps)
    between = frames[first + 1:last]  # what the nodes sent: the bus got exactly these, in this order, none left out
    assert {f[:3] for f in between} >= {f"{0x700 + n:03X}" for n in range(1, 128)}
    sent = [frame_text(can_id, data) for _, can_id, data in drain(emu.bus)]
    assert any(sent[i:i + len(between)] == between for i, f in enumerate(sent) if f == between[0]), \
        f"the log's {len(between)} frames between the markers are not a run of the bus's {len(sent)}"
    # The mapping of all 127 read: the TPDO1 of each by name (the last 500 such rows: two seconds of them), with
    # the traffic back.
    command(emu, "set all 0x1017 100")
    emu.bus.send(0x000, bytes([0x01, 0x00]))
    text.clear()
    text.send_keys("TPDO1 Read System Status=")
    wait_for(browser, "the TPDO1 of nodes 1 to 127 by their mapping",
             lambda s: {r["node"] for r in s["rows"]} == {str(n) for n in range(1, 128)} and
             all(r["text"].startswith("TPDO1 Read System Status=") for r in s["rows"]), 30.0)


def test_sdo_values_by_their_objects_type_and_aborts_by_the_served_texts(page, start_emulator):
    """An expedited SDO's value as its object's data type says (the node's dictionary, read as its SDOs appear): 0x1008
    of the Pro-Ionizer is the text "ES61", not 825643845; a REAL32 a float; an INTEGER16 written negative, signed. An
    abort with the text the emulator serves (`tables`: the core's), the same its own log gives it."""
    emu = start_emulator(*NODES)
    driver = open_trace(page, emu)
    drain(emu.bus)
    emu.bus.send(0x610, upload(0x1008, 0))
    _, _, answer = emu.bus.expect(lambda i, d: i == 0x590, 5.0, "node 16's answer for 0x1008")
    assert answer == bytes([0x43, 0x08, 0x10, 0x00]) + b"ES61"
    wait_for(driver, "0x1008 as its text", row_with('SDO upload response 0x1008:00 expedited 4 bytes = "ES61"',
                                                    id="590", node="16", kind="SDO"), 10.0)
    emu.bus.send(0x612, upload(0x2004, 3))  # Device Supply Voltage of the Bürkert, REAL32 24.0
    wait_for(driver, "a REAL32 as a float", row_with("SDO upload response 0x2004:03 expedited 4 bytes = 24 "
                                                     "(0x41C00000)", id="592"), 10.0)
    emu.bus.send(0x610, bytes([0x2B, 0x02, 0x20, 0x35, 0xFB, 0xFF, 0, 0]))  # 0x2002:35 INTEGER16 := -5
    wait_for(driver, "a signed value written", row_with("SDO download request 0x2002:35 expedited 2 bytes = -5 "
                                                        "(0xFFFB)", id="610", dir="rx", node="16"), 10.0)
    # An abort: its text is the served one, as the emulator's own log has it
    session = emu.open_session()
    (tables,) = [l for l in emu.exchange(session, '{"id":1,"cmd":"tables"}').lines() if isinstance(l, dict)]
    text = {a["code"]: a["text"] for a in tables["aborts"]}[0x06020000]
    emu.bus.send(0x610, upload(0x2F00, 0))
    wait_for(driver, "the abort with its served text",
             row_with(f"SDO abort 0x2F00:00: 0x06020000 {text}", id="590", node="16", kind="SDO"), 10.0)
    emu.wait_log(f"SDO abort 0x06020000 on 0x2F00:00 ({text})")
    assert snapshot(driver)["problem"] == ""
