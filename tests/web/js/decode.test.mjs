// web/decode.js: CAN frames read in CANopen terms, judged by the exact kind, node and text of each.
import {test} from "node:test";
import assert from "node:assert/strict";

import {EMCY_CLASSES, KINDS, abortTexts, bytesOf, decode, emcyClass, emcyCode, errorRegister} from "../../../web/decode.js";
import {needsServed, served} from "./served.mjs";

/** decode() of a frame from the bus (rx) or, with {dir: "tx", node}, of a node. */
function d(id, data, extra = {}) {
  return decode({id, data, rtr: false, dir: "rx", ...extra});
}

function text(id, data, extra = {}) {
  return d(id, data, extra).text;
}

test("the kinds the filter offers", () => {
  assert.deepEqual(KINDS, ["NMT", "SYNC", "EMCY", "TIME", "PDO", "SDO", "heartbeat", "LSS", "extended", "other"]);
});

test("bytesOf reads the events' hex", () => {
  assert.deepEqual([...bytesOf("00A1ff")], [0x00, 0xA1, 0xFF]);
  assert.deepEqual([...bytesOf("")], []);
});

test("NMT: the command and its target node, or all", () => {
  assert.deepEqual(d(0x000, "0100"), {kind: "NMT", node: null, text: "NMT start: all nodes"});
  assert.deepEqual(d(0x000, "0211"), {kind: "NMT", node: 17, text: "NMT stop: node 17"});
  assert.equal(text(0x000, "8010"), "NMT pre-operational: node 16");
  assert.equal(text(0x000, "8100"), "NMT reset node: all nodes");
  assert.equal(text(0x000, "827F"), "NMT reset communication: node 127");
  assert.equal(text(0x000, "0710"), "NMT command 0x07 (unknown): node 16");
  assert.deepEqual(d(0x000, "01"), {kind: "NMT", node: null, text: "NMT (2 bytes expected, 1 given)"});
});

test("SYNC, with its counter when it has one", () => {
  assert.deepEqual(d(0x080, ""), {kind: "SYNC", node: null, text: "SYNC"});
  assert.equal(text(0x080, "05"), "SYNC counter 5");
  assert.equal(text(0x080, "0102"), "SYNC (0 or 1 byte expected, 2 given)");
});

test("EMCY: the code with its CiA 301 class, the error register's bits, the manufacturer bytes", () => {
  assert.deepEqual(d(0x091, "3081110000000000", {dir: "tx", node: 17}),
    {kind: "EMCY", node: 17, text: "EMCY 0x8130 life guard error or heartbeat error, register 0x11 (generic, " +
      "communication), info 0000000000"});
  assert.equal(text(0x090, "2081110000000000"),
    "EMCY 0x8120 CAN in error passive mode, register 0x11 (generic, communication), info 0000000000");
  assert.equal(text(0x090, "4081110000000000"),
    "EMCY 0x8140 recovered from bus off, register 0x11 (generic, communication), info 0000000000");
  assert.equal(text(0x091, "005001A1B2C3D4E5"),
    "EMCY 0x5000 device hardware, register 0x01 (generic), info A1B2C3D4E5");
  assert.equal(text(0x0FF, "0000000000000000"), "EMCY 0x0000 error reset or no error, register 0x00, info 0000000000");
  assert.deepEqual(d(0x081, "1032050107000000"), {kind: "EMCY", node: 1,
    text: "EMCY 0x3210 voltage inside the device, register 0x05 (generic, voltage), info 0107000000"});
  assert.equal(text(0x081, "34FFFF"), "EMCY 0xFF34 device specific, register 0xFF (generic, current, voltage, " +
    "temperature, communication, device profile, bit 6, manufacturer), info ");
  assert.equal(text(0x081, "1200"), "EMCY (8 bytes expected, 2 given)");
});

