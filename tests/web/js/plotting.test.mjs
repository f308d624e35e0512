// web/plotting.js: the series of the plots, their default (the TPDO-mapped objects of the picked node), the sampling
// (one get per plotted node, never a second while the first is unanswered) and what an answer adds; against a
// stand-in for the session that answers as the emulator does (docs/control-protocol.md).
import {test} from "node:test";
import assert from "node:assert/strict";

import {MAX_SERIES, Plotting, RETRY_MS, plottableRow} from "../../../web/plotting.js";
import {NodeTable, nodeRef} from "../../../web/nodes.js";

const row = (object, name, type, unit = null, access = "ro") => ({object, name, type, unit, access});

// Two devices' dictionaries, as `objects` lists them (the parts that matter here).
const DICTIONARIES = {
  16: [
    row("0x1008:00", "Manufacturer device name", "VISIBLE_STRING"), row("0x1017:00", "Producer heartbeat time",
      "UNSIGNED16", null, "rw"),
    row("0x1A00:00", "Number of mapped objects", "UNSIGNED8", null, "rw"),
    row("0x1A00:01", "Mapping entry 1", "UNSIGNED32", null, "rw"), row("0x1A00:02", "Mapping entry 2", "UNSIGNED32"),
    row("0x1A00:03", "Mapping entry 3", "UNSIGNED32"),
    row("0x1A01:00", "Number of mapped objects", "UNSIGNED8", null, "rw"),
    row("0x1A01:01", "Mapping entry 1", "UNSIGNED32", null, "rw"),
    row("0x2000:01", "Command", "UNSIGNED8", null, "wo"),
    row("0x6000:01", "Read System Status", "UNSIGNED8"),
    row("0x6401:01", "Read Voltage Discharging", "UNSIGNED16", "V"),
    row("0x6401:02", "Read AC Current Discharging", "UNSIGNED16", "µA"),
  ],
  17: [
    row("0x1A00:00", "Number of mapped objects", "UNSIGNED8", null, "rw"),
    row("0x1A00:01", "Mapping entry 1", "UNSIGNED32", null, "rw"),
    row("0x6401:01", "Read Effective High Voltage", "INTEGER16", "V"),
  ],
};
const MAPPINGS = { // node -> object -> value (the mapping parameters)
  16: {"0x1A00:00": 3, "0x1A00:01": 0x60000108, "0x1A00:02": 0x00050008, "0x1A00:03": 0x64010110,
    "0x1A01:00": 1, "0x1A01:01": 0x64010110},
  17: {"0x1A00:00": 1, "0x1A00:01": 0x64010110},
};

/** The session's request() as the page's Session has it: requests wait until the test answers them. */
class FakeSession {
  asked = []; // {cmd, fields, resolve, reject}

  request(cmd, fields = {}) {
    return new Promise((resolve, reject) => this.asked.push({cmd, fields, resolve, reject}));
  }

  take(predicate = () => true) {
    const i = this.asked.findIndex(predicate);
    assert.notEqual(i, -1, `no such request among ${JSON.stringify(this.asked.map((a) => [a.cmd, a.fields]))}`);
    return this.asked.splice(i, 1)[0];
  }

  /** Answers every waiting objects and get request of the mapping as the emulator would, until none is left. */
  async answerSetup() {
    for (;;) {
      await settle();
      const r = this.asked.find((a) => a.cmd === "objects" || a.fields.objects?.some((o) => o.startsWith("0x1A")));
      if (r === undefined) {
        return;
      }
      this.asked.splice(this.asked.indexOf(r), 1);
      const node = Number(r.fields.node.split("@")[0]);
      if (r.cmd === "objects") {
        r.resolve({ok: true, node, objects: DICTIONARIES[node]});
      } else {
        r.resolve({ok: true, node, time_us: 1, values: r.fields.objects.map((object) => object in MAPPINGS[node]
          ? {object, value: MAPPINGS[node][object], type: "UNSIGNED32"}
          : {object, error: "sub-index does not exist (0x06090011)"})});
      }
    }
  }
}

const settle = () => new Promise((resolve) => setImmediate(resolve));

function shown(...ids) {
  return ids.map((node) => ({node, bus: "vcan0", device: "sds", variant: null, state: "PRE-OPERATIONAL", faults: [],
    last_emcy: null, last_heartbeat_us: null, error_register: 0, device_type: 0, heartbeat_ms: 0}));
}

function table(...ids) {
  const nodes = new NodeTable();
  nodes.show({time_us: 1_000_000, nodes: shown(...ids)}, 0);
  return nodes;
}

test("nodeRef: a node key in the control protocol's form; plottableRow: readable numbers only", () => {
  assert.equal(nodeRef("vcan0/16"), "16@vcan0");
  assert.equal(nodeRef("can/a/127"), "127@can/a");
  assert.equal(plottableRow(row("0x6401:01", "", "INTEGER16")), true);
  assert.equal(plottableRow(row("0x2540:01", "", "REAL32")), true);
  assert.equal(plottableRow(row("0x2003:00", "", "BOOLEAN")), true);
  assert.equal(plottableRow(row("0x1018:01", "", "UNSIGNED32", null, "const")), true);
  assert.equal(plottableRow(row("0x1008:00", "", "VISIBLE_STRING")), false);
  assert.equal(plottableRow(row("0x2001:00", "", "OCTET_STRING")), false);
  assert.equal(plottableRow(row("0x2000:01", "", "UNSIGNED8", null, "wo")), false);
});

