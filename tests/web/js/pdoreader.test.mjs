// web/pdoreader.js: which requests read the PDO mapping of the nodes the trace sees, and when they are read again.
import {test} from "node:test";
import assert from "node:assert/strict";

import {PARALLEL, PdoReader, mappingMayChange} from "../../../web/pdoreader.js";
import {PdoMaps} from "../../../web/pdomap.js";

/** A stand-in for web/api.js Session: each request waits until the test answers it. */
class StubSession {
  asked = [];

  request(cmd, fields = {}) {
    return new Promise((resolve, reject) => this.asked.push({cmd, fields, resolve, reject}));
  }

  /** The requests asked since the last take(), as [cmd, fields]; they stay answerable through `pending`. */
  take() {
    this.pending = this.asked;
    this.asked = [];
    return this.pending.map((r) => [r.cmd, r.fields]);
  }
}

const settle = () => new Promise((resolve) => setImmediate(resolve));

const OBJECTS = [
  {object: "0x1800:01", name: "COB-ID", object_name: "TPDO1 communication", type: "UNSIGNED32"},
  {object: "0x1A00:00", name: "Count", object_name: "TPDO1 mapping", type: "UNSIGNED8"},
  {object: "0x1A00:01", name: "Entry 1", object_name: "TPDO1 mapping", type: "UNSIGNED32"},
  {object: "0x6000:05", name: "Read Working Distance", object_name: "Read Input 8 Bit", type: "UNSIGNED8", unit: "cm"},
];

function values(node, bits = 8) {
  return [{object: "0x1800:01", value: 0x180 + node, type: "UNSIGNED32"},
    {object: "0x1A00:00", value: 1, type: "UNSIGNED8"},
    {object: "0x1A00:01", value: 0x60000500 + bits, type: "UNSIGNED32"}];
}

const LIST = {nodes: Array.from({length: PARALLEL + 2}, (_, k) => ({node: 17 + k, device: "sds", variant: "N", bus: "vcan0"}))};

test("a node's mapping: list, objects once per device, get of its PDO objects; then its PDOs decode", async () => {
  const maps = new PdoMaps();
  const read = [];
  const reader = new PdoReader(maps, (bus, node) => read.push(`${bus}/${node}`));
  const session = new StubSession();
  reader.want("vcan0", 17);
  reader.want("vcan0", 18);
  reader.want("vcan0", 17); // once
  reader.tick(session);
  await settle();
  assert.deepEqual(session.take(), [["list", {}]]); // the two share it
  session.pending[0].resolve(LIST);
  await settle();
  assert.deepEqual(session.take(), [["objects", {node: "17@vcan0"}]]); // sds/N: one dictionary for both
  session.pending[0].resolve({objects: OBJECTS});
  await settle();
  assert.deepEqual(session.take(), [
    ["get", {node: "17@vcan0", objects: ["0x1800:01", "0x1A00:00", "0x1A00:01"]}],
    ["get", {node: "18@vcan0", objects: ["0x1800:01", "0x1A00:00", "0x1A00:01"]}],
  ]);
  session.pending[0].resolve({values: values(17)});
  session.pending[1].resolve({values: values(18)});
  await settle();
  assert.deepEqual(read, ["vcan0/17", "vcan0/18"]);
  assert.deepEqual(maps.lookup({id: 0x192, dir: "tx", node: 18, bus: "vcan0"}, Uint8Array.from([15])),
    {name: "TPDO1", node: 18, text: "Read Working Distance=15 cm"});
  reader.tick(session);
  await settle();
  assert.deepEqual(session.take(), []); // nothing more to read
});