test("EMCY classes: a code not listed takes its class; codes below 0x1000 but 0 are unknown", () => {
  const cases = [
    [0x0000, "error reset or no error"], [0x0012, null], [0x1000, "generic error"], [0x2310, "current, device output side"],
    [0x3110, "mains voltage"], [0x4210, "device temperature"], [0x5530, "device hardware"], [0x6101, "internal software"],
    [0x7000, "additional modules"], [0x8110, "CAN overrun (objects lost)"], [0x8150, "CAN-ID collision"],
    [0x8210, "PDO not processed due to length error"], [0x8250, "RPDO timeout"], [0x8299, "protocol error"],
    [0x8F00, "monitoring"], [0x9000, "external error"], [0xA000, null], [0xF001, "additional functions"],
    [0xFF00, "device specific"],
  ];
  for (const [code, name] of cases) {
    assert.equal(emcyClass(code), name, code.toString(16));
  }
  assert.equal(text(0x085, "1200000000000000"), "EMCY 0x0012 unknown code, register 0x00, info 0000000000");
  assert.equal(emcyCode(0x8130), "0x8130 life guard error or heartbeat error"); // the overview's too (format.js)
  assert.equal(emcyCode(0xA000), "0xA000 unknown code");
  assert.equal(EMCY_CLASSES.size, 35);
  assert.equal(errorRegister(0x80), "0x80 (manufacturer)");
});

test("TIME: the date and time of day it carries (UTC)", () => {
  // 12:34:56.789 = 45,296,789 ms; 2024-01-02 is 14,611 days after 1984-01-01
  const ms = 45_296_789;
  const days = 14_611;
  const data = [ms & 0xFF, (ms >> 8) & 0xFF, (ms >> 16) & 0xFF, ms >>> 24, days & 0xFF, days >> 8]
    .map((b) => b.toString(16).padStart(2, "0")).join("");
  assert.deepEqual(d(0x100, data), {kind: "TIME", node: null, text: "TIME 2024-01-02 12:34:56.789"});
  assert.equal(text(0x100, "000000000000"), "TIME 1984-01-01 00:00:00.000");
  assert.equal(text(0x100, "00"), "TIME (6 bytes expected, 1 given)");
});

test("PDOs of the predefined connection set by name and node, without a mapping", () => {
  const cases = [[0x191, "TPDO1"], [0x211, "RPDO1"], [0x291, "TPDO2"], [0x311, "RPDO2"], [0x391, "TPDO3"],
    [0x411, "RPDO3"], [0x491, "TPDO4"], [0x511, "RPDO4"]];
  for (const [id, name] of cases) {
    assert.deepEqual(d(id, "000000000F"), {kind: "PDO", node: 17, text: name}, id.toString(16));
  }
  assert.deepEqual(decode({id: 0x181, data: "", rtr: true, dir: "rx"}), {kind: "PDO", node: 1,
    text: "TPDO1 remote request"});
  assert.deepEqual(d(0x180, "00"), {kind: "other", node: null, text: ""}); // node-ID 0: no PDO of the set
});

test("a PDO its mapping knows: the lookup's name, node and values come first, on any COB-ID", () => {
  const seen = [];
  const lookup = (frame, bytes) => {
    seen.push([frame.id, [...bytes]]);
    return frame.id === 0x1A5 ? {name: "TPDO2", node: 20, text: "Flow=1.5 l/min"} : null;
  };
  assert.deepEqual(decode({id: 0x1A5, data: "0000C03F", dir: "tx", node: 20}, lookup),
    {kind: "PDO", node: 20, text: "TPDO2 Flow=1.5 l/min"});
  assert.deepEqual(seen, [[0x1A5, [0, 0, 0xC0, 0x3F]]]);
  assert.deepEqual(decode({id: 0x191, data: "", dir: "tx", node: 17}, () => ({name: "TPDO1", node: 17, text: ""})),
    {kind: "PDO", node: 17, text: "TPDO1"});
  assert.deepEqual(decode({id: 0x191, data: "00", dir: "tx", node: 17}, () => null), {kind: "PDO", node: 17,
    text: "TPDO1"});
});

