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
    .map(dictionary.valueText), ["590", "-3", "24.5", "true", "false", "ES61", "0A1B", "nan", "18446744073709551615", "",
    ""]);
  assert.equal(dictionary.hexHint(590, "UNSIGNED32"), "0x0000024E");
  assert.equal(dictionary.hexHint(5, "UNSIGNED8"), "0x05");
  assert.equal(dictionary.hexHint(1000, "UNSIGNED16"), "0x03E8");
  assert.equal(dictionary.hexHint(-1, "INTEGER16"), "");
  assert.equal(dictionary.hexHint(24.5, "REAL32"), "");
  assert.equal(dictionary.hexHint("ES61", "VISIBLE_STRING"), "");
  assert.equal(dictionary.hexHint("18446744073709551615", "UNSIGNED64"), "");
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
