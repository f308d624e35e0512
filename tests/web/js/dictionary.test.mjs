// web/dictionary.js: the node view's dictionary tree, the values' texts and what a typed value is sent as.
import {test} from "node:test";
import assert from "node:assert/strict";

import * as dictionary from "../../../web/dictionary.js";
import {chunks} from "../../../web/objects.js";

// As `objects` answers them (docs/control-protocol.md), a few of the PRO IONIZER's.
const OBJECTS = [
  {object: "0x1000:00", name: "Device type", object_name: "Device type", type: "UNSIGNED32", access: "ro"},
  {object: "0x1017:00", name: "Producer heartbeat time", object_name: "Producer heartbeat time", type: "UNSIGNED16",
    access: "rw", low: 0, high: 60000},
  {object: "0x1018:00", name: "Highest sub-index supported", object_name: "Identity Object", type: "UNSIGNED8",
    access: "const"},
  {object: "0x1018:01", name: "Vendor-ID", object_name: "Identity Object", type: "UNSIGNED32", access: "ro"},
  {object: "0x1018:02", name: null, object_name: "Identity Object", type: "UNSIGNED32", access: "ro"},
  {object: "0x6401:01", name: "Read Voltage Discharging", object_name: "Read Analog Input 16 Bit",
    type: "UNSIGNED16", access: "ro", unit: "V"},
];

test("groupObjects: one group per index, in order, named by the object, each entry with index and sub", () => {
  const groups = dictionary.groupObjects(OBJECTS);
  assert.deepEqual(groups.map((g) => [g.index, g.name, g.entries.map((e) => e.sub)]), [
    ["0x1000", "Device type", ["00"]],
    ["0x1017", "Producer heartbeat time", ["00"]],
    ["0x1018", "Identity Object", ["00", "01", "02"]],
    ["0x6401", "Read Analog Input 16 Bit", ["01"]],
  ]);
  assert.deepEqual(groups[2].entries[1], {...OBJECTS[3], index: "0x1018", sub: "01"});
  assert.deepEqual(dictionary.groupObjects([]), []);
});

test("isSingle: only an object of sub-index 00 alone is one row", () => {
  const groups = dictionary.groupObjects(OBJECTS);
  assert.deepEqual(groups.map(dictionary.isSingle), [true, true, false, false]); // 0x6401 has only :01 here
});

test("isWritable: rw and wo; ro and const are not edited", () => {
  assert.deepEqual(["rw", "wo", "ro", "const"].map((access) => dictionary.isWritable({access})),
    [true, true, false, false]);
});

test("limits: both, one, none", () => {
  assert.equal(dictionary.limits({low: 0, high: 60000}), "0..60000");
  assert.equal(dictionary.limits({low: -5.5, high: 2.25}), "-5.5..2.25");
  assert.equal(dictionary.limits({low: 100}), "≥ 100");
  assert.equal(dictionary.limits({high: 8}), "≤ 8");
  assert.equal(dictionary.limits({}), "");
});

test("valueText and hexHint", () => {
  assert.deepEqual([590, -3, 24.5, true, false, "ES61", "0A1B", "nan", "18446744073709551615", null, undefined]
    .map((v) => dictionary.valueText(v)), ["590", "-3", "24.5", "true", "false", "ES61", "0A1B", "nan", "18446744073709551615", "",
    ""]);
  assert.equal(dictionary.hexHint(590, "UNSIGNED32"), "0x0000024E");
  assert.equal(dictionary.hexHint(5, "UNSIGNED8"), "0x05");
  assert.equal(dictionary.hexHint(1000, "UNSIGNED16"), "0x03E8");
  assert.equal(dictionary.hexHint(-1, "INTEGER16"), "");
  assert.equal(dictionary.hexHint(24.5, "REAL32"), "");
  assert.equal(dictionary.hexHint("ES61", "VISIBLE_STRING"), "");
  assert.equal(dictionary.hexHint("18446744073709551615", "UNSIGNED64"), "");
});

// As `objects` lists them: the PRO IONIZER's (names with "COB-ID") and the Bürkert's ("COB ID").
const cob = (object, name, type = "UNSIGNED32", objectName = name) =>
  ({object, name, object_name: objectName, type, access: "rw"});

test("isCobId: the communication objects' COB-IDs by index and sub, and any UNSIGNED32 named so", () => {
  const yes = [
    cob("0x1005:00", "COB ID SYNC"), cob("0x1012:00", "COB-ID time stamp object"), cob("0x1014:00", "COB-ID EMCY"),
    cob("0x1200:01", "COB-ID Client -> Server (rx)"), cob("0x1200:02", "COB-ID Server -> Client (tx)"),
    cob("0x1280:01", "COB-ID client to server"), cob("0x12FF:02", "COB-ID server to client"),
    cob("0x1400:01", "COB-ID used by PDO"), cob("0x15FF:01", "COB ID"), cob("0x1800:01", "COB ID"),
    cob("0x19FF:01", "COB-ID used by PDO"),
    cob("0x1005:00", null), // by its index, whatever its name
    cob("0x2100:03", "Heartbeat COB-ID"), cob("0x2101:00", "cobid of the gateway"), cob("0x2102:01", "COB ID"),
    cob("0x2103:01", null, "UNSIGNED32", "COB-ID list"), // a sub without a name: its object's
  ];
  for (const entry of yes) {
    assert.equal(dictionary.isCobId(entry), true, `${entry.object} ${entry.name}`);
  }
  const no = [
    cob("0x1200:03", "Node ID of the SDO Client", "UNSIGNED8"), cob("0x1200:00", "Number Of Entries", "UNSIGNED8"),
    cob("0x1400:02", "Transmission type", "UNSIGNED8"), cob("0x1800:05", "Event timer", "UNSIGNED16"),
    cob("0x1600:01", "PDO Mapping Entry 1"), cob("0x1A00:01", "1. mapped Object"), cob("0x1000:00", "Device type"),
    cob("0x1018:01", "Vendor-ID"), cob("0x1017:00", "Producer heartbeat time", "UNSIGNED16"),
    cob("0x2100:01", "COB-ID", "UNSIGNED16"), // a COB-ID is 32 bits: another type is something else
    cob("0x1005:00", "COB ID SYNC", "UNSIGNED16"), cob("0x2104:00", "Jacobide"),
  ];
  for (const entry of no) {
    assert.equal(dictionary.isCobId(entry), false, `${entry.object} ${entry.name}`);
  }
});

