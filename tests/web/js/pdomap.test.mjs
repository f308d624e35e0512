// web/pdomap.js: the objects read to know a node's PDOs, the PDOs they give, and payloads as named values.
import {test} from "node:test";
import assert from "node:assert/strict";

import {Dictionary, PdoMaps, pdoText, pdosOf, typeBits, valueText} from "../../../web/pdomap.js";
import {decode} from "../../../web/decode.js";

const o = (object, name, type, extra = {}) => ({object, name, object_name: extra.object_name ?? name, type,
  ...(extra.unit ? {unit: extra.unit} : {})});

// Part of the SDS dictionary as `objects` gives it (names as in od/sds.eds, units from od/sds.toml).
const SDS = [
  o("0x1400:00", "Largest Sub-Index supported", "UNSIGNED8"), o("0x1400:01", "COB-ID used by PDO", "UNSIGNED32"),
  o("0x1600:00", "Number of mapped Application Objects supported", "UNSIGNED8"),
  o("0x1600:01", "1. mapped Object", "UNSIGNED32"),
  o("0x1800:00", "Largest Sub-Index supported", "UNSIGNED8"), o("0x1800:01", "COB-ID used by PDO", "UNSIGNED32"),
  o("0x1801:01", "COB-ID used by PDO", "UNSIGNED32"),
  o("0x1A00:00", "Number of mapped Application Objects supported", "UNSIGNED8"),
  ...[1, 2, 3, 4, 5].map((s) => o(`0x1A00:0${s}`, `${s}. mapped Object`, "UNSIGNED32")),
  o("0x1A01:00", "Number of mapped Application Objects supported", "UNSIGNED8"),
  ...[1, 2, 3].map((s) => o(`0x1A01:0${s}`, `${s}. mapped Object`, "UNSIGNED32")),
  o("0x6000:01", "Read System Status", "UNSIGNED8", {object_name: "Read Input 8 Bit"}),
  o("0x6000:02", "Read High Voltage Balance", "UNSIGNED8", {object_name: "Read Input 8 Bit", unit: "% (50 = balanced)"}),
  o("0x6000:03", "Read Power Capacity", "UNSIGNED8", {object_name: "Read Input 8 Bit", unit: "%"}),
  o("0x6000:04", "Read Pollution", "UNSIGNED8", {object_name: "Read Input 8 Bit", unit: "%"}),
  o("0x6000:05", "Read Working Distance", "UNSIGNED8", {object_name: "Read Input 8 Bit", unit: "cm"}),
  o("0x6200:01", "Write HV Release", "UNSIGNED8", {object_name: "Write Output 8 Bit"}),
  o("0x6401:01", "Read Effective High Voltage", "INTEGER16", {object_name: "Read Analog Input 16 Bit", unit: "V"}),
  o("0x6401:02", "Read Effective Current", "INTEGER16", {object_name: "Read Analog Input 16 Bit", unit: "µA"}),
  o("0x6401:03", "Read DC Discharging Current", "INTEGER16", {object_name: "Read Analog Input 16 Bit", unit: "µA"}),
];

// What `get` answers for them on node 17 (the defaults of od/sds.eds; TPDO2 invalid here, bit 31).
const SDS_VALUES = [
  {object: "0x1400:01", value: 0x211, type: "UNSIGNED32"}, {object: "0x1600:00", value: 1, type: "UNSIGNED8"},
  {object: "0x1600:01", value: 0x62000108, type: "UNSIGNED32"},
  {object: "0x1800:01", value: 0x191, type: "UNSIGNED32"}, {object: "0x1A00:00", value: 5, type: "UNSIGNED8"},
  ...[1, 2, 3, 4, 5].map((s) => ({object: `0x1A00:0${s}`, value: 0x60000008 + s * 0x100, type: "UNSIGNED32"})),
  {object: "0x1801:01", value: 0x80000291, type: "UNSIGNED32"}, {object: "0x1A01:00", value: 3, type: "UNSIGNED8"},
  ...[1, 2, 3].map((s) => ({object: `0x1A01:0${s}`, value: 0x64010010 + s * 0x100, type: "UNSIGNED32"})),
];

