"""The overview of the web view in a browser (docs/web.md): what the page shows of the nodes of
canopen-emu-fakecan, and how soon it shows a change made on the bus or by a command. Judged by the page's text:
the cells of each row (td[data-field]) and the status line."""

import queue
import re
import statistics
import time

from browser import wait_until

NODES = ("pro-ionizer:16", "sds:17", "buerkert:18")
FIELDS = ("node", "bus", "device", "state", "device-type", "heartbeat", "heartbeat-age", "error-register", "faults",
          "emcy", "emcy-age")
TITLES = ["node", "bus", "device", "NMT state", "device type", "heartbeat", "last heartbeat", "error register",
          "faults", "last EMCY", "EMCY sent"]
AGE = re.compile(r"(\d+\.\d) s ago( \(overdue\))?")

# The page at one moment (one script: nothing changes between two reads): rows {node-ID: {field: text}}, the
# node-IDs in the rows' order, those whose heartbeat is marked overdue (its age's cell in red), the status line.
SNAPSHOT = """
const rows = {}, order = [], overdue = [];
for (const tr of document.querySelectorAll("#nodes tbody tr")) {
  const cells = {};
  for (const td of tr.cells) { cells[td.dataset.field] = td.textContent; }
  rows[cells.node] = cells;
  order.push(Number(cells.node));
  if (tr.querySelector('td[data-field="heartbeat-age"].overdue') !== null) { overdue.push(Number(cells.node)); }
}
return {rows, order, overdue, status: document.getElementById("status").textContent};
"""


def snapshot(driver):
    return driver.execute_script(SNAPSHOT)


def wait_for(driver, what, check, timeout):
    """The first snapshot for which check(snapshot) holds, polled every 50 ms; fails with the last one seen."""
    return wait_until(driver, what, snapshot, check, timeout, lambda last: f"the page showed {last}")


def age(text):
    """Seconds of an age cell ("1.3 s ago")."""
    match = AGE.fullmatch(text)
    assert match, text
    return float(match.group(1))


def command(emu, line):
    """A line of the command language on the emulator's stdin (as a user types it)."""
    emu.proc.stdin.write(line + "\n")
    emu.proc.stdin.flush()


# A browser where no WebSocket opens (a policy forbids them): the constructor throws, as it does then.
NO_WEBSOCKET = "window.WebSocket = class { constructor() { throw new DOMException('no WebSocket', 'SecurityError'); } };"


def without_websocket(driver):
    """Pages loaded from now on have no WebSocket; call the returned function to give it back."""
    added = driver.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {"source": NO_WEBSOCKET})
    return lambda: driver.execute_cdp_cmd("Page.removeScriptToEvaluateOnNewDocument", {"identifier": added["identifier"]})


def loaded(page, emu, count, timeout=30.0):
    """The page of `emu` with `count` rows: the first load starts a browser, on a busy machine slowly."""
    driver = page(emu)
    wait_for(driver, f"{count} rows", lambda s: len(s["rows"]) == count, timeout)
    return driver


