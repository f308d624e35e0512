// The node view's controls (docs/web.md "The node view"): forms made from a command's usage line, the arguments
// they send, the commands every node has beside its device's own, and the protocol faults as the emulator serves
// them (`tables`). No DOM: tested with node --test.

/*
 * A usage line is what `help NODE` answers in `commands` (docs/control-protocol.md): "load N MW|short",
 * "keypad release on|off", "efield N VOLT [RIPPLE]", "error CODE / warning CODE". Its first word is the command;
 * each later word is
 *   fixed    a literal word in lower case, sent as it is ("release")
 *   choice   literal alternatives ("on|off", "auto|hand|flashing"): a select
 *   input    an argument, a word in upper case ("N", "UA_PER_KV", "D1..D10|A1|A2"), or alternatives of which one is
 *            ("MW|short": a number or the word): a text field; `optional` from "[...]" on
 * " / " separates two commands that share the text ("error CODE / warning CODE"). Blanks around a "|" do not count
 * ("[N | P% [SEED]]" is "[N|P% [SEED]]": an optional N or P%, and an optional SEED).
 */

const ARGUMENT = /^[^a-z]*[A-Z][^a-z]*$/; // upper case and no lower case: "N", "P%", "D1..D10", "B0"

function word(token, optional) {
  const alternatives = token.split("|");
  if (alternatives.some((a) => ARGUMENT.test(a))) {
    const hint = alternatives.length === 1 ? token
      : `${alternatives.slice(0, -1).join(", ")} or ${alternatives.at(-1)}`;
    return {kind: "input", name: token, hint, optional};
  }
  if (alternatives.length > 1) {
    return {kind: "choice", options: alternatives, optional};
  }
  return {kind: "fixed", text: token};
}

/** The commands of one usage line: [{command, usage, words}] (words: above). */
export function parseUsage(usage) {
  return usage.replace(/ *\| */g, "|").split(" / ").map((part) => {
    const [command, ...tokens] = part.trim().split(/\s+/);
    let optional = false;
    const words = tokens.map((token) => {
      const bracketed = token.startsWith("[");
      optional ||= bracketed;
      return word(bracketed ? token.replace(/^\[|\]+$/g, "") : token, optional); // "INDEX[:SUB]" stays whole
    });
    return {command, usage: part.trim(), words};
  });
}

/**
 * The `args` of a command from what its form holds: `values` one string per word that is not fixed (inputs and
 * choices, in order). {args} or {error}: a required argument left empty, an argument with blanks (the protocol
 * takes words), an optional one given after one left out (the words would shift).
 */
export function argsOf(words, values) {
  const args = [];
  let given = 0;
  let skipped = null;
  for (const w of words) {
    if (w.kind === "fixed") {
      args.push(w.text);
      continue;
    }
    const value = (values[given++] ?? "").trim();
    if (value === "") {
      if (!w.optional) {
        return {error: `${w.name ?? w.options.join("|")} is needed`};
      }
      skipped ??= w.name ?? w.options.join("|");
      continue;
    }
    if (/\s/.test(value)) {
      return {error: `${w.name ?? "a value"}: one word, without blanks`};
    }
    if (skipped !== null) {
      return {error: `${w.name ?? w.options.join("|")} needs ${skipped} before it`};
    }
    args.push(value);
  }
  return {args};
}

/**
 * What every node has beside its device's commands (the command language's `help`, docs/emulator.md): `help NODE`
 * lists only the device's own, so these are here.
 */
export const NODE_COMMANDS = [
  {usage: "power-cycle", text: "restart the node as switching its supply off and on would (boot-up)"},
  {usage: "emcy CODE [REG] [B0] [B1] [B2] [B3] [B4]", text: "raise a raw CiA error (EMCY, 0x1001, 0x1003)"},
  {usage: "emcy-clear CODE [B0] [B1] [B2] [B3] [B4]", text: "clear it (error-reset EMCY)"},
];

/**
 * The forms of the protocol faults (docs/emulator.md "Protocol faults"), `fault NODE KIND [ARGS]`, ended by
 * `fault-clear NODE KIND`: from the `faults` of the emulator's `tables` answer ([{kind, usage, limits, text}], usage
 * the words after NODE, its first word the kind), in its order: [{kind, parsed (parseUsage()), text (with the limits
 * of the arguments)}].
 */
export function faultForms(faults) {
  return faults.map(({kind, usage, limits = "", text}) => ({kind, parsed: parseUsage(usage)[0],
    text: limits === "" ? text : `${text} (${limits})`}));
}

/** The faults in force as the overview's faults cell has them ("heartbeat-stop, sdo-delay"). */
export function faultsInForce(text) {
  return text === "" ? [] : text.split(", ");
}