test("the objects read for the PDOs: the COB-IDs and every mapping sub-index the node has, in gets of 64 at most", () => {
  assert.deepEqual(new Dictionary(SDS).mappingObjects(), [[
    "0x1400:01", "0x1600:00", "0x1600:01", "0x1800:01", "0x1A00:00", "0x1A00:01", "0x1A00:02", "0x1A00:03",
    "0x1A00:04", "0x1A00:05", "0x1801:01", "0x1A01:00", "0x1A01:01", "0x1A01:02", "0x1A01:03",
  ]]);
  // Four PDOs of each direction with 8 entries each: 8 COB-IDs and 4 x 2 x 9 mapping sub-indices = 80, in two gets.
  const full = [];
  for (const [comm, mapping] of [[0x1400, 0x1600], [0x1800, 0x1A00]]) {
    for (let n = 0; n < 4; n++) {
      full.push(o(`0x${(comm + n).toString(16).toUpperCase()}:01`, "COB ID", "UNSIGNED32"));
      for (let s = 0; s <= 8; s++) {
        full.push(o(`0x${(mapping + n).toString(16).toUpperCase()}:0${s}`, `Entry ${s}`, "UNSIGNED32"));
      }
    }
  }
  const lists = new Dictionary(full).mappingObjects();
  assert.deepEqual(lists.map((l) => l.length), [64, 16]);
  assert.equal(lists[0][0], "0x1400:01");
  assert.equal(lists[1][15], "0x1A03:08");
});

test("labels: a sub-index's own name where unique, else told apart by its object's name", () => {
  const dictionary = new Dictionary([
    o("0x2500:01", "Value", "REAL32", {object_name: "Sensor Value", unit: "l/min"}),
    o("0x2540:01", "Value", "REAL32", {object_name: "Control Value", unit: "l/min"}),
    o("0x2600:01", "Value", "REAL32", {object_name: "Gas Temperature"}),
    o("0x6000:05", "Read Working Distance", "UNSIGNED8", {object_name: "Read Input 8 Bit", unit: "cm"}),
    {object: "0x2700:00", name: null, object_name: "Status", type: "UNSIGNED8"},
  ]);
  assert.deepEqual(dictionary.entry(0x2500, 1), {object: "0x2500:01", label: "Sensor Value", type: "REAL32",
    unit: "l/min"});
  assert.equal(dictionary.entry(0x2600, 1).label, "Gas Temperature Value");
  assert.equal(dictionary.entry(0x6000, 5).label, "Read Working Distance");
  assert.equal(dictionary.entry(0x2700, 0).label, "Status");
  assert.equal(dictionary.entry(0x2800, 0), null);
});

test("the PDOs of a node from its values: valid ones, their COB-IDs and entries", () => {
  const pdos = pdosOf(SDS_VALUES, new Dictionary(SDS));
  assert.deepEqual(pdos.map((p) => [p.name, p.dir, p.cobId, p.mpdo, p.entries.length]),
    [["RPDO1", "rx", 0x211, null, 1], ["TPDO1", "tx", 0x191, null, 5]]);
  assert.deepEqual(pdos[1].entries[4], {object: "0x6000:05", label: "Read Working Distance", type: "UNSIGNED8",
    unit: "cm", bits: 8});
  // An object read with an error counts as absent; a count beyond the entries read stops at them; dummies, unknowns.
  const odd = pdosOf([
    {object: "0x1800:01", value: 0x20000123, type: "UNSIGNED32"}, {object: "0x1A00:00", value: 4, type: "UNSIGNED8"},
    {object: "0x1A00:01", value: 0x00050008, type: "UNSIGNED32"}, {object: "0x1A00:02", value: 0x21000110,
      type: "UNSIGNED32"}, {object: "0x1A00:03", error: "sub-index does not exist (0x06090011)"},
    {object: "0x1801:01", value: 0x281, type: "UNSIGNED32"}, {object: "0x1A01:00", value: 0xFE, type: "UNSIGNED8"},
    {object: "0x1802:01", value: 0x381, type: "UNSIGNED32"},
  ], new Dictionary(SDS));
  assert.deepEqual(odd, [
    {name: "TPDO1", dir: "tx", cobId: 0x123, mpdo: null, entries: [
      {object: null, label: "0x0005:00", type: null, unit: null, bits: 8},
      {object: "0x2100:01", label: "0x2100:01", type: null, unit: null, bits: 16}]},
    {name: "TPDO2", dir: "tx", cobId: 0x281, mpdo: "SAM", entries: []},
  ]);
});

