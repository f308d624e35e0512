// web/tpdo.js: the objects a node's TPDOs map, from its mapping parameters as get reads them.
import {test} from "node:test";
import assert from "node:assert/strict";

import {chunks, objectName, parseObject} from "../../../web/objects.js";
import {mappedObjects, mappingCounts, mappingEntries} from "../../../web/tpdo.js";

test("objects are written 0xIIII:SS and read in the command language's forms", () => {
  assert.equal(objectName(0x6401, 1), "0x6401:01");
  assert.equal(objectName(0x1A00, 0), "0x1A00:00");
  assert.deepEqual(parseObject("0x6401:01"), {index: 0x6401, sub: 1});
  assert.deepEqual(parseObject("6401:1"), {index: 0x6401, sub: 1});
  assert.deepEqual(parseObject(" 0x1017 "), {index: 0x1017, sub: 0});
  assert.deepEqual(parseObject("1a00:0x0A"), {index: 0x1A00, sub: 10});
  for (const bad of ["", "0x12345", "6401:100", "volts", "0x6401:", ":1"]) {
    assert.equal(parseObject(bad), null, bad);
  }
});

test("chunks of at most 64 objects (one get each)", () => {
  const list = Array.from({length: 130}, (_, i) => i);
  assert.deepEqual(chunks(list).map((c) => c.length), [64, 64, 2]);
  assert.deepEqual(chunks([]), []);
  assert.deepEqual(chunks([1, 2, 3], 2), [[1, 2], [3]]);
});

test("the mapping parameters' counts, from the objects rows", () => {
  const rows = ["0x1800:01", "0x1A00:00", "0x1A00:01", "0x1A01:00", "0x1A03:00", "0x1BFF:00", "0x1C00:00", "0x6401:01"]
    .map((object) => ({object}));
  assert.deepEqual(mappingCounts(rows), ["0x1A00:00", "0x1A01:00", "0x1A03:00", "0x1BFF:00"]);
});

test("the entries to read: sub 1..count of each mapping; an unreadable count maps nothing", () => {
  assert.deepEqual(mappingEntries([
    {object: "0x1A00:00", value: 2, type: "UNSIGNED8"},
    {object: "0x1A01:00", value: 0, type: "UNSIGNED8"},
    {object: "0x1A02:00", error: "object does not exist (0x06020000)"},
    {object: "0x1A03:00", value: 1, type: "UNSIGNED8"},
  ]), ["0x1A00:01", "0x1A00:02", "0x1A03:01"]);
});

test("the mapped objects in mapping order, each once, without dummy entries", () => {
  assert.deepEqual(mappedObjects([
    {object: "0x1A00:01", value: 0x60000108, type: "UNSIGNED32"},
    {object: "0x1A00:02", value: 0x00050008, type: "UNSIGNED32"}, // dummy: UNSIGNED8 padding
    {object: "0x1A00:03", value: 0x64010110, type: "UNSIGNED32"},
    {object: "0x1A01:01", value: 0x60000108, type: "UNSIGNED32"}, // again in another TPDO
    {object: "0x1A01:02", error: "no data available (0x08000024)"},
    {object: "0x1A02:01", value: 0x25000120, type: "UNSIGNED32"}, // a REAL32 of 32 bits
    {object: "0x1A02:02", value: 0xFFFFFF08, type: "UNSIGNED32"},
  ]), ["0x6000:01", "0x6401:01", "0x2500:01", "0xFFFF:FF"]);
});