test("SDO requests (client to server, 0x600 + node): every command specifier", () => {
  const cases = [
    ["4018100100000000", "SDO upload request 0x1018:01"],
    ["2B171000E8030000", "SDO download request 0x1017:00 expedited 2 bytes = 1000 (0x03E8)"],
    ["2F00620105000000", "SDO download request 0x6200:01 expedited 1 bytes = 5 (0x05)"],
    ["27011001FFFFFFFF", "SDO download request 0x1001:01 expedited 3 bytes = 16777215 (0xFFFFFF)"],
    ["2310180478563412", "SDO download request 0x1810:04 expedited 4 bytes = 305419896 (0x12345678)"],
    ["2210100100000080", "SDO download request 0x1010:01 expedited size not indicated = 2147483648 (0x80000000)"],
    ["210820000E000000", "SDO download request 0x2008:00 segmented 14 bytes"],
    ["200820000E000000", "SDO download request 0x2008:00 segmented size not indicated"],
    ["00414243444546FF", "SDO download segment toggle 0, 7 bytes"],
    ["1953445300000000", "SDO download segment toggle 1, 3 bytes \"SDS\", last"],
    ["1D00000000000000", "SDO download segment toggle 1, 1 bytes, last"],
    ["6000000000000000", "SDO upload segment request toggle 0"],
    ["7000000000000000", "SDO upload segment request toggle 1"],
    ["8018100100000206", "SDO abort 0x1018:01: 0x06020000"], // the abort texts have not come: the code alone
    ["A40820007F000000", "SDO block upload request 0x2008:00 block size 127, CRC"],
    ["A008200010000000", "SDO block upload request 0x2008:00 block size 16"],
    ["A100000000000000", "SDO block upload end response"],
    ["A2057F0000000000", "SDO block upload block response ackseq 5, block size 127"],
    ["A300000000000000", "SDO block upload start"],
    ["C6501F0100020000", "SDO block download request 0x1F50:01 512 bytes, CRC"],
    ["C0501F0100000000", "SDO block download request 0x1F50:01 size not indicated"],
    ["CD34120000000000", "SDO block download end request, 3 bytes not data, CRC 0x1234"],
    ["E000000000000000", "SDO command 0xE0 (unknown)"],
  ];
  for (const [data, expected] of cases) {
    assert.deepEqual(d(0x611, data), {kind: "SDO", node: 17, text: expected}, data);
  }
  assert.deepEqual(d(0x611, "4018"), {kind: "SDO", node: 17, text: "SDO (8 bytes expected, 2 given)"});
});

test("SDO responses (server to client, 0x580 + node): every command specifier", () => {
  const cases = [
    ["431810014E020000", "SDO upload response 0x1018:01 expedited 4 bytes = 590 (0x0000024E)"],
    ["4F00600105000000", "SDO upload response 0x6000:01 expedited 1 bytes = 5 (0x05)"],
    ["4B17100088130000", "SDO upload response 0x1017:00 expedited 2 bytes = 5000 (0x1388)"],
    ["4108100007000000", "SDO upload response 0x1008:00 segmented 7 bytes"],
    ["0953445300000000", "SDO upload segment toggle 0, 3 bytes \"SDS\", last"],
    ["1050726F2D496F6E", "SDO upload segment toggle 1, 7 bytes \"Pro-Ion\""],
    ["6017100000000000", "SDO download response 0x1017:00"],
    ["2000000000000000", "SDO download segment response toggle 0"],
    ["3000000000000000", "SDO download segment response toggle 1"],
    ["8000200011000906", "SDO abort 0x2000:00: 0x06090011"],
    ["8000200078563412", "SDO abort 0x2000:00: 0x12345678"],
    ["A4501F017F000000", "SDO block download response 0x1F50:01 block size 127, CRC"],
    ["A100000000000000", "SDO block download end response"],
    ["A27F7F0000000000", "SDO block download block response ackseq 127, block size 127"],
    ["A300000000000000", "SDO command 0xA3 (unknown)"],
    ["C608100007000000", "SDO block upload response 0x1008:00 7 bytes, CRC"],
    ["C9ABCD0000000000", "SDO block upload end request, 2 bytes not data, CRC 0xCDAB"],
    ["E000000000000000", "SDO command 0xE0 (unknown)"],
  ];
  for (const [data, expected] of cases) {
    assert.deepEqual(d(0x591, data, {dir: "tx", node: 17}), {kind: "SDO", node: 17, text: expected}, data);
  }
});

/** The data of an abort of 0x1000:00 with `code`. */
const abortData = (code) => "80001000" + [0, 8, 16, 24].map((s) => ((code >>> s) & 0xFF).toString(16).padStart(2, "0")).join("");