def test_the_page_lists_the_nodes_with_their_devices_and_states(page, start_emulator):
    emu = start_emulator(*NODES)
    driver = loaded(page, emu, 3)
    assert driver.title == "canopen-emu"
    titles = driver.execute_script("return [...document.querySelectorAll('#nodes thead th')].map((th) => th.textContent)")
    assert titles == TITLES
    shot = wait_for(driver, "the heartbeat ages", lambda s: all(AGE.fullmatch(r["heartbeat-age"])
                                                                 for r in s["rows"].values()), 5.0)
    assert shot["status"] == "fakecan0 (socketcan): 3 nodes"
    assert shot["order"] == [16, 17, 18]
    assert shot["overdue"] == []
    columns = driver.execute_script(
        "return [...document.querySelectorAll('#nodes tbody tr')].map((tr) => [...tr.cells].map((td) => td.dataset.field))")
    assert columns == [list(FIELDS)] * 3
    # the bus by its name in its column, by its name and kind on hovering over it (and in the status line)
    bus_titles = driver.execute_script(
        "return [...document.querySelectorAll('#nodes tbody td[data-field=bus]')].map((td) => td.title)")
    assert bus_titles == ["fakecan0 (socketcan)"] * 3
    for row in shot["rows"].values():
        assert age(row.pop("heartbeat-age")) < 30.0  # its first heartbeat: the emulator started a moment ago
    # device types, heartbeat periods: the EDS files (od/*.eds); nothing raised, no fault injected
    common = {"bus": "fakecan0", "state": "PRE-OPERATIONAL", "error-register": "0x00", "faults": "", "emcy": "",
              "emcy-age": ""}
    assert shot["rows"] == {
        "16": {"node": "16", "device": "pro-ionizer (full)", "device-type": "0x000F0191", "heartbeat": "1000 ms",
               **common},
        "17": {"node": "17", "device": "sds (N)", "device-type": "0x00000191", "heartbeat": "5000 ms", **common},
        "18": {"node": "18", "device": "buerkert", "device-type": "0x00000000", "heartbeat": "500 ms", **common},
    }


def test_nmt_start_from_the_bus_shows_operational_within_2_s(page, start_emulator):
    emu = start_emulator(*NODES)
    driver = loaded(page, emu, 3)
    shot = snapshot(driver)
    assert [r["state"] for r in shot["rows"].values()] == ["PRE-OPERATIONAL"] * 3
    emu.bus.send(0x000, bytes([0x01, 0x00]))  # NMT start, all nodes
    wait_for(driver, "OPERATIONAL for all three",
             lambda s: [r["state"] for r in s["rows"].values()] == ["OPERATIONAL"] * 3, 2.0)
    emu.bus.send(0x000, bytes([0x02, 17]))  # NMT stop, node 17 only
    shot = wait_for(driver, "STOPPED for node 17", lambda s: s["rows"]["17"]["state"] == "STOPPED", 2.0)
    assert [shot["rows"][n]["state"] for n in ("16", "18")] == ["OPERATIONAL"] * 2


def test_an_emcy_shows_in_its_nodes_row(page, start_emulator):
    emu = start_emulator(*NODES)
    driver = loaded(page, emu, 3)
    command(emu, "emcy 17 0x5000 0x01 0xA1 0xB2 0xC3 0xD4 0xE5")
    _, _, frame = emu.bus.expect(lambda i, d: i == 0x091, 5.0, "the EMCY of node 17")
    assert frame == bytes([0x00, 0x50, 0x01, 0xA1, 0xB2, 0xC3, 0xD4, 0xE5])
    shot = wait_for(driver, "the EMCY in node 17's row",
                    lambda s: s["rows"]["17"]["emcy"] == "0x5000 device hardware, reg 0x01 info A1B2C3D4E5", 2.0)
    assert shot["rows"]["17"]["error-register"] == "0x01"
    assert age(shot["rows"]["17"]["emcy-age"]) < 2.0
    assert [(shot["rows"][n]["emcy"], shot["rows"][n]["error-register"]) for n in ("16", "18")] == [("", "0x00")] * 2
    # The time since it keeps going (the emulator's clock from each show, the page's in between).
    first = age(shot["rows"]["17"]["emcy-age"])
    shot = wait_for(driver, "the EMCY's age a second on", lambda s: age(s["rows"]["17"]["emcy-age"]) >= first + 1.0, 5.0)
    assert shot["rows"]["17"]["emcy"] == "0x5000 device hardware, reg 0x01 info A1B2C3D4E5"