test("type sizes and values by type", () => {
  assert.deepEqual(["BOOLEAN", "UNSIGNED8", "INTEGER24", "REAL32", "REAL64", "VISIBLE_STRING", undefined].map(typeBits),
    [1, 8, 24, 32, 64, null, null]);
  assert.equal(valueText(1n, 1, "BOOLEAN"), "true");
  assert.equal(valueText(0n, 1, "BOOLEAN"), "false");
  assert.equal(valueText(0xFFFFn, 16, "INTEGER16"), "-1");
  assert.equal(valueText(0x7FFFn, 16, "INTEGER16"), "32767");
  assert.equal(valueText(0x800000n, 24, "INTEGER24"), "-8388608");
  assert.equal(valueText(0xFFFFFFFFn, 32, "UNSIGNED32"), "4294967295");
  assert.equal(valueText(0xFFFFFFFFFFFFFFFFn, 64, "UNSIGNED64"), "18446744073709551615");
  assert.equal(valueText(0x8000000000000000n, 64, "INTEGER64"), "-9223372036854775808");
  assert.equal(valueText(0x3DCCCCCDn, 32, "REAL32"), "0.1");
  assert.equal(valueText(0xC2F70000n, 32, "REAL32"), "-123.5");
  assert.equal(valueText(0x7FC00000n, 32, "REAL32"), "NaN");
  assert.equal(valueText(0x3FF8000000000000n, 64, "REAL64"), "1.5");
  assert.equal(valueText(0x00434241n, 32, "VISIBLE_STRING"), "\"ABC\"");
  assert.equal(valueText(0xBEEFn, 16, "OCTET_STRING"), "0xBEEF");
  assert.equal(valueText(42n, 8, null), "42"); // an object the dictionary does not list: unsigned
});

test("a payload by its mapping: name=value unit, little-endian, bit by bit", () => {
  const [, tpdo1] = pdosOf(SDS_VALUES, new Dictionary(SDS));
  assert.equal(pdoText(tpdo1, Uint8Array.from([0, 50, 100, 7, 15])),
    "Read System Status=0, Read High Voltage Balance=50 % (50 = balanced), Read Power Capacity=100 %, " +
    "Read Pollution=7 %, Read Working Distance=15 cm");
  assert.equal(pdoText(tpdo1, Uint8Array.from([1, 2, 3])),
    "Read System Status=1, Read High Voltage Balance=2 % (50 = balanced), Read Power Capacity=3 %, " +
    "(mapping needs 5 bytes, 3 sent)");
  const packed = {mpdo: null, entries: [
    {object: "0x2000:01", label: "A", type: "BOOLEAN", unit: null, bits: 1},
    {object: null, label: "0x0001:00", type: null, unit: null, bits: 3}, // a dummy: skipped
    {object: "0x2000:02", label: "B", type: "UNSIGNED8", unit: null, bits: 4},
    {object: "0x2000:03", label: "C", type: "INTEGER16", unit: "V", bits: 16},
    {object: "0x2000:04", label: "D", type: "REAL32", unit: "l/min", bits: 32},
  ]};
  // A = 1, B = 0xA (bits 4..7), C = -2, D = 1.5 (0x3FC00000)
  assert.equal(pdoText(packed, Uint8Array.from([0xA1, 0xFE, 0xFF, 0x00, 0x00, 0xC0, 0x3F])),
    "A=true, B=10, C=-2 V, D=1.5 l/min");
  assert.equal(pdoText({mpdo: null, entries: []}, Uint8Array.from([])), "");
});