test("an abort's text is the one of the texts given, whichever codes they have; a code they lack is unknown", () => {
  const aborts = abortTexts([{code: 0x05030000, text: "toggle bit not alternated"}, {code: 0x0BAD0001, text: "new"}]);
  const sdo = {aborts};
  assert.equal(decode({id: 0x601, data: abortData(0x05030000), dir: "rx"}, undefined, sdo).text,
    "SDO abort 0x1000:00: 0x05030000 toggle bit not alternated");
  assert.equal(decode({id: 0x581, data: abortData(0x0BAD0001), dir: "tx", node: 1}, undefined, sdo).text,
    "SDO abort 0x1000:00: 0x0BAD0001 new");
  assert.equal(decode({id: 0x601, data: abortData(0x06020000), dir: "rx"}, undefined, sdo).text,
    "SDO abort 0x1000:00: 0x06020000 unknown abort code");
});

test("every served abort code shows the served text, both ways", needsServed, () => {
  const sdo = {aborts: abortTexts(served.aborts)};
  assert.ok(served.aborts.length > 0);
  for (const {code, text} of served.aborts) {
    const expected = `SDO abort 0x1000:00: 0x${code.toString(16).toUpperCase().padStart(8, "0")} ${text}`;
    assert.equal(decode({id: 0x601, data: abortData(code), dir: "rx"}, undefined, sdo).text, expected);
    assert.equal(decode({id: 0x581, data: abortData(code), dir: "tx", node: 1}, undefined, sdo).text, expected);
  }
  const codes = new Set(served.aborts.map((a) => a.code));
  const unknown = [0x12345678, 0, 0xFFFFFFFF].find((c) => !codes.has(c));
  assert.equal(decode({id: 0x601, data: abortData(unknown), dir: "rx"}, undefined, sdo).text,
    `SDO abort 0x1000:00: 0x${unknown.toString(16).toUpperCase().padStart(8, "0")} unknown abort code`);
});

test("expedited SDO values by the data type of their object: text, signed, float, boolean; else unsigned", () => {
  const types = new Map([[0x1008, "VISIBLE_STRING"], [0x2001, "INTEGER8"], [0x2002, "INTEGER16"], [0x2003, "INTEGER32"],
    [0x2004, "REAL32"], [0x2005, "BOOLEAN"], [0x2006, "UNSIGNED16"], [0x2007, "OCTET_STRING"], [0x2008, "INTEGER64"],
    [0x2009, "INTEGER24"]]);
  const asked = [];
  const type = (frame, node, index, sub) => {
    asked.push([frame.id, node, index, sub]);
    return types.get(index) ?? null;
  };
  const up = (data) => decode({id: 0x591, data, dir: "tx", node: 17}, undefined, {type}).text;
  const down = (data) => decode({id: 0x611, data, dir: "rx"}, undefined, {type}).text;
  assert.equal(up("4308100045533631"), "SDO upload response 0x1008:00 expedited 4 bytes = \"ES61\"");
  assert.deepEqual(asked, [[0x591, 17, 0x1008, 0]]);
  assert.equal(up("4F08100041000000"), "SDO upload response 0x1008:00 expedited 1 bytes = \"A\"");
  assert.equal(up("4208100053445300"), "SDO upload response 0x1008:00 expedited size not indicated = \"SDS\"");
  assert.equal(up("4F012000FB000000"), "SDO upload response 0x2001:00 expedited 1 bytes = -5 (0xFB)");
  assert.equal(up("4B022001FEFF0000"), "SDO upload response 0x2002:01 expedited 2 bytes = -2 (0xFFFE)");
  assert.equal(up("4202200018FC0000"), "SDO upload response 0x2002:00 expedited size not indicated = -1000 " +
    "(0x0000FC18)"); // the type's 2 bytes of the 4
  assert.equal(up("4303200000000080"), "SDO upload response 0x2003:00 expedited 4 bytes = -2147483648 (0x80000000)");
  assert.equal(up("430420000000C03F"), "SDO upload response 0x2004:00 expedited 4 bytes = 1.5 (0x3FC00000)");
  assert.equal(up("4F05200001000000"), "SDO upload response 0x2005:00 expedited 1 bytes = true (0x01)");
  assert.equal(up("4F05200000000000"), "SDO upload response 0x2005:00 expedited 1 bytes = false (0x00)");
  assert.equal(up("4B062000FFFF0000"), "SDO upload response 0x2006:00 expedited 2 bytes = 65535 (0xFFFF)");
  assert.equal(up("4B072000FFFF0000"), "SDO upload response 0x2007:00 expedited 2 bytes = 65535 (0xFFFF)");
  assert.equal(up("43082000FFFFFFFF"), "SDO upload response 0x2008:00 expedited 4 bytes = 4294967295 (0xFFFFFFFF)");
  assert.equal(up("4709200000008000"), "SDO upload response 0x2009:00 expedited 3 bytes = -8388608 (0x800000)");
  assert.equal(up("4B022001FE000000").endsWith("= 254 (0x00FE)"), true); // 0x2002 is 16 bits: positive
  assert.equal(up("4F02200180000000"), "SDO upload response 0x2002:01 expedited 1 bytes = 128 (0x80)"); // too short
  assert.equal(up("4300300045533631"), "SDO upload response 0x3000:00 expedited 4 bytes = 825643845 (0x31365345)");
  // a download request to node 17: the same lookup, of the node it goes to
  asked.length = 0;
  assert.equal(down("2B022000F6FF0000"), "SDO download request 0x2002:00 expedited 2 bytes = -10 (0xFFF6)");
  assert.deepEqual(asked, [[0x611, 17, 0x2002, 0]]);
  assert.equal(down("2F052000FF000000"), "SDO download request 0x2005:00 expedited 1 bytes = true (0xFF)");
});