def test_a_protocol_fault_shows_and_the_heartbeat_age_grows(page, start_emulator):
    """Node 18 (500 ms heartbeat) stops its heartbeat: the fault shows, and its last heartbeat falls behind, marked
    overdue, while node 16's (1000 ms) stays recent; cleared, both show again, unmarked."""
    emu = start_emulator(*NODES)
    driver = loaded(page, emu, 3)
    command(emu, "fault 18 heartbeat-stop")
    shot = wait_for(driver, "the fault of node 18", lambda s: s["rows"]["18"]["faults"] == "heartbeat-stop", 2.0)
    in_force = time.monotonic()  # shown, so in force: no heartbeat of node 18 may come after this
    assert [shot["rows"][n]["faults"] for n in ("16", "17")] == ["", ""]
    # A running 500 ms heartbeat is never 4 s old, even seen through a show up to a second old.
    shot = wait_for(driver, "node 18's last heartbeat 4 s ago", lambda s: age(s["rows"]["18"]["heartbeat-age"]) >= 4.0,
                    10.0)
    assert age(shot["rows"]["16"]["heartbeat-age"]) < 3.0, shot["rows"]["16"]
    # more than 1.5 periods old at a show (web/nodes.js heartbeatOverdue): marked, in words and in red
    assert shot["rows"]["18"]["heartbeat-age"].endswith(" s ago (overdue)"), shot["rows"]["18"]
    assert shot["overdue"] == [18], shot
    late = [t - in_force for t, i, _ in drain(emu.bus) if i == 0x712 and t > in_force]
    assert late == [], late  # the bus agrees: nothing from node 18 since the fault
    command(emu, "fault-clear 18 heartbeat-stop")
    shot = wait_for(driver, "node 18's heartbeat back",
                    lambda s: s["rows"]["18"]["faults"] == "" and age(s["rows"]["18"]["heartbeat-age"]) < 2.0 and
                    s["overdue"] == [], 5.0)
    assert shot["rows"]["18"]["state"] == "PRE-OPERATIONAL"
    assert not shot["rows"]["18"]["heartbeat-age"].endswith("(overdue)"), shot["rows"]["18"]


def drain(bus):
    """Every frame the fake bus has received and no test has taken yet: (time, id, data)."""
    frames = []
    while not bus.frames.empty():
        frames.append(bus.frames.get_nowait())
    return frames


def test_127_nodes_are_127_rows_and_the_heartbeats_keep_their_time(page, start_emulator):
    """sds:1 ... sds:127: every row within a few seconds, all OPERATIONAL within 2 s of an NMT start, and with the
    page exchanging four times a second the 127 heartbeats (set to 500 ms) keep their period on the bus."""
    emu = start_emulator(*[f"sds:{n}" for n in range(1, 128)])
    driver = loaded(page, emu, 127)
    shot = snapshot(driver)
    assert shot["order"] == list(range(1, 128))
    assert {(r["device"], r["state"]) for r in shot["rows"].values()} == {("sds (N)", "PRE-OPERATIONAL")}
    assert shot["status"] == "fakecan0 (socketcan): 127 nodes"
    emu.bus.send(0x000, bytes([0x01, 0x00]))
    wait_for(driver, "OPERATIONAL for all 127",
             lambda s: {r["state"] for r in s["rows"].values()} == {"OPERATIONAL"}, 2.0)
    command(emu, "set all 0x1017 500")
    wait_for(driver, "the 500 ms heartbeat of all 127",
             lambda s: {r["heartbeat"] for r in s["rows"].values()} == {"500 ms"}, 5.0)
    drain(emu.bus)
    end = time.monotonic() + 4.0
    seen = {}
    while time.monotonic() < end:  # the bus's frames as they come, with the page exchanging meanwhile
        try:
            t, can_id, data = emu.bus.frames.get(timeout=1.0)
        except queue.Empty:
            raise AssertionError("no frame for 1 s from 127 nodes with a 500 ms heartbeat") from None
        if 0x701 <= can_id <= 0x77F and data == b"\x05":
            seen.setdefault(can_id - 0x700, []).append(t)
    assert sorted(seen) == list(range(1, 128))
    periods = [b - a for times in seen.values() for a, b in zip(times[1:], times[2:])]  # the first may be the set's
    assert 127 * 5 <= len(periods), len(periods)
    assert 0.49 <= statistics.median(periods) <= 0.51, statistics.median(periods)
    assert max(periods) < 0.8, sorted(periods)[-10:]
    assert snapshot(driver)["status"] == "fakecan0 (socketcan): 127 nodes"


