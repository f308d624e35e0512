"""The node view of the web view in a browser (docs/web.md "The node view"): a node opened from its row, its
dictionary with live values, values written in place (seen on the fake bus and by a python-canopen master), its
device's commands, the node commands and the protocol faults as controls. Judged by the page's text and by the exact
frames the nodes send on the fake bus."""

import statistics
import time

import canopen
from selenium.webdriver.common.by import By
from selenium.webdriver.common.keys import Keys
from selenium.webdriver.support.ui import Select, WebDriverWait

from browser import wait_until
from python_can_bus import FakeCanBus
from test_emulator_native import vendor_id

NODES = ("pro-ionizer:16", "sds:17", "buerkert:18")

# The node view at one moment (one script): the tab's label, the summary, each dictionary row shown {object: {field:
# text, editable, editor}}, each form's answer (a fault's as "fault KIND", with whether it is in force), the notes.
NODE_VIEW = """
const view = document.getElementById("view-node");
const rows = {};
for (const tr of view.querySelectorAll("table.dictionary tr.entry")) {
  const cells = {};
  for (const td of tr.cells) { cells[td.dataset.field] = td.textContent; }
  cells.editable = tr.querySelector("td.editable") !== null;
  cells.editor = tr.querySelector("input.editor") !== null;
  rows[tr.dataset.object] = cells;
}
const summary = {};
for (const dd of view.querySelectorAll(".node-summary dd")) { summary[dd.dataset.field] = dd.textContent; }
const forms = {};
for (const form of view.querySelectorAll("form.command")) {
  const output = form.querySelector("output");
  forms[form.dataset.fault ? `fault ${form.dataset.fault}` : form.dataset.command] = {
    answer: output.textContent, refused: output.classList.contains("refusal"),
    state: form.querySelector(".state")?.textContent ?? null};
}
return {
  tab: document.getElementById("tab-node").textContent, hidden: view.hidden, summary, rows, forms,
  device: [...view.querySelectorAll(".device-commands form")].map((f) => f.dataset.command),
  groups: [...view.querySelectorAll("table.dictionary tr.group")].map((tr) => tr.dataset.index),
  note: view.querySelector(".toolbar .note").textContent,
  picker: view.querySelector(".node-picker select").value,
};
"""


def view(driver):
    return driver.execute_script(NODE_VIEW)


def wait_for(driver, what, check, timeout):
    """The first view for which check(view) holds, polled every 50 ms; fails with the last one seen."""
    def describe(last):
        last = last or {}
        shown = {k: v for k, v in last.items() if k != "rows"}  # the rows of a whole dictionary would bury it
        rows = {o: r for o, r in last.get("rows", {}).items() if r["value"] or r["note"] or r["editor"]}
        return f"the page showed {shown}, rows with a value, note or editor {rows}"
    return wait_until(driver, what, view, check, timeout, describe)


def command(emu, line):
    """A line of the command language on the emulator's stdin."""
    emu.proc.stdin.write(line + "\n")
    emu.proc.stdin.flush()


def css(driver, selector):
    element = driver.find_element(By.CSS_SELECTOR, selector)
    driver.execute_script("arguments[0].scrollIntoView({block: 'center'})", element)
    return element


def open_node(page, emu, node):
    """The page of `emu` with the node `node` opened by a click on its row, its dictionary read."""
    driver = page(emu)
    row = WebDriverWait(driver, 30.0, poll_frequency=0.05).until(
        lambda d: d.find_elements(By.CSS_SELECTOR, f'#nodes tr[data-key="fakecan0/{node}"]'))[0]
    row.click()
    wait_for(driver, f"the dictionary of node {node}", lambda v: not v["hidden"] and "0x1000:00" in v["rows"], 10.0)
    return driver


def expand(driver, index):
    css(driver, f'tr[data-index="{index}"] button.toggle').click()


def edit(driver, obj, text):
    """Clicks the value of `obj`, types `text` over it and presses Enter."""
    css(driver, f'tr[data-object="{obj}"] td[data-field="value"]').click()
    editor = css(driver, f'tr[data-object="{obj}"] input.editor')
    editor.send_keys(Keys.CONTROL, "a")
    editor.send_keys(text, Keys.ENTER)


def run(driver, form, *values):
    """Fills the fields of a command's form (inputs and selects, in order) and presses its run/raise button."""
    fields = driver.find_elements(By.CSS_SELECTOR, f"{form} .fields input, {form} .fields select")
    assert len(fields) >= len(values), (form, len(fields))
    for field, value in zip(fields, values):
        if field.tag_name == "select":
            Select(field).select_by_value(value)
        else:
            field.send_keys(Keys.CONTROL, "a")
            field.send_keys(value)
    css(driver, f'{form} button[type="submit"]').click()