test("by default the first node's TPDO-mapped objects are plotted, found from its mapping", async () => {
  const session = new FakeSession();
  const p = new Plotting(session, table(16, 17));
  p.tick(0);
  assert.deepEqual(session.asked.map((a) => [a.cmd, a.fields]), [["objects", {node: "16@vcan0"}]]);
  await session.answerSetup();
  assert.equal(p.defaultKey, "vcan0/16");
  // 0x6000:01 and 0x6401:01 (twice mapped, once plotted); the dummy entry 0x0005 is padding
  assert.deepEqual(p.series, [
    {key: "vcan0/16", object: "0x6000:01", unit: "", label: "0x6000:01 Read System Status"},
    {key: "vcan0/16", object: "0x6401:01", unit: "V", label: "0x6401:01 Read Voltage Discharging"},
  ]);
  assert.deepEqual(p.charts().map((c) => [c.id, c.series.map((s) => s.object)]),
    [["vcan0/16 ", ["0x6000:01"]], ["vcan0/16 V", ["0x6401:01"]]]);
  assert.equal(p.problem, null);
});

test("a node only heard on the bus is never the default: the first emulated one is", async () => {
  const session = new FakeSession();
  const nodes = new NodeTable();
  nodes.show({time_us: 1_000_000, nodes: shown(16, 17),
    heard: [{node: 5, bus: "vcan0", state: "OPERATIONAL", boot_up: false, last_heartbeat_us: 900_000}]}, 0);
  assert.equal(nodes.rows(0)[0].key, "vcan0/5"); // first in the overview
  const p = new Plotting(session, nodes);
  p.tick(0);
  assert.deepEqual(session.asked.map((a) => [a.cmd, a.fields]), [["objects", {node: "16@vcan0"}]]);
});

test("a plot gains points: each answer of the sampling get is a sample at its time_us", async () => {
  const session = new FakeSession();
  const p = new Plotting(session, table(16));
  p.tick(0);
  await session.answerSetup();
  p.tick(250);
  const get = session.take((a) => a.cmd === "get");
  assert.deepEqual(get.fields, {node: "16@vcan0", objects: ["0x6000:01", "0x6401:01"]});
  p.tick(500); // unanswered: no second get for the node
  assert.deepEqual(session.asked, []);
  get.resolve({ok: true, node: 16, time_us: 2_000_000, values: [
    {object: "0x6000:01", value: 1, type: "UNSIGNED8"}, {object: "0x6401:01", value: 4200, type: "UNSIGNED16"}]});
  await settle();
  assert.equal(p.buffer("vcan0/16").length, 1);
  p.tick(750);
  const next = session.take((a) => a.cmd === "get");
  next.resolve({ok: true, node: 16, time_us: 2_250_000, values: [
    {object: "0x6000:01", value: 1, type: "UNSIGNED8"}, {object: "0x6401:01", error: "no data available (0x08000024)"}]});
  await settle();
  const b = p.buffer("vcan0/16");
  assert.deepEqual(b.times, [2, 2.25]);
  assert.deepEqual(b.column("0x6401:01"), [4200, null]);
  assert.deepEqual(b.column("0x6000:01"), [1, 1]);
});

test("a get that fails is shown as the problem and asked again at the next exchange", async () => {
  const session = new FakeSession();
  const p = new Plotting(session, table(16));
  p.tick(0);
  await session.answerSetup();
  p.tick(250);
  session.take((a) => a.cmd === "get").reject(new Error("no node 16"));
  await settle();
  assert.equal(p.problem, "node 16@vcan0: no node 16");
  p.tick(500);
  session.take((a) => a.cmd === "get").resolve({ok: true, node: 16, time_us: 5, values: []});
  await settle();
  assert.equal(p.problem, null);
});

test("page.plot's way in: add() plots any numeric object; the default then no longer follows the picked node",
  async () => {
    const session = new FakeSession();
    const p = new Plotting(session, table(16, 17));
    p.tick(0);
    await session.answerSetup();
    const added = p.add("vcan0/16", "6401:2");
    await session.answerSetup();
    await added;
    assert.deepEqual(p.series.map((s) => s.object), ["0x6000:01", "0x6401:01", "0x6401:02"]);
    assert.equal(p.defaultKey, null);
    assert.equal(p.series[2].unit, "µA");
    const changes = p.changes;
    await p.add("vcan0/16", "0x6401:02"); // already plotted: nothing changes
    assert.equal(p.changes, changes);
    p.select("vcan0/17", 1000);
    await session.answerSetup();
    assert.deepEqual(p.series.map((s) => s.key), ["vcan0/16", "vcan0/16", "vcan0/16"]);
    // another node's object: its own dictionary, its own get
    const other = p.add("vcan0/17", "0x6401:01");
    await session.answerSetup();
    await other;
    assert.deepEqual(p.charts().map((c) => c.id), ["vcan0/16 ", "vcan0/16 V", "vcan0/16 µA", "vcan0/17 V"]);
    p.tick(1250);
    assert.deepEqual(session.asked.map((a) => a.fields), [
      {node: "16@vcan0", objects: ["0x6000:01", "0x6401:01", "0x6401:02"]},
      {node: "17@vcan0", objects: ["0x6401:01"]},
    ]);
  });