def test_requests_answers_and_events_go_over_the_websocket_and_nothing_is_posted(page, start_emulator):
    """With the session's WebSocket open, the page's requests (`show all` once a second, the plots' samples) go out
    on it and everything comes back on it: no exchange at all, and a change on the bus shows at once."""
    emu = start_emulator(*NODES)
    driver = loaded(page, emu, 3)
    time.sleep(2.5)  # the socket opens after the first exchange
    driver.execute_script("performance.clearResourceTimings()")
    start = time.monotonic()
    emu.bus.send(0x000, bytes([0x01, 16]))  # NMT start node 16
    wait_for(driver, "node 16 OPERATIONAL", lambda s: s["rows"]["16"]["state"] == "OPERATIONAL", 1.0)
    time.sleep(max(0.0, start + 3.0 - time.monotonic()))
    command(emu, "emcy 17 0x5000 0x81")  # answered shows need requests: the table goes on changing
    shot = wait_for(driver, "the EMCY of node 17", lambda s: s["rows"]["17"]["emcy"].startswith("0x5000"), 2.0)
    fetches = driver.execute_script(
        "return performance.getEntriesByType('resource').filter((e) => e.initiatorType === 'fetch')"
        ".map((e) => new URL(e.name).pathname)")
    assert fetches == [], fetches
    assert shot["status"] == "fakecan0 (socketcan): 3 nodes"
    ages = [age(r["heartbeat-age"]) for r in shot["rows"].values() if AGE.fullmatch(r["heartbeat-age"])]
    assert ages and max(ages) < 3.0, shot  # show all is asked and answered over the socket: the ages are fresh


def test_without_a_websocket_the_stream_keeps_the_session_of_a_page_that_cannot_post(page, start_emulator, driver):
    """The WebSocket blocked (as a proxy that does not pass one would): the page takes its answers and events from
    its stream and posts its requests. The browser offline for new requests (Chromium's emulation leaves an open
    connection as it is): the page's exchanges fail and it says so, but its stream keeps its session (no expiry
    after 10 s) and brings what happened; back online, it posts again in the same session."""
    restore = without_websocket(driver)
    try:
        stream_page(page, start_emulator, driver)
    finally:
        restore()  # the browser serves the next tests


def stream_page(page, start_emulator, driver):
    emu = start_emulator(*NODES)
    driver = loaded(page, emu, 3)
    time.sleep(2.5)  # the stream opens after the first exchange
    session_url = rf"^http://127\.0\.0\.1:{emu.port}/api/session/[0-9a-f]{{32}}"
    page.expected_errors += [session_url + " - Failed to load resource: net::ERR_INTERNET_DISCONNECTED$"]
    driver.set_network_conditions(offline=True, latency=0, throughput=0)
    try:
        wait_for(driver, "the problem in the status line",
                 lambda s: s["status"] == "the emulator does not answer (stopped?)", 2.0)
        emu.bus.send(0x000, bytes([0x01, 0x00]))  # NMT start, all nodes: its events come on the stream
        wait_for(driver, "OPERATIONAL for all three through the stream",
                 lambda s: [r["state"] for r in s["rows"].values()] == ["OPERATIONAL"] * 3, 2.0)
        time.sleep(11.0)
        assert "removed" not in emu.log()
    finally:
        driver.delete_network_conditions()
    wait_for(driver, "the status line without a problem", lambda s: s["status"] == "fakecan0 (socketcan): 3 nodes", 3.0)
    command(emu, "emcy 16 0x3210 0x05")
    wait_for(driver, "the EMCY of node 16", lambda s: s["rows"]["16"]["emcy"] == "0x3210 voltage inside the device, reg 0x05 info 0000000000", 2.0)
    assert "removed" not in emu.log() and "dropped" not in emu.log()