test("heartbeat, boot-up, node guarding", () => {
  assert.deepEqual(d(0x711, "00", {dir: "tx", node: 17}), {kind: "heartbeat", node: 17, text: "boot-up"});
  assert.equal(text(0x711, "04"), "heartbeat: stopped");
  assert.equal(text(0x711, "05"), "heartbeat: operational");
  assert.equal(text(0x711, "7F"), "heartbeat: pre-operational");
  assert.equal(text(0x711, "12"), "heartbeat: state 0x12 (unknown)");
  assert.deepEqual(decode({id: 0x711, data: "", rtr: true, dir: "rx"}),
    {kind: "heartbeat", node: 17, text: "node guarding request"});
  assert.equal(text(0x711, "85"), "node guarding answer: operational, toggle 1");
  assert.equal(text(0x711, "7F", {guarded: true}), "node guarding answer: pre-operational, toggle 0");
  assert.equal(text(0x711, "FF", {guarded: true}), "node guarding answer: pre-operational, toggle 1");
  assert.equal(text(0x711, ""), "heartbeat (1 byte expected, 0 given)");
  assert.deepEqual(d(0x700, "05"), {kind: "other", node: null, text: ""});
});

test("LSS requests of the master (0x7E5)", () => {
  const cases = [
    ["0401000000000000", "LSS switch state global: configuration"],
    ["0400000000000000", "LSS switch state global: waiting"],
    ["0407000000000000", "LSS switch state global: mode 0x07 (unknown)"],
    ["402E010000000000", "LSS switch state selective vendor-ID 0x0000012E"],
    ["4101000000000000", "LSS switch state selective product code 0x00000001"],
    ["4202000000000000", "LSS switch state selective revision number 0x00000002"],
    ["4378563412000000", "LSS switch state selective serial number 0x12345678"],
    ["1110000000000000", "LSS configure node-ID 16"],
    ["1300020000000000", "LSS configure bit timing table 0 index 2 (500 kbit/s)"],
    ["1300050000000000", "LSS configure bit timing table 0 index 5 (reserved)"],
    ["1300090000000000", "LSS configure bit timing table 0 index 9 (automatic bit rate detection)"],
    ["1301030000000000", "LSS configure bit timing table 1 index 3"],
    ["1564000000000000", "LSS activate bit timing, switch delay 100 ms"],
    ["1700000000000000", "LSS store configuration"],
    ["5A00000000000000", "LSS inquire identity vendor-ID"],
    ["5B00000000000000", "LSS inquire identity product code"],
    ["5C00000000000000", "LSS inquire identity revision number"],
    ["5D00000000000000", "LSS inquire identity serial number"],
    ["5E00000000000000", "LSS inquire node-ID"],
    ["462E010000000000", "LSS identify remote slave vendor-ID 0x0000012E"],
    ["4701000000000000", "LSS identify remote slave product code 0x00000001"],
    ["4800000000000000", "LSS identify remote slave revision number low 0x00000000"],
    ["49FFFFFFFF000000", "LSS identify remote slave revision number high 0xFFFFFFFF"],
    ["4A00000000000000", "LSS identify remote slave serial number low 0x00000000"],
    ["4BFFFFFFFF000000", "LSS identify remote slave serial number high 0xFFFFFFFF"],
    ["4C00000000000000", "LSS identify non-configured remote slave"],
    ["5100000000800000", "LSS fastscan reset"],
    ["512E0100001F0000", "LSS fastscan ID 0x0000012E bit 31, vendor-ID, next vendor-ID"],
    ["5100000000000301", "LSS fastscan ID 0x00000000 bit 0, serial number, next product code"],
    ["9900000000000000", "LSS command 0x99 (unknown)"],
  ];
  for (const [data, expected] of cases) {
    assert.deepEqual(d(0x7E5, data), {kind: "LSS", node: null, text: expected}, data);
  }
  assert.equal(text(0x7E5, "04"), "LSS (8 bytes expected, 1 given)");
});

