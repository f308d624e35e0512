"""The plots view of the web view in a browser (docs/web.md "Plots"): the default series (the objects the TPDOs of
the first or the picked node map), their samples growing, the EMCY and NMT marks on the time axis, the picker and
the remove buttons, and 127 nodes. Judged by the page: the charts' headings and uPlot's legends, the sample count
and the marks' labels each chart element carries (data-points, data-marks), and the pixels of its canvas."""

import time

from selenium.webdriver.support.ui import Select, WebDriverWait

from browser import wait_until
from test_overview import command, loaded, wait_for

# The objects the TPDOs of a PRO IONIZER and of an SDS map (od/*.eds 0x1A00..: what their mapping parameters hold),
# as the legends name them, by chart: a chart per node and unit, in mapping order.
PRO_IONIZER_16 = {
    "node 16@fakecan0 · no unit": ["0x6000:01 Read System Status", "0x6000:03 Read Status Discharge 1",
                                   "0x6000:04 Read Status Discharge 2", "0x6000:05 Read Status Discharge 3",
                                   "0x6000:06 Read Status Discharge 4"],
    "node 16@fakecan0 · %": ["0x6000:02 Read Discharging Capacity"],
    "node 16@fakecan0 · V": ["0x6401:01 Read Voltage Discharging", "0x6401:05 Read E-Field Sensor 1",
                             "0x6401:06 Read Ripple E-Field Sensor 1", "0x6401:07 Read E-Field Sensor 2",
                             "0x6401:08 Read Ripple E-Field Sensor 2"],
    "node 16@fakecan0 · µA": ["0x6401:02 Read AC Current Discharging", "0x6401:03 DC Current Discharging"],
    "node 16@fakecan0 · 0.1 W": ["0x6401:04 Read Power Discharging"],
}
SDS_17 = {
    "node 17@fakecan0 · no unit": ["0x6000:01 Read System Status"],
    "node 17@fakecan0 · % (50 = balanced)": ["0x6000:02 Read High Voltage Balance"],
    "node 17@fakecan0 · %": ["0x6000:03 Read Power Capacity", "0x6000:04 Read Pollution"],
    "node 17@fakecan0 · cm": ["0x6000:05 Read Working Distance"],
    "node 17@fakecan0 · V": ["0x6401:01 Read Effective High Voltage"],
    "node 17@fakecan0 · µA": ["0x6401:02 Read Effective Current", "0x6401:03 Read DC Discharging Current"],
}
SERIES_COLOUR = (0x1A, 0x7F, 0x37)  # web/plotchart.js: the first series of a chart
EMCY_COLOUR = (0xCF, 0x22, 0x2E)  # web/plotchart.js MARK_COLORS.emcy

# The plots view at one moment: the status line, the series list, and each chart (by its heading) with its legend's
# series (uPlot's, the time column left out), data-points and data-marks; the headings in the page's order.
PLOTS = """
const charts = {}, order = [];
for (const plot of document.querySelectorAll("#view-plots .plot")) {
  charts[plot.querySelector("h3").textContent] = {
    legend: [...plot.querySelectorAll(".u-legend .u-series")].slice(1).map((s) => s.querySelector(".u-label").textContent),
    points: Number(plot.dataset.points ?? 0),
    marks: plot.dataset.marks ?? "",
    node: plot.dataset.node,
  };
  order.push(plot.querySelector("h3").textContent);
}
const status = document.querySelector("#view-plots .plots-status");
return {charts, order, status: status.textContent, problem: status.classList.contains("problem"),
        series: [...document.querySelectorAll("#view-plots .plots-series li")].map((li) => li.dataset.node + " " + li.dataset.object)};
"""

# The canvas of the chart headed arguments[0]: how many of its pixels are near the colour arguments[1] (each channel
# within arguments[2]), and the most pixels of exactly that colour in one column (a vertical line).
PIXELS = """
const [title, [r, g, b], tolerance] = arguments;
const plot = [...document.querySelectorAll("#view-plots .plot")].find((p) => p.querySelector("h3").textContent === title);
const canvas = plot.querySelector("canvas");
const {data, width, height} = canvas.getContext("2d").getImageData(0, 0, canvas.width, canvas.height);
let near = 0;
const columns = new Array(width).fill(0);
for (let i = 0; i < data.length; i += 4) {
  if (data[i + 3] > 200 && Math.abs(data[i] - r) <= tolerance && Math.abs(data[i + 1] - g) <= tolerance &&
      Math.abs(data[i + 2] - b) <= tolerance) {
    near++;
  }
  if (data[i] === r && data[i + 1] === g && data[i + 2] === b && data[i + 3] === 255) {
    columns[(i / 4) % width]++;
  }
}
return {near, column: Math.max(...columns), height};
"""


def plots(driver):
    return driver.execute_script(PLOTS)


