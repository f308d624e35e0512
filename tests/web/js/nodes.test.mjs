// web/nodes.js: the overview's model, from show answers and events, and the emulator's clock behind the ages.
import {test} from "node:test";
import assert from "node:assert/strict";

import {COLUMNS, EmuClock, HEARTBEAT_OVERDUE, NodeTable, busLabel, heartbeatOverdue, nodeCount, withBusHeadings}
  from "../../../web/nodes.js";

// As show answers them (docs/control-protocol.md), the three devices of the README's example.
function shown(node, device, variant, extra = {}) {
  return {
    node, device, variant, started_as: node, state: "PRE-OPERATIONAL", bus: "vcan0", error_register: 0, errors: [],
    device_type: 0x191, heartbeat_ms: 1000, last_heartbeat_us: 1_000_000, faults: [], last_emcy: null,
    tx_frames: 1, rx_frames: 0, tx_dropped: 0, ...extra,
  };
}

const SHOW = {
  id: 1, ok: true, time_us: 1_500_000,
  nodes: [
    shown(18, "buerkert", null, {device_type: 0, heartbeat_ms: 500}),
    shown(16, "pro-ionizer", "full", {device_type: 0xF0191, last_heartbeat_us: null}),
    shown(17, "sds", "N", {heartbeat_ms: 5000, faults: ["sdo-delay"], error_register: 5,
      last_emcy: {code: 0x3210, register: 5, info: "0000000000", time_us: 200_000}}),
  ],
};

function event(kind, node, timeUs, fields = {}) {
  return {event: kind, time_us: timeUs, bus: "vcan0", node, device: "sds", text: "", ...fields};
}

test("the clock runs from the last show on the page's clock, and an event's later time moves it on", () => {
  const clock = new EmuClock();
  assert.equal(clock.now(5), null);
  clock.set(1_500_000, 10_000); // the show answer's time_us, and performance.now() when it came
  assert.equal(clock.now(10_000), 1_500_000);
  assert.equal(clock.now(10_250), 1_750_000);
  assert.equal(clock.now(9_000), 1_500_000); // never before the anchor
  clock.advance(1_600_000, 10_250); // an earlier event: no change
  assert.equal(clock.now(10_250), 1_750_000);
  clock.advance(2_000_000, 10_250); // later than the estimate: the estimate lagged
  assert.equal(clock.now(10_350), 2_100_000);
});

test("rows: every column, ordered by node-ID, ages against the clock", () => {
  const table = new NodeTable();
  table.show(SHOW, 0);
  const rows = table.rows(500); // 0.5 s after the answer: the clock is at 2.0 s
  assert.deepEqual(rows.map((r) => r.key), ["vcan0/16", "vcan0/17", "vcan0/18"]);
  assert.deepEqual(rows.map((r) => Object.keys(r.cells)), rows.map(() => COLUMNS.map((c) => c.field)));
  assert.deepEqual(rows[0].cells, {
    "node": "16", "bus": "vcan0", "device": "pro-ionizer (full)", "state": "PRE-OPERATIONAL",
    "device-type": "0x000F0191", "heartbeat": "1000 ms", "heartbeat-age": "never", "error-register": "0x00",
    "faults": "", "emcy": "", "emcy-age": "",
  });
  assert.deepEqual(rows[1].cells, {
    "node": "17", "bus": "vcan0", "device": "sds (N)", "state": "PRE-OPERATIONAL", "device-type": "0x00000191",
    "heartbeat": "5000 ms", "heartbeat-age": "1.0 s ago", "error-register": "0x05", "faults": "sdo-delay",
    "emcy": "0x3210 voltage inside the device, reg 0x05 info 0000000000", "emcy-age": "1.8 s ago",
  });
  assert.equal(rows[2].cells["device"], "buerkert");
  assert.equal(rows[2].cells["device-type"], "0x00000000");
  assert.equal(rows[2].cells["heartbeat"], "500 ms");
  assert.equal(table.rows(3_000)[1].cells["heartbeat-age"], "3.5 s ago"); // it grows as time goes on
});

