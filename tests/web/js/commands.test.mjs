// web/commands.js: the forms made from the usage lines of `help NODE`, and the arguments they send.
import {test} from "node:test";
import assert from "node:assert/strict";

import {NODE_COMMANDS, PROTOCOL_FAULTS, argsOf, faultsInForce, parseUsage} from "../../../web/commands.js";

const input = (name, hint = name, optional = false) => ({kind: "input", name, hint, optional});

test("parseUsage: the command, its arguments, literal words and alternatives", () => {
  assert.deepEqual(parseUsage("status"), [{command: "status", usage: "status", words: []}]);
  assert.deepEqual(parseUsage("pollution PERCENT")[0].words, [input("PERCENT")]);
  assert.deepEqual(parseUsage("air UA_PER_KV")[0].words, [input("UA_PER_KV")]);
  assert.deepEqual(parseUsage("hw-release on|off")[0].words, [{kind: "choice", options: ["on", "off"], optional: false}]);
  assert.deepEqual(parseUsage("keypad release on|off"), [{command: "keypad", usage: "keypad release on|off", words: [
    {kind: "fixed", text: "release"}, {kind: "choice", options: ["on", "off"], optional: false}]}]);
  assert.deepEqual(parseUsage("mode auto|hand|flashing")[0].words,
    [{kind: "choice", options: ["auto", "hand", "flashing"], optional: false}]);
  // an argument or a word: a text field that says both
  assert.deepEqual(parseUsage("load N MW|short")[0].words, [input("N"), input("MW|short", "MW or short")]);
  assert.deepEqual(parseUsage("speed N RPM|off")[0].words, [input("N"), input("RPM|off", "RPM or off")]);
  assert.deepEqual(parseUsage("sensor D1..D10|A1|A2 STATE")[0].words,
    [input("D1..D10|A1|A2", "D1..D10, A1 or A2"), input("STATE")]);
});

test("parseUsage: optional arguments from the first [ on", () => {
  assert.deepEqual(parseUsage("efield N VOLT [RIPPLE]")[0].words,
    [input("N"), input("VOLT"), input("RIPPLE", "RIPPLE", true)]);
  assert.deepEqual(parseUsage("error CODE [STATE]")[0].words, [input("CODE"), input("STATE", "STATE", true)]);
  assert.deepEqual(parseUsage("sdo-ignore [N|P%] [SEED]")[0].words,
    [input("N|P%", "N or P%", true), input("SEED", "SEED", true)]);
  assert.deepEqual(parseUsage("sdo-abort INDEX[:SUB] CODE")[0].words, [input("INDEX[:SUB]"), input("CODE")]);
});

test("parseUsage: two commands on one line", () => {
  assert.deepEqual(parseUsage("error CODE / warning CODE"), [
    {command: "error", usage: "error CODE", words: [input("CODE")]},
    {command: "warning", usage: "warning CODE", words: [input("CODE")]},
  ]);
});

test("argsOf: fixed words in place, values trimmed, optional ones left out at the end", () => {
  const keypad = parseUsage("keypad release on|off")[0].words;
  assert.deepEqual(argsOf(keypad, ["on"]), {args: ["release", "on"]});
  const efield = parseUsage("efield N VOLT [RIPPLE]")[0].words;
  assert.deepEqual(argsOf(efield, [" 1", "3000 ", ""]), {args: ["1", "3000"]});
  assert.deepEqual(argsOf(efield, ["1", "3000", "20"]), {args: ["1", "3000", "20"]});
  assert.deepEqual(argsOf([], []), {args: []});
});

test("argsOf: what cannot be sent is said, not sent", () => {
  const efield = parseUsage("efield N VOLT [RIPPLE]")[0].words;
  assert.deepEqual(argsOf(efield, ["1", "", ""]), {error: "VOLT is needed"});
  assert.deepEqual(argsOf(efield, ["1", "30 00", ""]), {error: "VOLT: one word, without blanks"});
  const emcy = parseUsage(NODE_COMMANDS[1].usage)[0].words;
  assert.deepEqual(argsOf(emcy, ["0x5000", "", "0xA1", "", "", "", ""]), {error: "B0 needs REG before it"});
  assert.deepEqual(argsOf(emcy, ["0x5000", "0x01", "0xA1", "", "", "", ""]), {args: ["0x5000", "0x01", "0xA1"]});
  const mode = parseUsage("mode auto|hand|flashing")[0].words;
  assert.deepEqual(argsOf(mode, [""]), {error: "auto|hand|flashing is needed"});
});

test("the node's commands and the protocol faults parse to forms", () => {
  assert.deepEqual(NODE_COMMANDS.map((c) => parseUsage(c.usage)[0].command), ["power-cycle", "emcy", "emcy-clear"]);
  assert.deepEqual(PROTOCOL_FAULTS.map((f) => parseUsage(f.usage)[0].command), ["sdo-ignore", "sdo-delay",
    "sdo-abort", "heartbeat-stop", "heartbeat-jitter", "heartbeat-state", "tpdo-freeze", "tpdo-drop", "tpdo-length",
    "emcy-burst", "reboot", "bus-off", "lss-silent"]); // the kinds `fault NODE` lists
  assert.ok(PROTOCOL_FAULTS.every((f) => parseUsage(f.usage).length === 1));
});

test("faultsInForce: the overview's faults cell as a list", () => {
  assert.deepEqual(faultsInForce(""), []);
  assert.deepEqual(faultsInForce("heartbeat-stop"), ["heartbeat-stop"]);
  assert.deepEqual(faultsInForce("heartbeat-stop, sdo-delay"), ["heartbeat-stop", "sdo-delay"]);
});