def wait_plots(driver, what, check, timeout):
    """The first view of the plots for which check() holds, polled every 50 ms; fails with the last one seen."""
    return wait_until(driver, what, plots, check, timeout, lambda last: f"the plots view showed {last}")


def legends(view):
    return {title: chart["legend"] for title, chart in view["charts"].items()}


def show_plots(driver):
    driver.find_element("id", "tab-plots").click()
    assert driver.find_element("id", "view-plots").is_displayed()


def test_the_first_nodes_tpdo_objects_are_plotted_and_gain_points(page, start_emulator):
    emu = start_emulator("pro-ionizer:16", "sds:17")
    driver = loaded(page, emu, 2)
    show_plots(driver)
    view = wait_plots(driver, "the charts of node 16's TPDO objects, sampled",
                      lambda v: legends(v) == PRO_IONIZER_16 and all(c["points"] >= 2 for c in v["charts"].values()),
                      10.0)
    assert view["order"] == list(PRO_IONIZER_16)  # in mapping order
    assert view["status"] == ("the objects the TPDOs of node 16@fakecan0 map (14): they follow the node picked in the "
                              "network view until a series is added or removed here")
    assert view["problem"] is False
    assert len(view["series"]) == 14 and view["series"][0] == "fakecan0/16 0x6000:01"
    # A node's charts share its samples; they go on growing.
    first = view["charts"]["node 16@fakecan0 · V"]["points"]
    assert {c["points"] for c in view["charts"].values()} <= {first, first + 1}
    wait_plots(driver, "4 more samples", lambda v: v["charts"]["node 16@fakecan0 · V"]["points"] >= first + 4, 10.0)
    # The line of the series (0x6000:02, the discharging capacity, alone in its chart) is on the canvas, over a 30 s
    # span a second's samples some 38 pixels long; no mark is.
    Select(driver.find_element("css selector", "#view-plots select[name=span]")).select_by_visible_text("30 s")
    pixels = WebDriverWait(driver, 3.0, poll_frequency=0.1).until(
        lambda d: (p := d.execute_script(PIXELS, "node 16@fakecan0 · %", SERIES_COLOUR, 40))["near"] >= 30 and p)
    assert pixels["near"] >= 30, pixels
    assert driver.execute_script(PIXELS, "node 16@fakecan0 · no unit", EMCY_COLOUR, 0)["column"] == 0


def test_the_node_picked_in_the_network_view_becomes_the_plot(page, start_emulator):
    emu = start_emulator("pro-ionizer:16", "sds:17")
    driver = loaded(page, emu, 2)
    show_plots(driver)
    wait_plots(driver, "node 16's charts", lambda v: legends(v) == PRO_IONIZER_16, 10.0)
    driver.find_element("id", "tab-network").click()
    driver.find_element("css selector", '#nodes tr[data-key="fakecan0/17"]').click()
    show_plots(driver)
    view = wait_plots(driver, "node 17's charts, sampled",
                      lambda v: legends(v) == SDS_17 and all(c["points"] >= 2 for c in v["charts"].values()), 10.0)
    assert view["status"].startswith("the objects the TPDOs of node 17@fakecan0 map (8)")


def test_an_emcy_and_an_nmt_change_are_marked_on_the_time_axis(page, start_emulator):
    emu = start_emulator("pro-ionizer:16", "sds:17")
    driver = loaded(page, emu, 2)
    show_plots(driver)
    wait_plots(driver, "node 16's charts, sampled",
               lambda v: legends(v) == PRO_IONIZER_16 and all(c["points"] >= 2 for c in v["charts"].values()), 10.0)
    command(emu, "emcy 17 0x3210 0x05")  # another node's: not on node 16's charts
    emu.bus.expect(lambda i, d: i == 0x091, 5.0, "the EMCY of node 17")
    command(emu, "emcy 16 0x5000 0x01 0xA1 0xB2 0xC3 0xD4 0xE5")
    emu.bus.expect(lambda i, d: i == 0x090, 5.0, "the EMCY of node 16")
    view = wait_plots(driver, "the EMCY's mark on node 16's charts",
                      lambda v: all(c["marks"] == "EMCY 0x5000" for c in v["charts"].values()), 5.0)
    pixels = driver.execute_script(PIXELS, "node 16@fakecan0 · V", EMCY_COLOUR, 0)
    assert pixels["column"] >= pixels["height"] * 0.4, pixels  # a red line across the plot
    emu.bus.send(0x000, bytes([0x01, 0x00]))  # NMT start, all nodes
    view = wait_plots(driver, "the NMT change's mark",
                      lambda v: all(c["marks"] == "EMCY 0x5000, OPERATIONAL" for c in v["charts"].values()), 5.0)
    assert len(view["charts"]) == 5