def test_without_a_stream_the_page_exchanges_and_comes_back_after_its_session_expired(page, start_emulator, driver):
    """The stream refused (blocked: as a proxy that does not pass a streamed answer would): the page takes
    everything with its exchanges. One that could not exchange for over 10 s (the browser offline; as a hidden tab
    whose timers the browser slowed) finds its session removed, opens a new one, and shows what happened meanwhile."""
    driver.execute_cdp_cmd("Network.enable", {})
    driver.execute_cdp_cmd("Network.setBlockedURLs", {"urls": ["*/stream"]})
    restore = without_websocket(driver)
    try:
        emu = start_emulator(*NODES)
        driver = loaded(page, emu, 3)
        # What the browser logs of the streams blocked, the exchanges cut off, and the one that found the session gone.
        session_url = rf"^http://127\.0\.0\.1:{emu.port}/api/session/[0-9a-f]{{32}}"
        page.expected_errors += [session_url + "/stream - Failed to load resource: net::ERR_BLOCKED_BY_CLIENT$",
                                 session_url + " - Failed to load resource: net::ERR_INTERNET_DISCONNECTED$",
                                 session_url + r" - Failed to load resource: the server responded with a status of 404 \(Not Found\)$"]
        driver.set_network_conditions(offline=True, latency=0, throughput=0)
        try:
            wait_for(driver, "the problem in the status line",
                     lambda s: s["status"] == "the emulator does not answer (stopped?)", 2.0)
            emu.bus.send(0x000, bytes([0x01, 0x00]))  # NMT start, all nodes, while the page sees nothing
            emu.wait_log("web: web session 1 removed: no exchange for 10 s", timeout=20.0)
            assert [r["state"] for r in snapshot(driver)["rows"].values()] == ["PRE-OPERATIONAL"] * 3
        finally:
            driver.delete_network_conditions()
        shot = wait_for(driver, "OPERATIONAL for all three through a new session",
                        lambda s: [r["state"] for r in s["rows"].values()] == ["OPERATIONAL"] * 3, 5.0)
        assert shot["status"] == "fakecan0 (socketcan): 3 nodes"
        command(emu, "emcy 16 0x3210 0x05")  # and its events come again
        wait_for(driver, "the EMCY of node 16", lambda s: s["rows"]["16"]["emcy"] == "0x3210 voltage inside the device, reg 0x05 info 0000000000", 2.0)
    finally:
        driver.execute_cdp_cmd("Network.setBlockedURLs", {"urls": []})  # the browser serves the next tests
        restore()


def test_nodes_heard_on_the_bus_get_a_row_that_does_not_open(page, start_emulator):
    """A node that is not emulated shows by its heartbeats: its state and their age; a click does not open it."""
    emu = start_emulator(*NODES)
    driver = loaded(page, emu, 3)
    emu.bus.send(0x705, b"\x05")  # node 5 elsewhere on the bus: Operational
    shot = wait_for(driver, "a row for node 5", lambda s: s["order"] == [5, 16, 17, 18], 3.0)
    row = shot["rows"]["5"]
    assert {k: v for k, v in row.items() if k != "heartbeat-age"} == {
        "node": "5", "bus": "fakecan0", "device": "heard on the bus", "state": "OPERATIONAL", "device-type": "",
        "heartbeat": "", "error-register": "", "faults": "", "emcy": "", "emcy-age": ""}
    assert age(row["heartbeat-age"]) < 3.0
    assert shot["status"] == "fakecan0 (socketcan): 3 nodes, 1 heard on the bus"
    emu.bus.send(0x705, b"\x00")  # its boot-up: it was reset
    wait_for(driver, "node 5 booted", lambda s: s["rows"]["5"]["device"] == "heard on the bus (boot-up)"
             and s["rows"]["5"]["state"] == "PRE-OPERATIONAL", 3.0)
    driver.find_element("css selector", '#nodes tr[data-key="fakecan0/5"]').click()
    assert driver.execute_script("return document.getElementById('tab-node').disabled") is True
    assert driver.execute_script("return document.getElementById('view-network').hidden") is False
    driver.find_element("css selector", '#nodes tr[data-key="fakecan0/17"]').click()
    assert driver.execute_script("return document.getElementById('view-node').hidden") is False
    assert driver.execute_script("return location.hash") == "#node"