def drain(bus):
    frames = []
    while not bus.frames.empty():
        frames.append(bus.frames.get_nowait())
    return frames


def heartbeat_gaps(bus, node, count, timeout):
    """The gaps between the next count + 1 heartbeats of `node` on the fake bus (their arrival times)."""
    times = [bus.expect(lambda i, d: i == 0x700 + node and len(d) == 1, timeout, f"heartbeat of node {node}")[0]
             for _ in range(count + 1)]
    return [b - a for a, b in zip(times, times[1:])]


def test_a_row_click_opens_the_node_with_its_dictionary_and_live_values(page, start_emulator):
    emu = start_emulator(*NODES)
    driver = open_node(page, emu, 18)
    shown = wait_for(driver, "the Bürkert's summary and commands",
                     lambda v: v["summary"]["device"] == "buerkert" and v["device"], 5.0)
    assert shown["tab"] == "Node 18 (buerkert)"
    assert shown["picker"] == "fakecan0/18"
    assert shown["summary"]["state"] == "PRE-OPERATIONAL"
    assert shown["summary"]["heartbeat"] == "500 ms"
    assert shown["summary"]["error-register"] == "0x00"
    # help 18: the device's commands, each a form ("error CODE [STATE]", "mode auto|hand|flashing" ...)
    assert shown["device"] == ["setpoint", "flow-fault", "valve-fault", "supply", "temperature", "error",
                               "clear-error", "mode", "status"]
    assert "0x1018" in shown["groups"] and "0x1018:01" not in shown["rows"]  # objects of several: collapsed
    assert shown["rows"]["0x1017:00"]["object"] == "0x1017"  # an object of one sub-index is one row
    # numeric rows have a plot button (shown when a plots view takes it: page.plot), strings none
    assert shown["rows"]["0x1017:00"]["actions"] == "plot"
    assert shown["rows"]["0x1008:00"]["actions"] == ""
    expand(driver, "0x1018")
    # (15 s: the rows are read at the next exchange; a full suite's load once delayed it past 5 s)
    shown = wait_for(driver, "the identity's values",
                     lambda v: all(v["rows"].get(f"0x1018:0{s}", {}).get("value") for s in range(5)), 15.0)
    identity = {o: {f: shown["rows"][o][f] for f in ("object", "name", "type", "access", "value", "editable")}
                for o in ("0x1018:00", "0x1018:01")}
    assert identity == {
        "0x1018:00": {"object": "0x1018:00", "name": "Number Of Entries", "type": "UNSIGNED8", "access": "ro",
                      "value": "4", "editable": False},
        "0x1018:01": {"object": "0x1018:01", "name": "Vendor ID", "type": "UNSIGNED32", "access": "ro",
                      "value": str(vendor_id("buerkert")), "editable": False},
    }
    # unit and limits where the device gives them
    expand(driver, "0x2540")
    shown = wait_for(driver, "the set-point with its unit", lambda v: "0x2540:01" in v["rows"], 5.0)
    assert (shown["rows"]["0x2540:01"]["unit"], shown["rows"]["0x2540:01"]["type"]) == ("l/min", "REAL32")
    # Live: a value changed by the command language shows without any action in the page.
    css(driver, 'tr[data-object="0x1017:00"]')
    command(emu, "set 18 0x1017 250")
    wait_for(driver, "the heartbeat period set on stdin", lambda v: v["rows"]["0x1017:00"]["value"] == "250", 5.0)
    # The picker opens another node.
    Select(css(driver, ".node-picker select")).select_by_value("fakecan0/16")
    shown = wait_for(driver, "node 16's dictionary", lambda v: "0x2002" in v["groups"], 5.0)
    assert shown["tab"] == "Node 16 (pro-ionizer)"
    assert shown["summary"]["device"] == "pro-ionizer (full)"
    limits = wait_for(driver, "node 16's 0x1017 read", lambda v: v["rows"]["0x1017:00"]["value"] == "1000", 5.0)
    assert limits["rows"]["0x1017:00"]["limits"] == "0..60000"