test("a COB-ID's value in hex of 8 digits (its decimal the tooltip), other values as they are", () => {
  const sync = cob("0x1005:00", "COB ID SYNC");
  const tpdo = cob("0x1800:01", "COB-ID used by PDO");
  assert.equal(dictionary.valueText(128, sync), "0x00000080");
  assert.equal(dictionary.valueText(0x80000190 + 2, tpdo), "0x80000192"); // bit 31: the PDO is not valid
  assert.equal(dictionary.valueText(0, sync), "0x00000000");
  assert.equal(dictionary.valueHint(128, sync), "128");
  assert.equal(dictionary.valueHint(0x80000192, tpdo), "2147484050");
  assert.equal(dictionary.valueText(undefined, sync), "");
  assert.equal(dictionary.valueText("0x80", sync), "0x80"); // not a number: as given
  const vendor = cob("0x1018:01", "Vendor-ID");
  assert.equal(dictionary.valueText(590, vendor), "590");
  assert.equal(dictionary.valueHint(590, vendor), "0x0000024E");
  assert.equal(dictionary.valueHint("ES61", cob("0x1008:00", "Name", "VISIBLE_STRING")), "");
  // What the editor starts with (valueText) is taken back as typed: hex as the emulator reads it, decimal a number
  assert.deepEqual(dictionary.parseInput(dictionary.valueText(129, sync), "UNSIGNED32"), {value: "0x00000081"});
  assert.deepEqual(dictionary.parseInput("130", "UNSIGNED32"), {value: 130});
});

test("parseInput: numbers as numbers, strings for VISIBLE_STRING and what the emulator must read", () => {
  const cases = [
    ["200", "UNSIGNED16", {value: 200}],
    [" 200 ", "UNSIGNED16", {value: 200}],
    ["70000", "UNSIGNED16", {value: 70000}],
    ["-12", "INTEGER16", {value: -12}],
    ["24.5", "REAL32", {value: 24.5}],
    ["1e3", "REAL32", {value: 1000}],
    ["0x2A", "UNSIGNED8", {value: "0x2A"}],
    ["18446744073709551615", "UNSIGNED64", {value: "18446744073709551615"}],
    ["9007199254740991", "UNSIGNED64", {value: 9007199254740991}],
    ["true", "BOOLEAN", {value: true}],
    ["false", "BOOLEAN", {value: false}],
    ["nan", "REAL32", {value: "nan"}],
    ["twelve", "UNSIGNED8", {value: "twelve"}],
    ["", "UNSIGNED8", {error: "a value is needed"}],
    ["  ", "REAL32", {error: "a value is needed"}],
    ["200", "VISIBLE_STRING", {value: "200"}],
    [" a name ", "VISIBLE_STRING", {value: " a name "}],
    ["", "VISIBLE_STRING", {value: ""}],
  ];
  for (const [text, type, expected] of cases) {
    assert.deepEqual(dictionary.parseInput(text, type), expected, `${JSON.stringify(text)} ${type}`);
  }
});

test("batches: at most 64 objects a request", () => {
  const objects = Array.from({length: 130}, (_, i) => `0x2000:${i}`);
  const pieces = chunks(objects);
  assert.deepEqual(pieces.map((p) => p.length), [64, 64, 2]);
  assert.deepEqual(pieces.flat(), objects);
  assert.deepEqual(chunks([]), []);
  assert.deepEqual(chunks(["a", "b", "c"], 2), [["a", "b"], ["c"]]);
});

test("ValuePoll: once a second, at once for something unread, never while a round is unanswered", () => {
  const poll = new dictionary.ValuePoll(1000);
  const shown = Array.from({length: 70}, (_, i) => `0x2000:${i}`);
  assert.deepEqual(poll.take(0, [], true), []); // nothing shown: nothing asked
  assert.deepEqual(poll.take(0, shown, true).map((b) => b.length), [64, 6]);
  assert.ok(poll.busy);
  assert.deepEqual(poll.take(5000, shown, true), []); // the round is unanswered
  poll.done();
  assert.deepEqual(poll.take(250, shown, false), []); // too soon
  assert.deepEqual(poll.take(250, shown.slice(0, 3), true), [shown.slice(0, 3)]); // a group expanded: at once
  poll.done();
  assert.deepEqual(poll.take(1000, shown, false), []);
  assert.deepEqual(poll.take(1250, shown, false).length, 2);
  poll.done();
  assert.ok(!poll.busy);
});