test("heartbeatOverdue: more than 1.5 periods old at the last show, a period of 0 or no heartbeat yet never", () => {
  assert.equal(HEARTBEAT_OVERDUE, 1.5);
  const n = (heartbeat_ms, last_heartbeat_us, shown_us = 10_000_000) => ({heartbeat_ms, last_heartbeat_us, shown_us});
  assert.equal(heartbeatOverdue(n(500, 9_250_000)), false); // 750 ms: 1.5 periods, not more
  assert.equal(heartbeatOverdue(n(500, 9_249_999)), true);
  assert.equal(heartbeatOverdue(n(1000, 8_600_000)), false);
  assert.equal(heartbeatOverdue(n(1000, 8_400_000)), true);
  assert.equal(heartbeatOverdue(n(0, 1_000_000)), false); // 0x1017 = 0: it sends none
  assert.equal(heartbeatOverdue(n(500, null)), false); // never heard: not watched yet
  assert.equal(heartbeatOverdue(n(500, 10_400_000)), false); // a boot-up after the show

  const table = new NodeTable();
  const answer = (timeUs, lastUs) => ({time_us: timeUs, nodes: [
    shown(18, "buerkert", null, {heartbeat_ms: 500, last_heartbeat_us: lastUs}),
    shown(16, "pro-ionizer", "full", {heartbeat_ms: 0, last_heartbeat_us: 1_000_000}),
    shown(17, "sds", "N", {heartbeat_ms: 1000, last_heartbeat_us: null})]});
  table.show(answer(2_000_000, 1_600_000), 0); // 0.4 s old at the show
  const seen = (ms) => table.rows(ms).map((r) => [r.key, r.overdue, r.cells["heartbeat-age"]]);
  // Between two shows the age grows on the page's clock, but the mark waits for a show: a running heartbeat is
  // only known from one, so 1.4 s counted here is no stopped heartbeat yet.
  assert.deepEqual(seen(1_000), [
    ["vcan0/16", false, "2.0 s ago"], ["vcan0/17", false, "never"], ["vcan0/18", false, "1.4 s ago"]]);
  table.show(answer(3_000_000, 1_600_000), 1_000); // no heartbeat of 18 since: 1.4 s old at this show
  assert.deepEqual(seen(1_250)[2], ["vcan0/18", true, "1.6 s ago (overdue)"]);
  table.event(event("boot-up", 18, 3_100_000), 1_300); // it is back
  assert.deepEqual(seen(1_300)[2], ["vcan0/18", false, "0.2 s ago"]);
  table.show(answer(4_000_000, 3_600_000), 2_000);
  assert.deepEqual(seen(2_000)[2], ["vcan0/18", false, "0.4 s ago"]);
});

test("nodes of several buses: by bus in the emulator's order, then node-ID; an ID on two buses is two rows", () => {
  const table = new NodeTable();
  table.show({time_us: 0, nodes: [shown(20, "sds", "N", {bus: "vcan1"}), shown(5, "sds", "N"),
    shown(3, "sds", "N", {bus: "vcan1"}), shown(20, "sds", "N")]}, 0);
  assert.deepEqual(table.rows(0).map((r) => r.key), ["vcan1/3", "vcan1/20", "vcan0/5", "vcan0/20"]);
});

test("events change their node's row until the next show says otherwise", () => {
  const table = new NodeTable();
  table.show(SHOW, 0);
  table.event(event("nmt", 17, 1_600_000, {from: "PRE-OPERATIONAL", to: "OPERATIONAL"}), 100);
  table.event(event("emcy", 18, 1_700_000, {code: 0x5000, register: 1, info: "A1B2C3D4E5"}), 200);
  table.event(event("fault", 16, 1_700_000, {fault: "heartbeat-stop", action: "injected"}), 200);
  table.event(event("fault", 17, 1_700_000, {fault: "sdo-delay", action: "cleared"}), 200);
  table.event(event("fault", 16, 1_700_000, {fault: "tpdo-freeze", action: "injected"}), 200);
  table.event(event("nmt", 99, 1_700_000, {from: "PRE-OPERATIONAL", to: "STOPPED"}), 200); // not shown yet: ignored
  let rows = table.rows(200);
  assert.equal(rows.length, 3);
  assert.deepEqual(rows.map((r) => r.state), ["PRE-OPERATIONAL", "OPERATIONAL", "PRE-OPERATIONAL"]);
  assert.equal(rows[1].cells["state"], "OPERATIONAL");
  assert.equal(rows[0].cells["faults"], "heartbeat-stop, tpdo-freeze");
  assert.equal(rows[1].cells["faults"], "");
  assert.equal(rows[2].cells["emcy"], "0x5000 device hardware, reg 0x01 info A1B2C3D4E5");
  assert.equal(rows[2].cells["error-register"], "0x01");
  assert.equal(rows[2].cells["emcy-age"], "0.0 s ago"); // the clock moved to the event's time
  table.event(event("fault", 16, 1_800_000, {fault: "heartbeat-stop", action: "ended"}), 300);
  table.event(event("boot-up", 17, 1_900_000), 400);
  rows = table.rows(400);
  assert.equal(rows[0].cells["faults"], "tpdo-freeze");
  assert.equal(rows[1].cells["state"], "PRE-OPERATIONAL");
  assert.equal(rows[1].cells["heartbeat-age"], "0.0 s ago");
  table.show({time_us: 3_000_000, nodes: [shown(17, "sds", "N")]}, 1_000); // node 16 and 18 gone: their rows too
  rows = table.rows(1_000);
  // its 1000 ms heartbeat 2.0 s old at this show: overdue (heartbeatOverdue)
  assert.deepEqual(rows.map((r) => [r.key, r.cells["faults"], r.cells["heartbeat-age"], r.overdue]),
    [["vcan0/17", "", "2.0 s ago (overdue)", true]]);
});