test("multiplexed PDOs: SAM by the producer's dictionary, DAM raw", () => {
  const dictionary = new Dictionary([o("0x2500:02", "Value", "REAL32", {object_name: "Gas Temperature", unit: "°C"})]);
  const sam = {mpdo: "SAM", entries: []};
  assert.equal(pdoText(sam, Uint8Array.from([0x12, 0x00, 0x25, 0x02, 0x00, 0x00, 0xC8, 0x41]), dictionary),
    "SAM-MPDO of node 18 0x2500:02 Value=25 °C");
  assert.equal(pdoText(sam, Uint8Array.from([0x12, 0x00, 0x26, 0x01, 0x01, 0x00, 0x00, 0x00]), dictionary),
    "SAM-MPDO of node 18 0x2600:01 = 0x00000001");
  assert.equal(pdoText({mpdo: "DAM", entries: []}, Uint8Array.from([0x85, 0x00, 0x62, 0x01, 0x01, 0, 0, 0]), null),
    "DAM-MPDO to node 5 0x6200:01 = 0x00000001");
  assert.equal(pdoText({mpdo: "DAM", entries: []}, Uint8Array.from([0x80, 0x00, 0x62, 0x01, 0x01, 0, 0, 0]), null),
    "DAM-MPDO to all nodes 0x6200:01 = 0x00000001");
  assert.equal(pdoText(sam, Uint8Array.from([0x12]), dictionary), "SAM-MPDO (8 bytes expected, 1 given)");
});

test("PdoMaps finds a node's TPDO by its frames and an RPDO by frames from the bus; decode() uses it", () => {
  const maps = new PdoMaps();
  const dictionary = new Dictionary(SDS);
  maps.set("vcan0", 17, pdosOf(SDS_VALUES, dictionary), dictionary);
  const lookup = (frame, bytes) => maps.lookup(frame, bytes);
  assert.deepEqual(decode({id: 0x191, data: "0032640A0F", dir: "tx", node: 17, bus: "vcan0"}, lookup), {
    kind: "PDO", node: 17, text: "TPDO1 Read System Status=0, Read High Voltage Balance=50 % (50 = balanced), " +
      "Read Power Capacity=100 %, Read Pollution=10 %, Read Working Distance=15 cm"});
  assert.deepEqual(decode({id: 0x211, data: "01", dir: "rx", bus: "vcan0"}, lookup),
    {kind: "PDO", node: 17, text: "RPDO1 Write HV Release=1"});
  // Another bus, another node's frame on that COB-ID: not this node's mapping.
  assert.equal(maps.lookup({id: 0x191, dir: "tx", node: 17, bus: "vcan1"}, new Uint8Array(5)), null);
  assert.equal(maps.lookup({id: 0x191, dir: "tx", node: 18, bus: "vcan0"}, new Uint8Array(5)), null);
  assert.equal(maps.lookup({id: 0x191, dir: "rx", bus: "vcan0"}, new Uint8Array(5)), null); // a TPDO is sent by it
  assert.ok(maps.has("vcan0", 17));
  maps.delete("vcan0", 17);
  assert.equal(maps.lookup({id: 0x211, dir: "rx", bus: "vcan0"}, new Uint8Array(1)), null);
  assert.ok(!maps.has("vcan0", 17));
});

test("an RPDO several nodes receive is shown as the lowest node-ID's", () => {
  const maps = new PdoMaps();
  const rpdo = (node) => [{name: "RPDO1", dir: "rx", cobId: 0x200, mpdo: null, entries: [
    {object: "0x6200:01", label: `Out ${node}`, type: "UNSIGNED8", unit: null, bits: 8}]}];
  maps.set("vcan0", 20, rpdo(20), null);
  maps.set("vcan0", 3, rpdo(3), null);
  assert.deepEqual(maps.lookup({id: 0x200, dir: "rx", bus: "vcan0"}, Uint8Array.from([7])),
    {name: "RPDO1", node: 3, text: "Out 3=7"});
  maps.clear();
  assert.equal(maps.lookup({id: 0x200, dir: "rx", bus: "vcan0"}, Uint8Array.from([7])), null);
});
