// web/commands.js: the forms made from the usage lines of `help NODE` and of the served kinds of fault, and the
// arguments they send.
import {test} from "node:test";
import assert from "node:assert/strict";

import {NODE_COMMANDS, argsOf, faultForms, faultsInForce, parseUsage} from "../../../web/commands.js";
import {needsServed, served} from "./served.mjs";

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
  // blanks around "|" do not count; a bracket inside one: optional from there on, as any other
  const ignore = [input("N|P%", "N or P%", true), input("SEED", "SEED", true)];
  assert.deepEqual(parseUsage("sdo-ignore [N | P% [SEED]]")[0].words, ignore);
  assert.deepEqual(parseUsage("sdo-ignore [N|P% [SEED]]")[0].words, ignore);
  assert.deepEqual(parseUsage("mode auto | hand")[0].words, [{kind: "choice", options: ["auto", "hand"], optional: false}]);
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

test("the node's commands parse to forms", () => {
  assert.deepEqual(NODE_COMMANDS.map((c) => parseUsage(c.usage)[0].command), ["power-cycle", "emcy", "emcy-clear"]);
  assert.ok(NODE_COMMANDS.every((c) => parseUsage(c.usage).length === 1));
});

test("faultForms: a form per served kind of fault, in its order, whatever the kind", () => {
  const forms = faultForms([
    {kind: "wire-cut", usage: "wire-cut MS [SIDE|both]", limits: "MS 1..100", text: "the wire is cut for MS ms"},
    {kind: "nap", usage: "nap", limits: "", text: "the node naps"},
  ]);
  assert.deepEqual(forms, [
    {kind: "wire-cut", parsed: {command: "wire-cut", usage: "wire-cut MS [SIDE|both]",
      words: [input("MS"), input("SIDE|both", "SIDE or both", true)]}, text: "the wire is cut for MS ms (MS 1..100)"},
    {kind: "nap", parsed: {command: "nap", usage: "nap", words: []}, text: "the node naps"},
  ]);
  assert.deepEqual(argsOf(forms[0].parsed.words, ["20", ""]), {args: ["20"]});
});

test("the served kinds of fault each make one form of their kind, with their text", needsServed, () => {
  const forms = faultForms(served.faults);
  assert.ok(served.faults.length > 0);
  assert.deepEqual(forms.map((f) => f.kind), served.faults.map((f) => f.kind));
  for (const [i, f] of served.faults.entries()) {
    assert.deepEqual(parseUsage(f.usage).map((p) => p.command), [f.kind], f.usage); // one command, the kind's
    assert.ok(f.text.length > 0, f.kind);
    assert.equal(forms[i].text, f.limits === "" ? f.text : `${f.text} (${f.limits})`);
    // every word of the usage but the kind is an argument the form asks for: none is sent as a fixed word
    assert.ok(forms[i].parsed.words.every((w) => w.kind === "input"), f.usage);
  }
});

test("faultsInForce: the overview's faults cell as a list", () => {
  assert.deepEqual(faultsInForce(""), []);
  assert.deepEqual(faultsInForce("heartbeat-stop"), ["heartbeat-stop"]);
  assert.deepEqual(faultsInForce("heartbeat-stop, sdo-delay"), ["heartbeat-stop", "sdo-delay"]);
});