test("add refuses what cannot be plotted, with what is wrong", async () => {
  const session = new FakeSession();
  const p = new Plotting(session, table(16));
  const refused = async (object, message) => {
    const refusal = assert.rejects(p.add("vcan0/16", object), {message});
    await session.answerSetup();
    await refusal;
  };
  await refused("volts", '"volts" is not an object: INDEX:SUB in hex (0x6401:01)');
  await refused("0x6401:09", "node 16@vcan0 has no object 0x6401:09");
  await refused("0x1008", "0x1008:00 of node 16@vcan0 (VISIBLE_STRING, ro) is not a number that can be read");
  await refused("0x2000:01", "0x2000:01 of node 16@vcan0 (UNSIGNED8, wo) is not a number that can be read");
  assert.deepEqual(p.series, []);
});

test("at most MAX_SERIES series", async () => {
  const session = new FakeSession();
  const p = new Plotting(session, table(16));
  const many = Array.from({length: MAX_SERIES + 1}, (_, i) => row(`0x3000:${i.toString(16).toUpperCase().padStart(2, "0")}`,
    `value ${i}`, "UNSIGNED8"));
  const dictionary = p.dictionary("vcan0/16");
  session.take((a) => a.cmd === "objects").resolve({ok: true, node: 16, objects: many});
  await dictionary;
  for (const r of many.slice(0, MAX_SERIES)) {
    await p.add("vcan0/16", r.object);
  }
  await assert.rejects(p.add("vcan0/16", many[MAX_SERIES].object), {message: `at most ${MAX_SERIES} series: remove one first`});
  p.tick(0);
  assert.equal(session.take((a) => a.cmd === "get").fields.objects.length, MAX_SERIES); // one get holds them all
});

test("remove: the series and, with a node's last one, its samples and its get go", async () => {
  const session = new FakeSession();
  const p = new Plotting(session, table(16));
  p.tick(0);
  await session.answerSetup();
  p.remove("vcan0/16", "0x6000:01");
  assert.deepEqual(p.series.map((s) => s.object), ["0x6401:01"]);
  assert.deepEqual(p.buffer("vcan0/16").columns, ["0x6401:01"]);
  p.remove("vcan0/16", "0x6401:01");
  assert.equal(p.buffer("vcan0/16"), undefined);
  p.tick(250);
  assert.deepEqual(session.asked, []);
  p.select("vcan0/16", 300); // changed by the user: picking a node no longer replaces the series
  assert.deepEqual(session.asked, []);
});

test("picking a node makes its TPDO objects the default; a mapping not answered is asked again later", async () => {
  const session = new FakeSession();
  const p = new Plotting(session, table(16, 17));
  p.select("vcan0/17", 0);
  session.take((a) => a.cmd === "objects").reject(new Error("the session ended before it answered"));
  await settle();
  assert.equal(p.problem, "node 17@vcan0: its TPDO mapping: the session ended before it answered");
  p.tick(RETRY_MS - 1);
  assert.deepEqual(session.asked, []);
  p.tick(RETRY_MS);
  await session.answerSetup();
  assert.deepEqual(p.series, [{key: "vcan0/17", object: "0x6401:01", unit: "V", label: "0x6401:01 Read Effective High Voltage"}]);
  assert.equal(p.problem, null);
  p.select("vcan0/16", RETRY_MS + 100);
  await session.answerSetup();
  assert.equal(p.defaultKey, "vcan0/16");
  assert.deepEqual(p.series.map((s) => s.object), ["0x6000:01", "0x6401:01"]);
  assert.equal(p.buffer("vcan0/17"), undefined);
});

test("no node yet: nothing asked", () => {
  const session = new FakeSession();
  const p = new Plotting(session, new NodeTable());
  p.tick(0);
  assert.deepEqual(session.asked, []);
});

test("EMCYs and NMT changes become marks of their node", () => {
  const p = new Plotting(new FakeSession(), new NodeTable());
  p.event({event: "emcy", time_us: 3_000_000, bus: "vcan0", node: 16, code: 0x5000, register: 1, info: "00"});
  p.event({event: "nmt", time_us: 4_000_000, bus: "vcan0", node: 16, from: "PRE-OPERATIONAL", to: "STOPPED"});
  assert.deepEqual(p.marks.between("vcan0/16", 0, 5).map((m) => m.label), ["EMCY 0x5000", "STOPPED"]);
});
