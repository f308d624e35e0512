"""The trace view of the web page in a browser (docs/web.md "The trace"): the frames the fake bus sends and sees,
decoded in CANopen terms in the page's table; its filter, pause, the frames recorded only while it is shown, and the
candump log it saves, compared line by line with the frames of the bus. Judged by the page's text: the cells of each
row (td[data-field]) and the status line of the view."""

import re
import time
from pathlib import Path

from selenium.common.exceptions import TimeoutException
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import Select, WebDriverWait

from test_overview import command, drain, loaded

NODES = ("pro-ionizer:16", "sds:17", "buerkert:18")
CAN_RTR_FLAG = 0x40000000
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
    seen = {}

    def holds(d):
        seen["last"] = snapshot(d)
        return seen["last"] if check(seen["last"]) else False

    try:
        return WebDriverWait(driver, timeout, poll_frequency=0.05).until(holds)
    except TimeoutException:
        last = seen.get("last") or {}
        raise AssertionError(f"not within {timeout} s: {what}; the trace showed {last.get('count')!r} "
                             f"{last.get('problem')!r}, last rows {(last.get('rows') or [])[-12:]}") from None


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
