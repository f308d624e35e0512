// web/tracelog.js: the trace's frames (decoded as they come, bounded), its filter, and the texts of a row.
import {test} from "node:test";
import assert from "node:assert/strict";

import {CAPACITY, COLUMNS, TraceLog, cells, parseFilter, sinceStart, wallClock} from "../../../web/tracelog.js";

let time = 1_000_000;
/** A frame event as the emulator sends it. */
function ev(id, data, extra = {}) {
  time += 1000;
  return {event: "frame", time_us: time, bus: "vcan0", dir: "rx", id, data, ...extra};
}

test("the columns and the bound", () => {
  assert.deepEqual(COLUMNS.map((c) => c.title), ["time", "bus", "dir", "COB-ID", "node", "kind", "decoded", "data"]);
  assert.equal(CAPACITY, 20_000);
});

test("a frame is decoded as it comes, numbered, and kept", () => {
  const log = new TraceLog(10);
  const entry = log.add(ev(0x611, "4018100100000000"));
  assert.deepEqual(entry, {seq: 1, time_us: time, bus: "vcan0", dir: "rx", node: null, id: 0x611,
    data: "4018100100000000", rtr: false, eff: false, guarded: false, kind: "SDO", about: 17,
    text: "SDO upload request 0x1018:01"});
  const answer = log.add(ev(0x591, "431810014E020000", {dir: "tx", node: 17, device: "sds"}));
  assert.equal(answer.text, "SDO upload response 0x1018:01 expedited 4 bytes = 590 (0x0000024E)");
  assert.equal(answer.node, 17);
  assert.equal(log.newest, 2);
  assert.deepEqual([...log.ring].map((e) => e.seq), [1, 2]);
});

test("a node guarding answer is told by the request before it", () => {
  const log = new TraceLog(10);
  assert.equal(log.add(ev(0x711, "", {rtr: true})).text, "node guarding request");
  assert.equal(log.add(ev(0x711, "7F", {dir: "tx", node: 17})).text, "node guarding answer: pre-operational, toggle 0");
  assert.equal(log.add(ev(0x711, "7F", {dir: "tx", node: 17})).text, "heartbeat: pre-operational"); // not asked
  log.add(ev(0x712, "", {rtr: true}));
  assert.equal(log.add(ev(0x712, "7F", {bus: "vcan1", dir: "tx", node: 18})).text, "heartbeat: pre-operational");
});

test("an extended frame: 8 digits, kind extended, no PDO lookup, no guarding toggle, found by its candump text", () => {
  let lookups = 0;
  const log = new TraceLog(10, (frame) => {
    lookups++;
    return frame.id === 0x181 ? {name: "TPDO1", node: 1, text: "A=1"} : null;
  });
  const ext = log.add(ev(0x181, "1122", {eff: true}));
  assert.deepEqual({kind: ext.kind, about: ext.about, text: ext.text, eff: ext.eff}, {kind: "extended", about: null,
    text: "", eff: true});
  assert.equal(lookups, 0); // the PDO mapping is not asked, so its values never come from this frame's bytes
  assert.deepEqual(cells(ext), {time: sinceStart(ext.time_us), bus: "vcan0", dir: "rx", id: "00000181", node: "",
    kind: "extended", text: "", data: "11 22"});
  const pdo = log.add(ev(0x181, "1122"));
  assert.deepEqual([pdo.kind, pdo.text, cells(pdo).id], ["PDO", "TPDO1 A=1", "181"]);
  assert.equal(lookups, 1);
  assert.equal(log.redecode("vcan0"), false); // redecoding leaves it extended
  assert.equal(ext.kind, "extended");
  const texts = (filter) => log.lastMatching(parseFilter(filter).match, 10).map((e) => `${e.kind} ${e.eff}`);
  assert.deepEqual(texts({kind: "extended"}), ["extended true"]);
  assert.deepEqual(texts({text: "00000181#1122"}), ["extended true"]);
  assert.deepEqual(texts({kind: "PDO"}), ["PDO false"]);
  assert.deepEqual(texts({node: "1"}), ["PDO false"]);
  // an extended remote frame 0x711 is no guard request: the 11-bit answer after it is a heartbeat
  log.add(ev(0x711, "", {rtr: true, eff: true}));
  assert.equal(log.add(ev(0x711, "7F", {dir: "tx", node: 17})).text, "heartbeat: pre-operational");
});

