#!/usr/bin/env python3
"""Screenshots of the web view's views for the docs (docs/web/*.png: docs/web.md shows them, README.md the network
view): the page of canopen-emu-fakecan (the whole program, its CAN bus played by this script) with the README's
three nodes and a scripted scene, in Debian's headless Chromium at 1280x800.

    python3 tests/web/screenshots.py --emu PATH --out DIR

tools/web-screenshots builds the program and runs this into docs/web/; the ctest web/screenshots runs it into the
build tree, so that the command keeps working. Each picture is taken once its view shows what the scene made (rows,
values, points, frames): a view that does not get there fails the run rather than leaving an empty picture.
"""

import argparse
import os
import struct
import sys
import tempfile
import time
from pathlib import Path

from browser import WINDOW, missing, start_browser

HERE = Path(__file__).resolve().parent
NODES = ("pro-ionizer:16", "sds:17", "buerkert:18")


def wait(driver, what, script, timeout=20.0):
    """Polls `script` (JavaScript returning a truthy value when the view is ready) until it holds."""
    end = time.monotonic() + timeout
    while True:
        result = driver.execute_script(script)
        if result:
            return result
        if time.monotonic() > end:
            raise SystemExit(f"screenshots: {what}: not shown within {timeout} s")
        time.sleep(0.1)


def command(emu, line):
    emu.proc.stdin.write(line + "\n")
    emu.proc.stdin.flush()


def sdo_upload(emu, node, index, sub):
    """An SDO upload from the script's 'master' on the fake bus, its answer awaited (the trace shows both)."""
    emu.bus.send(0x600 + node, bytes([0x40, index & 0xFF, index >> 8, sub, 0, 0, 0, 0]))
    emu.bus.expect(lambda i, d: i == 0x580 + node and d[1:4] == bytes([index & 0xFF, index >> 8, sub]), 5.0,
                   f"the SDO answer of node {node}")


def scene(emu):
    """What the pictures show: a started network, one node heard beside the emulated ones, an EMCY, a protocol
    fault in force, some SDO traffic."""
    emu.bus.send(0x705, b"\x05")  # a device elsewhere on the bus: heard, Operational
    emu.bus.send(0x000, bytes([0x01, 0x00]))  # NMT start, all nodes
    command(emu, "emcy 17 0x5000 0x01 0xA1 0xB2 0xC3 0xD4 0xE5")
    command(emu, "fault 18 heartbeat-jitter 200")
    command(emu, "setpoint 18 40")  # the flow controller's values move towards it: the plot has a curve
    for node in (16, 17, 18):
        sdo_upload(emu, node, 0x1018, 1)


def shoot(driver, out, name):
    """The window as a PNG file; checked to be one, as wide as the window, and not a blank page (a blank 1280 px
    PNG compresses to a few hundred bytes; a page with text and lines takes tens of kilobytes)."""
    path = out / f"{name}.png"
    driver.save_screenshot(str(path))
    data = path.read_bytes()
    width, height = struct.unpack(">II", data[16:24])
    if data[:8] != b"\x89PNG\r\n\x1a\n" or data[12:16] != b"IHDR" or width != WINDOW[0] or len(data) < 8000:
        raise SystemExit(f"screenshots: {path}: not a {WINDOW[0]} px wide picture of the page "
                         f"({len(data)} bytes, {width}x{height})")
    print(f"screenshots: {path} ({width}x{height}, {len(data)} bytes)")
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--emu", required=True, help="canopen-emu-fakecan")
    parser.add_argument("--out", required=True, type=Path, help="directory for the PNG files")
    args = parser.parse_args()
    os.environ["CO_EMU_FAKECAN"] = str(Path(args.emu).resolve())
    sys.path.insert(0, str(HERE.parent / "native"))
    from test_web_native import WebEmulator  # the emulator as the native web tests start it

    if missing():
        raise SystemExit(f"screenshots: no {' or '.join(missing())} (Debian: apt-get install "
                         "--no-install-recommends chromium chromium-driver)")
    args.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="co-shots-") as tmp:
        emu = WebEmulator(Path(tmp), nodes=NODES)
        driver = start_browser()
        try:
            scene(emu)
            driver.get(f"http://127.0.0.1:{emu.port}/#network")
            wait(driver, "the network: four rows, the emulated nodes Operational, the EMCY and the fault", """
                const rows = [...document.querySelectorAll('#nodes tbody tr')];
                const text = (key, field) => document.querySelector(
                    `#nodes tr[data-key="${key}"] td[data-field="${field}"]`)?.textContent;
                return rows.length === 4 && ["16", "17", "18"].every((n) => text(`fakecan0/${n}`, "state") ===
                    "OPERATIONAL") && text("fakecan0/17", "emcy") !== "" && text("fakecan0/18", "faults") !== "";
            """)
            shoot(driver, args.out, "network")
            driver.find_element("css selector", '#nodes tr[data-key="fakecan0/18"]').click()
            wait(driver, "the node view's dictionary", """
                return !document.getElementById('view-node').hidden &&
                    document.querySelector('#view-node tr.group[data-index="0x1018"] button.toggle') !== null;
            """)
            driver.find_element("css selector", '#view-node tr.group[data-index="0x1018"] button.toggle').click()
            wait(driver, "the identity's values", """
                const cells = [...document.querySelectorAll('#view-node tr.entry td[data-field="value"]')];
                return cells.filter((td) => td.textContent !== "").length >= 8;
            """)
            shoot(driver, args.out, "node")
            driver.find_element("id", "tab-plots").click()
            # steps of the set-point (the flow follows), an over-temperature and its end (EMCYs: marks on the axis)
            for line in ("setpoint 18 75", "temperature 18 80", "setpoint 18 20", "temperature 18 25",
                         "setpoint 18 55"):
                time.sleep(1.5)
                command(emu, line)
            wait(driver, "the plots: 40 samples of node 18", """
                const charts = [...document.querySelectorAll('#view-plots [data-points]')];
                return charts.length > 0 && charts.every((c) => Number(c.dataset.points) >= 40);
            """, timeout=40.0)
            shoot(driver, args.out, "plots")
            driver.find_element("id", "tab-trace").click()
            wait(driver, "the trace view", "return !document.getElementById('view-trace').hidden")
            time.sleep(1.0)  # its subscription is in place
            for node in (16, 17, 18):
                sdo_upload(emu, node, 0x1000, 0)
            command(emu, "emcy 16 0x4210 0x09 1 2 3 4 5")
            wait(driver, "the trace: SDO, EMCY, PDO and heartbeat rows", """
                const kinds = new Set([...document.querySelectorAll('#view-trace tr[data-kind]')]
                    .map((tr) => tr.dataset.kind));
                // and every PDO by its mapping (read lazily, node by node: "TPDO1 Sensor Value=55 l/min")
                const pdos = [...document.querySelectorAll('#view-trace tr[data-kind="PDO"] td[data-field="text"]')];
                return ["SDO", "EMCY", "PDO", "heartbeat"].every((k) => [...kinds].some((s) => s.startsWith(k))) &&
                    pdos.length > 0 && pdos.every((td) => td.textContent.includes("="));
            """)
            # held where the SDO and EMCY rows are still in sight (the PDOs of three nodes move the table on)
            driver.find_element("xpath", "//section[@id='view-trace']//button[text()='Pause']").click()
            shoot(driver, args.out, "trace")
            errors = [e["message"] for e in driver.get_log("browser") if e["level"] == "SEVERE"]
            if errors:
                raise SystemExit(f"screenshots: the page logged errors: {errors}")
        finally:
            driver.quit()
            emu.quit()


if __name__ == "__main__":
    main()