def test_the_heartbeat_period_edited_in_place_reaches_the_bus_and_a_refusal_shows(page, start_emulator):
    emu = start_emulator(*NODES)
    driver = open_node(page, emu, 16)
    wait_for(driver, "0x1017 read", lambda v: v["rows"]["0x1017:00"]["value"] == "1000", 5.0)
    edit(driver, "0x1017:00", "200")
    shown = wait_for(driver, "200 written", lambda v: not v["rows"]["0x1017:00"]["editor"] and
                     v["rows"]["0x1017:00"]["value"] == "200", 5.0)
    assert shown["rows"]["0x1017:00"]["note"] == ""
    drain(emu.bus)
    gaps = heartbeat_gaps(emu.bus, 16, 6, 5.0)[1:]  # the first may have begun before the write
    assert 0.19 <= statistics.median(gaps) <= 0.21, gaps
    assert all(0.15 <= g <= 0.30 for g in gaps), gaps
    # Out of the type's range: the protocol's error beside the row, the value as it was.
    edit(driver, "0x1017:00", "70000")
    shown = wait_for(driver, "the refusal", lambda v: v["rows"]["0x1017:00"]["note"] != "" and
                     v["rows"]["0x1017:00"]["note"] != "writing…", 5.0)
    assert shown["rows"]["0x1017:00"]["note"] == "70000 is out of range: 0x1017:00 (UNSIGNED16) holds 0..65535"
    assert (shown["rows"]["0x1017:00"]["value"], shown["rows"]["0x1017:00"]["editor"]) == ("200", False)
    edit(driver, "0x1017:00", "abc")
    wait_for(driver, "the refusal of a word", lambda v: v["rows"]["0x1017:00"]["note"] == "'abc' is not a number", 5.0)
    # Escape leaves it as it was, without a write.
    css(driver, 'tr[data-object="0x1017:00"] td[data-field="value"]').click()
    css(driver, 'tr[data-object="0x1017:00"] input.editor').send_keys("5", Keys.ESCAPE)
    shown = wait_for(driver, "the editor closed", lambda v: not v["rows"]["0x1017:00"]["editor"], 2.0)
    assert shown["rows"]["0x1017:00"]["value"] == "200"
    gaps = heartbeat_gaps(emu.bus, 16, 2, 5.0)
    assert all(0.15 <= g <= 0.30 for g in gaps), gaps
    # Read-only and const rows have no editor.
    for obj in ("0x1000:00", "0x1001:00"):
        assert not shown["rows"][obj]["editable"], shown["rows"][obj]
        css(driver, f'tr[data-object="{obj}"] td[data-field="value"]').click()
    assert not any(r["editor"] for r in view(driver)["rows"].values())


def test_cob_ids_show_in_hex_and_are_edited_in_hex_or_decimal(page, start_emulator):
    """COB-IDs (0x1005, 0x1014, 0x1200:01/02, 0x1400:01, 0x1800:01 ...) in hex of 8 digits, their decimal the tooltip;
    the editor starts with the hex shown and takes hex or decimal, and the node's SDO server then answers the value."""
    emu = start_emulator(*NODES)
    driver = open_node(page, emu, 18)
    expand(driver, "0x1200")
    expand(driver, "0x1800")
    cob_ids = {"0x1005:00": "0x00000080", "0x1014:00": "0x00000092", "0x1200:01": "0x00000612",
               "0x1200:02": "0x00000592", "0x1800:01": "0x00000192"}
    for obj in (*cob_ids, "0x1200:03", "0x1800:02"):  # only the rows in sight are read: each brought into it
        css(driver, f'tr[data-object="{obj}"]')
        shown = wait_for(driver, f"{obj} read", lambda v: v["rows"][obj]["value"] != "", 5.0)
    assert {o: shown["rows"][o]["value"] for o in cob_ids} == cob_ids
    assert shown["rows"]["0x1200:03"]["value"] == "0"  # the SDO client's node-ID: no COB-ID, decimal
    assert shown["rows"]["0x1800:02"]["value"] == "254"  # its transmission type: decimal
    title = 'return document.querySelector(`tr[data-object="${arguments[0]}"] td[data-field="value"]`).title'
    assert driver.execute_script(title, "0x1005:00") == "128"
    assert driver.execute_script(title, "0x1800:02") == "0xFE"  # other unsigned values: their hex
    css(driver, 'tr[data-object="0x1005:00"] td[data-field="value"]').click()
    editor = css(driver, 'tr[data-object="0x1005:00"] input.editor')
    assert editor.get_attribute("value") == "0x00000080"  # as shown
    editor.send_keys(Keys.ESCAPE)
    edit(driver, "0x1005:00", "0x00000081")
    wait_for(driver, "0x81 written in hex", lambda v: v["rows"]["0x1005:00"]["value"] == "0x00000081" and
             not v["rows"]["0x1005:00"]["editor"] and v["rows"]["0x1005:00"]["note"] == "", 5.0)
    edit(driver, "0x1005:00", "130")
    wait_for(driver, "130 written in decimal", lambda v: v["rows"]["0x1005:00"]["value"] == "0x00000082" and
             not v["rows"]["0x1005:00"]["editor"] and v["rows"]["0x1005:00"]["note"] == "", 5.0)
    network = canopen.Network(bus=FakeCanBus(emu.bus))
    network.connect()
    try:
        node = network.add_node(18, canopen.ObjectDictionary())
        assert node.sdo.upload(0x1005, 0x00) == (0x82).to_bytes(4, "little")
    finally:
        network.disconnect()