test("a show's lists are the table's own: changing them later changes no row", () => {
  const answer = structuredClone(SHOW);
  const table = new NodeTable();
  table.show(answer, 0);
  table.event(event("fault", 17, 1_600_000, {fault: "reboot", action: "injected"}), 0);
  assert.deepEqual(answer.nodes[2].faults, ["sdo-delay"]);
});

test("nodes heard on the bus get rows of their own, in node-ID order among the emulated ones", () => {
  const table = new NodeTable();
  table.show({...SHOW, heard: [
    {node: 5, bus: "vcan0", state: "OPERATIONAL", boot_up: false, last_heartbeat_us: 1_200_000},
    {node: 20, bus: "vcan0", state: "PRE-OPERATIONAL", boot_up: true, last_heartbeat_us: 1_400_000},
  ]}, 0);
  const rows = table.rows(0);
  assert.deepEqual(rows.map((r) => r.key), ["vcan0/5", "vcan0/16", "vcan0/17", "vcan0/18", "vcan0/20"]);
  const blank = Object.fromEntries(COLUMNS.map(({field}) => [field, ""]));
  assert.deepEqual(rows[0], {key: "vcan0/5", state: "OPERATIONAL", heard: true, overdue: false, cells: {
    ...blank, "node": "5", "bus": "vcan0", "device": "heard on the bus", "state": "OPERATIONAL",
    "heartbeat-age": "0.3 s ago"}});
  assert.equal(rows[4].cells.device, "heard on the bus (boot-up)");
  assert.equal(rows[1].heard, false);
  assert.equal(table.isHeard("vcan0/5"), true);
  assert.equal(table.isHeard("vcan0/16"), false);
  assert.equal(table.isHeard("vcan0/99"), false);
  table.show(SHOW, 0); // no longer heard (a later show without it): gone
  assert.equal(table.rows(0).length, 3);
});

test("several buses: a heading before each bus's rows, with its kind and counts; one bus: no heading", () => {
  const table = new NodeTable();
  table.show({...SHOW, nodes: [...SHOW.nodes, shown(16, "sds", "N", {bus: "vcan1"})],
    heard: [{node: 5, bus: "vcan1", state: "OPERATIONAL", boot_up: false, last_heartbeat_us: 1_200_000}]}, 0);
  const items = withBusHeadings(table.rows(0));
  assert.deepEqual(items.map((r) => r.heading ?? r.key), [
    "vcan0: 3 nodes", "vcan0/16", "vcan0/17", "vcan0/18",
    "vcan1: 1 node, 1 heard on the bus", "vcan1/5", "vcan1/16"]);
  assert.equal(items[0].key, "bus:vcan0");
  const one = new NodeTable();
  one.show(SHOW, 0);
  assert.deepEqual(withBusHeadings(one.rows(0)), one.rows(0));

  // with the kinds show gives (bus_kind): each heading names its bus's kind
  const kinds = new NodeTable();
  kinds.show({...SHOW, nodes: [shown(16, "sds", "N", {bus_kind: "socketcan"}),
    shown(16, "sds", "N", {bus: "plant", bus_kind: "virtual"})]}, 0);
  assert.deepEqual(withBusHeadings(kinds.rows(0), kinds.buses()).filter((r) => r.heading).map((r) => r.heading),
    ["vcan0 (socketcan): 1 node", "plant (virtual): 1 node"]);
});

test("each bus by its name and its kind: buses() in show's order, the label, the status line's count", () => {
  const table = new NodeTable();
  const udp = "udp_multicast:239.74.163.2:43113";
  table.show({...SHOW, nodes: [shown(16, "sds", "N", {bus: "plant", bus_kind: "virtual"}),
    shown(17, "sds", "N", {bus: udp, bus_kind: "udp_multicast"})],
  heard: [{node: 5, bus: "vcan1", bus_kind: "socketcan", state: "OPERATIONAL", boot_up: false,
    last_heartbeat_us: 1_200_000}]}, 0);
  // a bus with heard nodes only has its kind from them
  assert.deepEqual(table.buses(), [{name: "plant", kind: "virtual"}, {name: udp, kind: "udp_multicast"},
    {name: "vcan1", kind: "socketcan"}]);
  assert.equal(busLabel("vcan0", "socketcan"), "vcan0 (socketcan)");
  assert.equal(busLabel(udp, "udp_multicast"), udp); // its name says it already
  assert.equal(busLabel("vcan0", null), "vcan0"); // an emulator without bus_kind
  assert.equal(nodeCount(table.rows(0), table.buses()),
    `plant (virtual), ${udp}, vcan1 (socketcan): 2 nodes, 1 heard on the bus`);
  assert.equal(nodeCount(table.rows(0)), "2 nodes, 1 heard on the bus");
  const old = new NodeTable(); // an emulator before bus_kind: the names alone
  old.show(SHOW, 0);
  assert.deepEqual(old.buses(), [{name: "vcan0", kind: null}]);
  assert.equal(nodeCount(old.rows(0), old.buses()), "vcan0: 3 nodes");
});