test("since() gives what came after a seq, as far as the ring still has it", () => {
  const log = new TraceLog(3);
  for (let i = 0; i < 5; i++) {
    log.add(ev(0x080, ""));
  }
  assert.deepEqual(log.since(3).map((e) => e.seq), [4, 5]);
  assert.deepEqual(log.since(0).map((e) => e.seq), [3, 4, 5]); // 1 and 2 were pushed out
  assert.deepEqual(log.since(5), []);
  assert.equal(log.ring.dropped, 2);
  log.clear();
  assert.deepEqual(log.since(0), []);
  assert.equal(log.add(ev(0x080, "")).seq, 6); // numbers go on: a row drawn before the clear is never matched again
});

test("the filter: kind, node, text in any case; bad input says why", () => {
  const log = new TraceLog(100);
  log.add(ev(0x000, "0100"));
  log.add(ev(0x611, "4018100100000000"));
  log.add(ev(0x591, "431810014E020000", {dir: "tx", node: 17}));
  log.add(ev(0x712, "05", {dir: "tx", node: 18}));
  log.add(ev(0x091, "3081110000000000", {dir: "tx", node: 17}));
  const texts = (filter) => log.lastMatching(parseFilter(filter).match, 100).map((e) => e.text);
  assert.equal(texts({}).length, 5);
  assert.deepEqual(texts({kind: "SDO"}), ["SDO upload request 0x1018:01",
    "SDO upload response 0x1018:01 expedited 4 bytes = 590 (0x0000024E)"]);
  assert.deepEqual(texts({node: "18"}), ["heartbeat: operational"]);
  assert.deepEqual(texts({node: "0x11", kind: "EMCY"}), [
    "EMCY 0x8130 life guard error or heartbeat error, register 0x11 (generic, communication), info 0000000000"]);
  assert.deepEqual(texts({text: "upload RESPONSE"}), ["SDO upload response 0x1018:01 expedited 4 bytes = 590 (0x0000024E)"]);
  assert.deepEqual(texts({text: "712#05"}), ["heartbeat: operational"]); // COB-ID#data as candump writes it
  assert.deepEqual(texts({text: "nmt"}), ["NMT start: all nodes"]);
  assert.deepEqual(texts({text: "  "}).length, 5);
  assert.deepEqual(parseFilter({node: "200"}), {match: null, error: "node: \"200\" is not a node-ID (1 to 127)"});
  assert.deepEqual(parseFilter({node: "x"}), {match: null, error: "node: \"x\" is not a node-ID (1 to 127)"});
  assert.deepEqual(parseFilter({node: "0"}).error, "node: \"0\" is not a node-ID (1 to 127)");
  assert.match(parseFilter({kind: "CAN"}).error, /^kind: CAN is not one of NMT, SYNC/);
});

test("lastMatching gives the newest that match, oldest first, at most the limit", () => {
  const log = new TraceLog(100);
  for (let i = 0; i < 10; i++) {
    log.add(ev(0x080, i.toString(16).padStart(2, "0")));
  }
  const odd = (e) => parseInt(e.data, 16) % 2 === 1;
  assert.deepEqual(log.lastMatching(odd, 3).map((e) => e.text), ["SYNC counter 5", "SYNC counter 7", "SYNC counter 9"]);
  assert.deepEqual(log.lastMatching(() => false, 3), []);
});