def test_a_value_written_in_the_page_is_read_by_a_python_canopen_master(page, start_emulator):
    emu = start_emulator(*NODES)
    driver = open_node(page, emu, 16)
    expand(driver, "0x2002")
    wait_for(driver, "0x2002:01 read", lambda v: v["rows"].get("0x2002:01", {}).get("value") == "500", 5.0)
    edit(driver, "0x2002:01", "2500")
    wait_for(driver, "2500 written", lambda v: v["rows"]["0x2002:01"]["value"] == "2500" and
             not v["rows"]["0x2002:01"]["editor"], 5.0)
    edit(driver, "0x2002:01", "50")  # below the device's own limit: refused by it
    shown = wait_for(driver, "the device's refusal", lambda v: v["rows"]["0x2002:01"]["note"] not in ("", "writing…"),
                     5.0)
    assert shown["rows"]["0x2002:01"]["note"] == "0x2002:01: value of parameter written too low (0x06090032)"
    drain(emu.bus)
    network = canopen.Network(bus=FakeCanBus(emu.bus))
    network.connect()
    try:
        node = network.add_node(16, canopen.ObjectDictionary())
        assert node.sdo.upload(0x2002, 0x01) == (2500).to_bytes(2, "little")
    finally:
        network.disconnect()


def test_a_device_command_from_the_page_makes_the_node_send_its_emcy(page, start_emulator):
    emu = start_emulator(*NODES)
    driver = open_node(page, emu, 17)
    wait_for(driver, "the SDS's commands", lambda v: "error" in v["device"], 5.0)
    run(driver, '.device-commands form[data-command="error"]')  # CODE left empty: said, not sent
    shown = wait_for(driver, "the missing argument", lambda v: v["forms"]["error"]["answer"] != "", 2.0)
    assert shown["forms"]["error"] == {"answer": "CODE is needed", "refused": True, "state": None}
    run(driver, '.device-commands form[data-command="error"]', "99")
    shown = wait_for(driver, "the refusal", lambda v: v["forms"]["error"]["answer"] not in ("CODE is needed", "…"),
                     5.0)
    assert shown["forms"]["error"] == {"answer": "error 99 is not in this device's table (see `faults`)",
                                       "refused": True, "state": None}
    drain(emu.bus)
    run(driver, '.device-commands form[data-command="error"]', "1")
    _, _, frame = emu.bus.expect(lambda i, d: i == 0x091, 5.0, "the EMCY of node 17")
    assert frame == bytes([0x20, 0x23, 0x03, 0x01, 0x01, 0x00, 0x00, 0x00])  # 0x2320, register 0x03, error 1
    shown = wait_for(driver, "the answer and the EMCY in the summary",
                     lambda v: v["summary"]["emcy"] == "0x2320 current, device output side, reg 0x03 info 0101000000", 5.0)
    assert shown["forms"]["error"] == {"answer": "node 17: sds: error 1 raised: HV short circuit / arcing",
                                       "refused": False, "state": None}
    assert shown["summary"]["error-register"] == "0x03"


def test_power_cycle_from_the_page_makes_the_node_send_its_boot_up(page, start_emulator):
    emu = start_emulator(*NODES)
    driver = open_node(page, emu, 16)
    drain(emu.bus)
    run(driver, 'form[data-command="power-cycle"]')
    t, _, frame = emu.bus.expect(lambda i, d: i == 0x710 and d == b"\x00", 5.0, "the boot-up of node 16")
    shown = wait_for(driver, "the answer", lambda v: v["forms"]["power-cycle"]["answer"] not in ("", "…"), 5.0)
    assert shown["forms"]["power-cycle"] == {"answer": "node 16: power cycled", "refused": False, "state": None}
    # only node 16 restarted
    others = [i for _, i, d in drain(emu.bus) if i in (0x711, 0x712) and d == b"\x00"]
    assert others == []