test("a node seen in SDOs: its dictionary alone, for its objects' types; its PDOs later read its mapping", async () => {
  const maps = new PdoMaps();
  const read = [];
  const reader = new PdoReader(maps, (bus, node) => read.push(`${bus}/${node}`));
  const session = new StubSession();
  reader.wantTypes("vcan0", 17);
  reader.wantTypes("vcan0", 17); // once
  assert.equal(reader.typeOf("vcan0", 17, 0x6000, 5), null); // not read yet
  reader.tick(session);
  await settle();
  assert.deepEqual(session.take(), [["list", {}]]);
  session.pending[0].resolve(LIST);
  await settle();
  assert.deepEqual(session.take(), [["objects", {node: "17@vcan0"}]]);
  session.pending[0].resolve({objects: OBJECTS});
  await settle();
  assert.deepEqual(read, ["vcan0/17"]); // the trace decodes its SDOs again
  assert.equal(reader.typeOf("vcan0", 17, 0x6000, 5), "UNSIGNED8");
  assert.equal(reader.typeOf("vcan0", 17, 0x6000, 6), null); // no such object
  assert.equal(reader.typeOf("vcan1", 17, 0x6000, 5), null); // another bus: not read
  assert.ok(!maps.has("vcan0", 17)); // no mapping read: no get asked
  reader.tick(session);
  await settle();
  assert.deepEqual(session.take(), []);
  reader.want("vcan0", 17); // a PDO of it: now its mapping, by the dictionary already read
  reader.tick(session);
  await settle();
  assert.deepEqual(session.take(), [["get", {node: "17@vcan0", objects: ["0x1800:01", "0x1A00:00", "0x1A00:01"]}]]);
  session.pending[0].resolve({values: values(17)});
  await settle();
  assert.ok(maps.has("vcan0", 17));
  reader.wantTypes("vcan0", 17); // its PDOs and its types are read: nothing more
  reader.tick(session);
  await settle();
  assert.deepEqual(session.take(), []);
  reader.clear();
  assert.equal(reader.typeOf("vcan0", 17, 0x6000, 5), null);
});

test(`at most ${PARALLEL} nodes are read at once`, async () => {
  const reader = new PdoReader(new PdoMaps());
  const session = new StubSession();
  const nodes = Array.from({length: PARALLEL + 2}, (_, k) => 17 + k);
  const named = (list) => list.map((node) => `${node}@vcan0`);
  for (const node of nodes) {
    reader.want("vcan0", node);
  }
  reader.tick(session);
  await settle();
  session.take();
  session.pending[0].resolve(LIST);
  await settle();
  session.take();
  session.pending[0].resolve({objects: OBJECTS});
  await settle();
  assert.deepEqual(session.take().map(([, f]) => f.node), named(nodes.slice(0, PARALLEL)));
  const gets = session.pending;
  reader.tick(session);
  await settle();
  assert.deepEqual(session.take(), []);
  for (const r of gets) {
    r.resolve({values: values(0)});
  }
  await settle();
  reader.tick(session);
  await settle();
  assert.deepEqual(session.take().map(([, f]) => f.node), named(nodes.slice(PARALLEL))); // the dictionary is known
});

test("a node the emulator does not have is not read; stale() looks for it again", async () => {
  const maps = new PdoMaps();
  const reader = new PdoReader(maps);
  const session = new StubSession();
  reader.want("vcan0", 5); // an RPDO to a device on the bus that is not emulated
  reader.tick(session);
  await settle();
  session.take();
  session.pending[0].resolve(LIST);
  await settle();
  assert.deepEqual(session.take(), []);
  reader.tick(session);
  await settle();
  assert.deepEqual(session.take(), []);
  reader.stale("vcan0", 5); // its boot-up: LSS may have given a node that ID
  reader.tick(session);
  await settle();
  assert.deepEqual(session.take(), [["list", {}]]);
});