test("LSS answers of the slaves (0x7E4)", () => {
  const cases = [
    ["4400000000000000", "LSS switch state selective response"],
    ["1100000000000000", "LSS configure node-ID response: success"],
    ["1101000000000000", "LSS configure node-ID response: node-ID out of range"],
    ["11FF050000000000", "LSS configure node-ID response: manufacturer-specific error 0x05"],
    ["1300000000000000", "LSS configure bit timing response: success"],
    ["1301000000000000", "LSS configure bit timing response: bit timing not supported"],
    ["1700000000000000", "LSS store configuration response: success"],
    ["1701000000000000", "LSS store configuration response: store not supported"],
    ["1702000000000000", "LSS store configuration response: storage media access error"],
    ["1703000000000000", "LSS store configuration response: error 3"],
    ["5A2E010000000000", "LSS inquire identity vendor-ID response 0x0000012E"],
    ["5D21000000000000", "LSS inquire identity serial number response 0x00000021"],
    ["5E10000000000000", "LSS inquire node-ID response 16"],
    ["4F00000000000000", "LSS identify slave response"],
    ["5000000000000000", "LSS identify non-configured slave response"],
    ["9900000000000000", "LSS response 0x99 (unknown)"],
  ];
  for (const [data, expected] of cases) {
    assert.deepEqual(d(0x7E4, data, {dir: "tx", node: 16}), {kind: "LSS", node: null, text: expected}, data);
  }
});

test("other COB-IDs are shown raw: no text, the sender as the node", () => {
  assert.deepEqual(d(0x123, "DEADBEEF"), {kind: "other", node: null, text: ""});
  assert.deepEqual(d(0x7E6, "00", {dir: "tx", node: 5}), {kind: "other", node: 5, text: ""});
  assert.deepEqual(d(0x580, "4018100100000000"), {kind: "other", node: null, text: ""}); // node-ID 0
});

test("an extended (29-bit) frame is never read as CANopen, whatever its identifier", () => {
  const extended = {kind: "extended", node: null, text: ""};
  assert.deepEqual(d(0x1234567, "01", {eff: true}), extended);
  assert.deepEqual(d(0x1234567, "01"), extended); // above 11 bits: extended even unmarked
  assert.deepEqual(d(0x181, "1122", {eff: true}), extended); // not TPDO1 of node 1
  assert.deepEqual(d(0x000, "0100", {eff: true}), extended); // not an NMT start
  assert.deepEqual(d(0x711, "", {eff: true, rtr: true}), extended); // not a node guarding request
  assert.deepEqual(d(0x591, "431810014E020000", {eff: true}), extended); // not an SDO answer
  assert.deepEqual(d(0x7E5, "0401000000000000", {eff: true}), extended); // not LSS
  // a node's mapping that names this COB-ID is not asked: its PDOs are 11-bit frames
  let asked = 0;
  const pdo = () => { asked++; return {name: "TPDO1", node: 1, text: "A=1"}; };
  assert.deepEqual(decode({id: 0x181, data: "11", rtr: false, eff: true, dir: "rx"}, pdo), extended);
  assert.equal(asked, 0);
  assert.equal(decode({id: 0x181, data: "11", rtr: false, dir: "rx"}, pdo).kind, "PDO"); // the 11-bit one is
});