def test_a_protocol_fault_raised_from_the_page_stops_the_heartbeats_until_cleared(page, start_emulator):
    emu = start_emulator(*NODES)
    driver = open_node(page, emu, 18)
    fault = 'form[data-fault="heartbeat-stop"]'
    run(driver, 'form[data-fault="sdo-delay"]')  # its MS left empty
    shown = wait_for(driver, "the missing argument", lambda v: v["forms"]["fault sdo-delay"]["answer"] != "", 2.0)
    assert shown["forms"]["fault sdo-delay"] == {"answer": "MS is needed", "refused": True, "state": ""}
    run(driver, fault)
    shown = wait_for(driver, "the fault in force", lambda v: v["forms"]["fault heartbeat-stop"]["state"] == "in force",
                     5.0)
    in_force = time.monotonic()
    assert shown["forms"]["fault heartbeat-stop"]["answer"] == \
        "node 18: fault heartbeat-stop: no heartbeat (nor node-guarding answer)"
    assert shown["summary"]["faults"] == "heartbeat-stop"
    overdue = "return document.querySelector('#view-node dd[data-field=\"heartbeat-age\"]').classList.contains('overdue')"
    shown = wait_for(driver, "the heartbeat marked overdue in the summary",
                     lambda v: v["summary"]["heartbeat-age"].endswith(" s ago (overdue)"), 5.0)
    assert driver.execute_script(overdue) is True
    others = [s["state"] for k, s in shown["forms"].items() if k.startswith("fault ") and k != "fault heartbeat-stop"]
    assert others and all(state == "" for state in others), others  # every other served kind: not in force
    # the overview has it too
    css(driver, "#tab-network").click()
    WebDriverWait(driver, 2.0, poll_frequency=0.05).until(lambda d: d.execute_script(
        "return document.querySelector('#nodes tr[data-key=\"fakecan0/18\"] td[data-field=\"faults\"]').textContent")
        == "heartbeat-stop")
    time.sleep(2.0)  # four periods of its 500 ms heartbeat
    frames = drain(emu.bus)
    assert [t for t, i, _ in frames if i == 0x712 and t > in_force] == []
    assert [i for t, i, _ in frames if i == 0x710 and t > in_force], "node 16's heartbeat goes on"
    css(driver, "#tab-node").click()
    css(driver, f"{fault} button.clear").click()
    wait_for(driver, "the fault cleared", lambda v: v["forms"]["fault heartbeat-stop"]["state"] == "" and
             v["summary"]["faults"] == "", 5.0)
    wait_for(driver, "the heartbeat no longer overdue", lambda v: v["summary"]["heartbeat-age"].endswith(" s ago") and
             not v["summary"]["heartbeat-age"].endswith("(overdue)"), 5.0)
    assert driver.execute_script(overdue) is False
    gaps = heartbeat_gaps(emu.bus, 18, 3, 5.0)
    assert all(0.4 <= g <= 0.65 for g in gaps), gaps


BOOLEANS_EDS = """[FileInfo]
FileName=booleans.eds
FileVersion=1
EDSVersion=4.0
[DeviceInfo]
VendorName=Test Vendor
VendorNumber=0x00000ABC
ProductName=Valve
ProductNumber=0x00000003
RevisionNumber=0x00010000
BaudRate_125=1
Granularity=8
NrOfRXPDO=0
NrOfTXPDO=0
LSS_Supported=0
[MandatoryObjects]
SupportedObjects=3
1=0x1000
2=0x1001
3=0x1018
[1000]
ParameterName=Device type
ObjectType=0x7
DataType=0x0007
AccessType=ro
DefaultValue=0
[1001]
ParameterName=Error register
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=0
[1018]
ParameterName=Identity object
ObjectType=0x9
SubNumber=2
[1018sub0]
ParameterName=Highest sub-index supported
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=1
[1018sub1]
ParameterName=Vendor-ID
ObjectType=0x7
DataType=0x0007
AccessType=ro
DefaultValue=0x00000ABC
[ManufacturerObjects]
SupportedObjects=4
1=0x2000
2=0x2001
3=0x2002
4=0x2003
[2000]
ParameterName=Valve Open
ObjectType=0x7
DataType=0x0001
AccessType=rw
DefaultValue=1
[2001]
ParameterName=Reset Request
ObjectType=0x7
DataType=0x0001
AccessType=wo
DefaultValue=0
[2002]
ParameterName=Valve Name
ObjectType=0x7
DataType=0x0009
AccessType=ro
DefaultValue=V1
[2003]
ParameterName=Switch Count
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=3
"""