test("stale() reads a node again, after the read under way; other buses and nodes stay", async () => {
  const maps = new PdoMaps();
  const read = [];
  const reader = new PdoReader(maps, (bus, node) => read.push(node));
  const session = new StubSession();
  reader.want("vcan0", 17);
  reader.tick(session);
  await settle();
  session.take();
  session.pending[0].resolve(LIST);
  await settle();
  session.take();
  session.pending[0].resolve({objects: OBJECTS});
  await settle();
  session.take();
  reader.stale("vcan0", null); // an NMT pre-operational to all while the get is under way
  reader.stale("vcan1", 17);
  session.pending[0].resolve({values: values(17)});
  await settle();
  assert.deepEqual(read, [17]);
  reader.tick(session);
  await settle();
  assert.deepEqual(session.take(), [["get", {node: "17@vcan0", objects: ["0x1800:01", "0x1A00:00", "0x1A00:01"]}]]);
  session.pending[0].resolve({values: values(17, 8)});
  await settle();
  assert.deepEqual(read, [17, 17]);
});

test("a failed read says why; a new session tries again, asking the list anew", async () => {
  const reader = new PdoReader(new PdoMaps());
  const session = new StubSession();
  reader.want("vcan0", 17);
  reader.tick(session);
  await settle();
  session.take();
  session.pending[0].resolve(LIST);
  await settle();
  session.take();
  session.pending[0].reject(new Error("the session ended before it answered"));
  await settle();
  assert.equal(reader.problem, "PDO mapping of node 17: the session ended before it answered");
  reader.tick(session);
  await settle();
  assert.deepEqual(session.take(), []);
  reader.reset();
  reader.tick(session);
  await settle();
  assert.deepEqual(session.take(), [["list", {}]]);
  session.pending[0].resolve(LIST);
  await settle();
  assert.deepEqual(session.take(), [["objects", {node: "17@vcan0"}]]); // the failed dictionary is asked again
});

test("clear() forgets the nodes and their PDOs", async () => {
  const maps = new PdoMaps();
  const reader = new PdoReader(maps);
  maps.set("vcan0", 17, [{name: "TPDO1", dir: "tx", cobId: 0x191, mpdo: null, entries: []}], null);
  reader.want("vcan0", 17);
  reader.clear();
  assert.ok(!maps.has("vcan0", 17));
  const session = new StubSession();
  reader.tick(session);
  await settle();
  assert.deepEqual(session.take(), []);
});

test("after which frames a mapping may have changed", () => {
  const f = (id, data, extra = {}) => mappingMayChange({id, data, rtr: false, bus: "vcan0", ...extra});
  assert.deepEqual(f(0x000, "8011"), {bus: "vcan0", node: 17});
  assert.deepEqual(f(0x000, "8100"), {bus: "vcan0", node: null});
  assert.deepEqual(f(0x000, "8211"), {bus: "vcan0", node: 17});
  assert.equal(f(0x000, "0111"), null); // start: the mapping it runs with is the one read
  assert.equal(f(0x000, "0211"), null);
  assert.deepEqual(f(0x711, "00"), {bus: "vcan0", node: 17}); // boot-up
  assert.equal(f(0x711, "05"), null);
  assert.equal(f(0x711, "", {rtr: true}), null);
  assert.deepEqual(f(0x591, "60001A0100000000"), {bus: "vcan0", node: 17}); // download of 0x1A00:01 answered
  assert.deepEqual(f(0x591, "6000140100000000"), {bus: "vcan0", node: 17}); // 0x1400:01
  assert.deepEqual(f(0x591, "60FF1B0000000000"), {bus: "vcan0", node: 17}); // 0x1BFF
  assert.equal(f(0x591, "6017100000000000"), null); // 0x1017
  assert.equal(f(0x591, "60FF130000000000"), null); // 0x13FF
  assert.equal(f(0x611, "2F001A0000000000"), null); // the request: not yet written
  assert.equal(f(0x591, "43001A0100000000"), null); // an upload
  assert.equal(f(0x580, "60001A0100000000"), null);
  // an extended frame is none of these, whatever its identifier and bytes
  assert.equal(f(0x000, "8011", {eff: true}), null);
  assert.equal(f(0x000, "8100", {eff: true}), null);
  assert.equal(f(0x711, "00", {eff: true}), null);
  assert.equal(f(0x591, "60001A0100000000", {eff: true}), null);
});
