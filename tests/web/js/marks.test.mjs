// web/marks.js: EMCYs and NMT changes as marks of the plots' time axis.
import {test} from "node:test";
import assert from "node:assert/strict";

import {Marks, markOf} from "../../../web/marks.js";

function event(kind, node, timeUs, fields = {}) {
  return {event: kind, time_us: timeUs, bus: "vcan0", node, device: "sds", text: "", ...fields};
}

test("an EMCY is marked by its code, an NMT change by the state it went to; other events are no mark", () => {
  assert.deepEqual(markOf(event("emcy", 16, 2_500_000, {code: 0x5000, register: 1, info: "A1B2C3D4E5"})),
    {t: 2.5, kind: "emcy", label: "EMCY 0x5000"});
  assert.deepEqual(markOf(event("emcy", 16, 0, {code: 0x10, register: 1, info: "0000000000"})),
    {t: 0, kind: "emcy", label: "EMCY 0x0010"});
  assert.deepEqual(markOf(event("nmt", 17, 1_000_000, {from: "PRE-OPERATIONAL", to: "OPERATIONAL"})),
    {t: 1, kind: "nmt", label: "OPERATIONAL"});
  for (const kind of ["boot-up", "fault", "heartbeat", "frame"]) {
    assert.equal(markOf(event(kind, 16, 1)), null);
  }
});

test("marks by node (bus and node-ID), in a time range", () => {
  const marks = new Marks();
  marks.event(event("nmt", 16, 1_000_000, {to: "OPERATIONAL"}));
  marks.event(event("emcy", 16, 2_000_000, {code: 0x3210}));
  marks.event(event("emcy", 17, 2_000_000, {code: 0x5000}));
  marks.event({...event("emcy", 16, 3_000_000, {code: 0x1000}), bus: "vcan1"});
  marks.event(event("boot-up", 16, 4_000_000));
  marks.event({event: "interface", time_us: 5, bus: "vcan0", text: "up"}); // no node
  assert.deepEqual(marks.between("vcan0/16", 0, 10).map((m) => m.label), ["OPERATIONAL", "EMCY 0x3210"]);
  assert.deepEqual(marks.between("vcan0/16", 1.5, 2).map((m) => m.label), ["EMCY 0x3210"]);
  assert.deepEqual(marks.between("vcan0/17", 0, 10).map((m) => m.label), ["EMCY 0x5000"]);
  assert.deepEqual(marks.between("vcan1/16", 0, 10).map((m) => m.label), ["EMCY 0x1000"]);
  assert.deepEqual(marks.between("vcan0/18", 0, 10), []);
});

test("a node keeps its newest marks only", () => {
  const marks = new Marks(3);
  for (let i = 1; i <= 5; i++) {
    marks.event(event("emcy", 16, i * 1e6, {code: i}));
  }
  assert.deepEqual(marks.between("vcan0/16", 0, 10).map((m) => m.t), [3, 4, 5]);
});