PLOT_BUTTONS = """
return [...document.querySelectorAll('#view-node table.dictionary tr.entry')]
  .filter((tr) => tr.querySelector('button.plot') !== null && getComputedStyle(tr.querySelector('button.plot')).display
          !== 'none')
  .map((tr) => tr.dataset.object);
"""


def test_a_boolean_row_has_a_plot_button_as_the_plots_picker_offers_it(page, start_emulator, tmp_path):
    """The node view's plot buttons and the plots view's picker offer the same objects (objects.js plottableRow):
    a BOOLEAN that can be read too (plotted as 0/1), not a write-only one nor a string. The button plots it."""
    from test_plots import plots, show_plots, wait_plots
    eds = tmp_path / "booleans.eds"
    eds.write_text(BOOLEANS_EDS)
    emu = start_emulator(f"{eds}:5")
    driver = open_node(page, emu, 5)
    shown = wait_for(driver, "the valve's objects", lambda v: "0x2003:00" in v["rows"], 5.0)
    assert {o: (r["type"], r["access"]) for o, r in shown["rows"].items() if o.startswith("0x20")} == {
        "0x2000:00": ("BOOLEAN", "rw"), "0x2001:00": ("BOOLEAN", "wo"), "0x2002:00": ("VISIBLE_STRING", "ro"),
        "0x2003:00": ("UNSIGNED8", "ro")}
    expand(driver, "0x1018")  # every row shown: the whole dictionary
    wait_for(driver, "0x1018 expanded", lambda v: "0x1018:01" in v["rows"], 5.0)
    buttons = driver.execute_script(PLOT_BUTTONS)
    assert buttons == ["0x1000:00", "0x1001:00", "0x1018:00", "0x1018:01", "0x2000:00", "0x2003:00"]
    # the plots view's picker offers exactly these
    show_plots(driver)
    Select(driver.find_element(By.CSS_SELECTOR, "#view-plots select[name=node]")).select_by_value("fakecan0/5")
    objects = driver.find_element(By.CSS_SELECTOR, "#view-plots select[name=object]")
    WebDriverWait(driver, 5.0, poll_frequency=0.05).until(lambda d: objects.is_enabled())
    assert [o.get_attribute("value") for o in Select(objects).options if o.get_attribute("value")] == buttons
    # the BOOLEAN's button plots it: its series in the plots view, sampled
    css(driver, "#tab-node").click()
    css(driver, 'tr[data-object="0x2000:00"] button.plot').click()
    show_plots(driver)
    view = wait_plots(driver, "the BOOLEAN plotted and sampled", lambda v: any(
        "0x2000:00 Valve Open" in c["legend"] and c["points"] >= 2 for c in v["charts"].values()), 5.0)
    assert "fakecan0/5 0x2000:00" in view["series"]
    assert plots(driver)["problem"] is False


def test_a_device_of_12000_entries_is_shown_whole(page, start_emulator, tmp_path):
    """Its `objects` answer is some 2.5 MB: more than a web session may hold (1 MiB), so before issue 32 the session
    was dropped and the page never showed the dictionary. The answer now comes over several exchanges, and the page
    takes its line once it is whole."""
    from test_control_native import big_eds
    eds = tmp_path / "big.eds"
    big_eds(eds, 12000)
    emu = start_emulator(f"{eds}:5")
    # On a loaded machine the page can spend over 10 s on the rows of a piece: its session is then removed and it
    # opens another and asks again (test_overview's offline test covers that path); the browser logs the 404 of the
    # exchange that found the session gone. What counts here is the dictionary shown whole.
    page.expected_errors.append(rf"^http://127\.0\.0\.1:{emu.port}/api/session/[0-9a-f]{{32}} - Failed to load "
                                r"resource: the server responded with a status of 404 \(Not Found\)$")
    driver = open_node(page, emu, 5)
    shown = wait_for(driver, "the last object of node 5's dictionary", lambda v: "0x4EDF:00" in v["rows"]
                     or "0x4EDF" in v["groups"], 60.0)
    assert "0x2000:00" in shown["rows"] or "0x2000" in shown["groups"]
    assert "dropped" not in emu.log()