def test_the_picker_adds_any_numeric_object_and_remove_takes_it_away(page, start_emulator):
    emu = start_emulator("pro-ionizer:16", "sds:17")
    driver = loaded(page, emu, 2)
    show_plots(driver)
    wait_plots(driver, "node 16's charts", lambda v: legends(v) == PRO_IONIZER_16, 10.0)
    driver.find_element("css selector", "#view-plots .plots-picker button[type=submit]").click()
    view = wait_plots(driver, "the refusal", lambda v: v["problem"], 2.0)
    assert view["status"] == "pick a node and one of its objects first"
    nodes = Select(driver.find_element("css selector", "#view-plots select[name=node]"))
    assert [o.text for o in nodes.options] == ["node", "16@fakecan0 pro-ionizer (full)", "17@fakecan0 sds (N)"]
    nodes.select_by_value("fakecan0/17")
    objects = driver.find_element("css selector", "#view-plots select[name=object]")
    WebDriverWait(driver, 5.0, poll_frequency=0.05).until(lambda d: objects.is_enabled())
    offered = [o.get_attribute("value") for o in Select(objects).options]
    assert "0x6401:01" in offered and "0x1017:00" in offered
    assert "0x1008:00" not in offered  # a VISIBLE_STRING: not a number
    Select(objects).select_by_value("0x6401:01")
    driver.find_element("css selector", "#view-plots .plots-picker button[type=submit]").click()
    view = wait_plots(driver, "node 17's object plotted beside node 16's, sampled",
                      lambda v: v["charts"].get("node 17@fakecan0 · V", {}).get("points", 0) >= 2, 5.0)
    assert view["charts"]["node 17@fakecan0 · V"]["legend"] == ["0x6401:01 Read Effective High Voltage"]
    assert legends(view) == {**PRO_IONIZER_16, "node 17@fakecan0 · V": ["0x6401:01 Read Effective High Voltage"]}
    assert view["status"] == "15 series" and view["problem"] is False
    # Its own plot now: picking another node in the network view leaves it as it is.
    driver.find_element("id", "tab-network").click()
    driver.find_element("css selector", '#nodes tr[data-key="fakecan0/17"]').click()
    show_plots(driver)
    assert legends(plots(driver))["node 17@fakecan0 · V"] == ["0x6401:01 Read Effective High Voltage"]
    assert len(plots(driver)["series"]) == 15
    # Removed: node 17's chart goes, and one of node 16's series. The second button is found before the first
    # removal is drawn: the list keeps the items of the series that stay, so it is still there to be clicked.
    second = driver.find_element("css selector",
                                 '#view-plots .plots-series li[data-node="fakecan0/16"][data-object="0x6401:05"] button')
    driver.find_element("css selector",
                        '#view-plots .plots-series li[data-node="fakecan0/17"][data-object="0x6401:01"] button').click()
    wait_plots(driver, "node 17's series gone from the list",
               lambda v: not any(s.startswith("fakecan0/17 ") for s in v["series"]), 2.0)
    second.click()
    expected = {**PRO_IONIZER_16, "node 16@fakecan0 · V": [s for s in PRO_IONIZER_16["node 16@fakecan0 · V"]
                                                           if not s.startswith("0x6401:05")]}
    view = wait_plots(driver, "two series removed", lambda v: legends(v) == expected, 2.0)
    assert view["status"] == "13 series"


def test_127_nodes_the_plots_keep_up(page, start_emulator):
    """sds:1 ... sds:127, the plots view shown: node 1's charts gain samples and show the NMT start as a mark, while
    the overview (drawn in the same frames) shows all 127 OPERATIONAL within 2 s."""
    emu = start_emulator(*[f"sds:{n}" for n in range(1, 128)])
    driver = loaded(page, emu, 127)
    show_plots(driver)
    view = wait_plots(driver, "node 1's charts, sampled",
                      lambda v: len(v["charts"]) == 6 and all(c["points"] >= 2 for c in v["charts"].values()), 10.0)
    assert {c["node"] for c in view["charts"].values()} == {"fakecan0/1"}
    emu.bus.send(0x000, bytes([0x01, 0x00]))
    wait_plots(driver, "the NMT start marked", lambda v: all(c["marks"] == "OPERATIONAL" for c in v["charts"].values()),
               2.0)
    driver.find_element("id", "tab-network").click()
    wait_for(driver, "OPERATIONAL for all 127", lambda s: {r["state"] for r in s["rows"].values()} == {"OPERATIONAL"},
             2.0)
    first = plots(driver)  # hidden: not drawn, but sampled
    time.sleep(1.0)
    show_plots(driver)
    view = wait_plots(driver, "samples taken while the view was hidden",
                      lambda v: v["charts"]["node 1@fakecan0 · V"]["points"]
                      >= first["charts"]["node 1@fakecan0 · V"]["points"] + 2, 2.0)