test("redecode: PDOs seen before their mapping was read get their values", () => {
  let mapped = false;
  const log = new TraceLog(10, (frame) => (mapped && frame.id === 0x191 ? {name: "TPDO1", node: 17, text: "A=1"} : null));
  const before = log.add(ev(0x191, "01", {dir: "tx", node: 17}));
  const other = log.add(ev(0x191, "01", {bus: "vcan1", dir: "tx", node: 17}));
  assert.equal(before.text, "TPDO1");
  assert.equal(log.redecode("vcan0"), false); // the mapping has not come: nothing changed
  mapped = true;
  assert.equal(log.redecode("vcan0"), true);
  assert.equal(before.text, "TPDO1 A=1");
  assert.equal(other.text, "TPDO1"); // another bus: not this one's mapping
});

test("redecode: SDO values get their type as the node's dictionary comes; aborts their text as the texts come", () => {
  let types = null; // the dictionary of node 17 on vcan0, once read
  const log = new TraceLog(10, undefined, (frame, node, index, sub) =>
    (types !== null && frame.bus === "vcan0" && node === 17 ? types.get(`${index}:${sub}`) ?? null : null));
  const name = log.add(ev(0x591, "4308100045533631", {dir: "tx", node: 17}));
  const other = log.add(ev(0x591, "4308100045533631", {bus: "vcan1", dir: "tx", node: 17}));
  const abort = log.add(ev(0x591, "8008100000000206", {dir: "tx", node: 17}));
  assert.equal(name.text, "SDO upload response 0x1008:00 expedited 4 bytes = 825643845 (0x31365345)");
  assert.equal(abort.text, "SDO abort 0x1008:00: 0x06020000");
  types = new Map([["4104:0", "VISIBLE_STRING"]]);
  assert.equal(log.redecode("vcan0"), true);
  assert.equal(name.text, "SDO upload response 0x1008:00 expedited 4 bytes = \"ES61\"");
  assert.equal(other.text, "SDO upload response 0x1008:00 expedited 4 bytes = 825643845 (0x31365345)");
  assert.deepEqual(log.lastMatching(parseFilter({text: "es61"}).match, 10), [name]); // found by its new text
  assert.equal(log.useAbortTexts(new Map([[0x06020000, "object does not exist"]])), true);
  assert.equal(abort.text, "SDO abort 0x1008:00: 0x06020000 object does not exist");
  assert.equal(log.add(ev(0x591, "8008100000000206", {dir: "tx", node: 17})).text, abort.text); // and those to come
  assert.equal(log.useAbortTexts(new Map([[0x06020000, "object does not exist"]])), false); // nothing changed
});

test("a row's texts; the time since the start or by the wall clock", () => {
  const log = new TraceLog(10);
  const entry = log.add({event: "frame", time_us: 12_345_678, bus: "vcan0", dir: "tx", node: 17, id: 0x591,
    data: "431810014E020000"});
  assert.deepEqual(cells(entry), {time: "12.345", bus: "vcan0", dir: "tx", id: "591", node: "17", kind: "SDO",
    text: "SDO upload response 0x1018:01 expedited 4 bytes = 590 (0x0000024E)", data: "43 18 10 01 4E 02 00 00"});
  const rtr = log.add({event: "frame", time_us: 5, bus: "vcan0", dir: "rx", id: 0x711, data: "", rtr: true});
  assert.deepEqual(cells(rtr), {time: "0.000", bus: "vcan0", dir: "rx", id: "711", node: "17", kind: "heartbeat",
    text: "node guarding request", data: "remote request"});
  const nmt = log.add({event: "frame", time_us: 5, bus: "vcan0", dir: "rx", id: 0, data: "0100"});
  assert.equal(cells(nmt).node, "");
  const clock = {time_us: 2_345_678, unix_us: new Date(2024, 0, 2, 14, 3, 7, 250).getTime() * 1000};
  assert.equal(cells(entry, {wall: true, clock}).time, "14:03:17.250");
  assert.equal(cells(entry, {wall: true, clock: null}).time, "12.345"); // hello's clock not there yet
  assert.equal(sinceStart(0), "0.000");
  assert.equal(sinceStart(3_600_000_999), "3600.000");
  assert.equal(wallClock(new Date(2024, 0, 2, 0, 0, 5, 7).getTime() * 1000), "00:00:05.007");
});
