// The node view's controls (docs/web.md "The node view"): a form per command of the node's device (from `help
// NODE`), per command every node has (power-cycle, emcy, emcy-clear), and per protocol fault (raise, clear, whether
// it is in force: the kinds the emulator serves in `tables`). Each sends its command through the page's session and
// shows the answer's lines or its error.

import {NODE_COMMANDS, argsOf, faultForms, parseUsage} from "./commands.js";

/**
 * A form for one command (parseUsage()): its usage and help text, a field per argument, a button, the answer.
 * send(args) resolves to the answer ({lines}) or rejects with the refusal.
 */
function commandForm(parsed, text, send, buttonText) {
  const form = document.createElement("form");
  form.className = "command";
  form.dataset.command = parsed.command;
  const usage = document.createElement("code");
  usage.className = "usage";
  usage.textContent = parsed.usage;
  usage.title = text;
  const help = document.createElement("span");
  help.className = "help";
  help.textContent = text;
  const fields = document.createElement("span");
  fields.className = "fields";
  const inputs = [];
  for (const w of parsed.words) {
    if (w.kind === "fixed") {
      const fixed = document.createElement("span");
      fixed.className = "fixed";
      fixed.textContent = w.text;
      fields.append(fixed);
    } else if (w.kind === "choice") {
      const select = document.createElement("select");
      select.setAttribute("aria-label", w.options.join("|"));
      for (const option of w.optional ? ["", ...w.options] : w.options) {
        select.add(new Option(option, option));
      }
      inputs.push(select);
      fields.append(select);
    } else {
      const input = document.createElement("input");
      input.type = "text";
      input.placeholder = w.optional ? `[${w.hint}]` : w.hint;
      input.setAttribute("aria-label", w.name);
      input.size = Math.max(4, Math.min(12, w.hint.length + 2));
      inputs.push(input);
      fields.append(input);
    }
  }
  const button = document.createElement("button");
  button.type = "submit";
  button.textContent = buttonText;
  fields.append(button);
  const answer = document.createElement("output");
  answer.className = "answer";
  form.append(usage, help, fields, answer);
  const show = (lines, refused) => {
    answer.textContent = lines;
    answer.classList.toggle("refusal", refused);
  };
  form.addEventListener("submit", async (e) => {
    e.preventDefault();
    const {args, error} = argsOf(parsed.words, inputs.map((i) => i.value));
    if (error !== undefined) {
      show(error, true);
      return;
    }
    button.disabled = true;
    show("…", false);
    try {
      show((await send(args)).lines.join("\n"), false);
    } catch (refusal) {
      show(refusal.message, true);
    } finally {
      button.disabled = false;
    }
  });
  return {form, show};
}

function section(title) {
  const div = document.createElement("section");
  const h = document.createElement("h3");
  h.textContent = title;
  div.append(h);
  return div;
}

export class NodeControls {
  #run;
  #device;
  #faults = new Map(); // kind -> its row
  #faultsShown = null; // the faults in force marked last (joined); null: none marked on the rows there are
  #faultsBox; // the section of the faults
  #faultNote;

  /** root: the element to fill; run(cmd, args) sends {"cmd":cmd,"node":…,"args":args} for the node shown and
   * resolves to its answer, or rejects with its error. */
  constructor(root, run) {
    this.#run = run;
    this.#device = section("Device");
    this.#device.classList.add("device-commands");
    const node = section("Node");
    for (const {usage, text} of NODE_COMMANDS) {
      const parsed = parseUsage(usage)[0];
      node.append(commandForm(parsed, text, (args) => this.#run(parsed.command, args), "run").form);
    }
    root.append(this.#device, node, this.#faultSection());
    this.loading();
  }

  /** The protocol faults: the `faults` of the emulator's `tables` answer. Made once: the table does not change. */
  loadFaults(faults) {
    if (this.#faults.size > 0) {
      return;
    }
    this.#faultNote.remove();
    for (const {kind, parsed, text} of faultForms(faults)) {
      this.#faultsBox.append(this.#faultForm(kind, parsed, text));
    }
    this.#faultsShown = null; // the new rows are marked with the next update
  }

  /** The table of faults could not be read. */
  faultsFailed(error) {
    this.#faultNote.textContent = `tables: ${error}`;
    this.#faultNote.classList.add("refusal");
  }

  /** Before the device's commands have come. */
  loading() {
    this.#setDevice("reading the device's commands…");
  }

  /** The device's commands could not be read. */
  failed(error) {
    this.#setDevice(`help: ${error}`).classList.add("refusal");
  }

  /** The device's commands: `help NODE`'s `commands` ([{usage, text}]). */
  load(commands) {
    const forms = commands.flatMap(({usage, text}) => parseUsage(usage).map((parsed) =>
      commandForm(parsed, text, (args) => this.#run(parsed.command, args), "run").form));
    this.#device.replaceChildren(this.#device.firstElementChild, ...forms);
    if (forms.length === 0) {
      this.#setDevice("no commands of its own");
    }
  }

  /** Marks the faults in force (the overview's: `show`, fault events). */
  update(inForce) {
    const key = inForce.join(",");
    if (key === this.#faultsShown) {
      return;
    }
    this.#faultsShown = key;
    for (const [kind, row] of this.#faults) {
      const active = inForce.includes(kind);
      row.dataset.inForce = String(active);
      row.querySelector(".state").textContent = active ? "in force" : "";
    }
  }

  #setDevice(text) {
    const p = document.createElement("p");
    p.className = "note";
    p.textContent = text;
    this.#device.replaceChildren(this.#device.firstElementChild, p);
    return p;
  }

  #faultSection() {
    const faults = section("Protocol faults");
    const all = document.createElement("div");
    all.className = "fault-all";
    const output = document.createElement("output");
    output.className = "answer";
    const button = (text, cmd) => {
      const b = document.createElement("button");
      b.type = "button";
      b.textContent = text;
      b.addEventListener("click", async () => {
        try {
          output.textContent = (await this.#run(cmd, [])).lines.join("\n");
          output.classList.remove("refusal");
        } catch (refusal) {
          output.textContent = refusal.message;
          output.classList.add("refusal");
        }
      });
      return b;
    };
    all.append(button("list", "faults"), button("clear all", "fault-clear"), output);
    this.#faultNote = document.createElement("p");
    this.#faultNote.className = "note";
    this.#faultNote.textContent = "reading the kinds of fault…";
    faults.append(all, this.#faultNote);
    this.#faultsBox = faults;
    return faults;
  }

  /** The form of one kind of fault: raise with its arguments, clear, whether it is in force. */
  #faultForm(kind, parsed, text) {
    const {form, show} = commandForm(parsed, text, (args) => this.#run("fault", [kind, ...args]), "raise");
    form.classList.add("fault");
    form.dataset.fault = kind;
    const state = document.createElement("span");
    state.className = "state";
    const clear = document.createElement("button");
    clear.type = "button";
    clear.className = "clear";
    clear.textContent = "clear";
    clear.addEventListener("click", async () => {
      try {
        show((await this.#run("fault-clear", [kind])).lines.join("\n"), false);
      } catch (refusal) {
        show(refusal.message, true);
      }
    });
    form.querySelector(".fields").append(clear, state);
    this.#faults.set(kind, form);
    return form;
  }
}
