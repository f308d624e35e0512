// The node view (docs/web.md "The node view"): one node picked in the network view or the picker, its summary as
// the overview has it, its object dictionary as a tree with the values in sight read about once a second and the
// writable ones edited in place (`set`, as the command language's), and its commands as controls. A panel of the
// page (web/app.js): everything goes through the page's control session.

import {element} from "./dom.js";
import {DictionaryTree} from "./node-tree.js";
import {NodeControls} from "./node-controls.js";
import {faultsInForce} from "./commands.js";
import {ValuePoll, groupObjects, parseInput} from "./dictionary.js";
import {nodeRef} from "./nodes.js";

/** The summary's fields: the overview's cells (web/nodes.js) of the node and their titles. */
const SUMMARY = [["device", "device"], ["state", "NMT state"], ["heartbeat", "heartbeat"],
  ["heartbeat-age", "last heartbeat"], ["error-register", "error register"], ["faults", "protocol faults"],
  ["emcy", "last EMCY"], ["emcy-age", "EMCY sent"]];

class NodePanel {
  view = "node";
  #page;
  #key = null; // the node shown; null: none yet
  #visible = false;
  #dictionaries = new Map(); // key -> groups (groupObjects) of its `objects` answer: read once per node
  #commands = new Map(); // key -> its device's commands (`help NODE`)
  #loading = null; // the key whose `objects` is on its way; null: none
  #helpLoading = null; // the key whose `help` is on its way; null: none
  #loaded = false; // the tree shows the dictionary of #key
  #poll = new ValuePoll(1000);
  #root;
  #picker;
  #pickerKeys = "";
  #summary = new Map(); // field -> dd
  #dictionaryNote;
  #tree;
  #controls;

  constructor(page) {
    this.#page = page;
    this.#root = document.getElementById("view-node");
    const head = element("div", {className: "node-head"});
    const label = element("label", {className: "node-picker", textContent: "node "});
    this.#picker = element("select");
    this.#picker.addEventListener("change", () => this.#page.select(this.#picker.value));
    label.append(this.#picker);
    const summary = element("dl", {className: "node-summary"});
    for (const [field, title] of SUMMARY) {
      const item = element("div");
      const dd = element("dd");
      dd.dataset.field = field;
      item.append(element("dt", {textContent: title}), dd);
      summary.append(item);
      this.#summary.set(field, dd);
    }
    head.append(label, summary);

    const dictionary = element("section", {className: "node-dictionary"});
    const tools = element("div", {className: "toolbar"});
    const expand = element("button", {textContent: "expand all"});
    const collapse = element("button", {textContent: "collapse all"});
    expand.type = collapse.type = "button";
    expand.addEventListener("click", () => this.#tree.expandAll(true));
    collapse.addEventListener("click", () => this.#tree.expandAll(false));
    this.#dictionaryNote = element("span", {className: "note"});
    tools.append(element("h2", {textContent: "Object dictionary"}), expand, collapse, this.#dictionaryNote);
    const table = element("table", {className: "dictionary"});
    dictionary.append(tools, table);
    this.#tree = new DictionaryTree(table, {
      onEdit: (entry, text) => this.#write(entry, text),
      onPlot: (entry) => this.#page.plot?.(this.#key, entry.object),
    });

    const controls = element("section", {className: "node-controls"});
    controls.append(element("h2", {textContent: "Commands"}));
    this.#controls = new NodeControls(controls, (cmd, args) => this.#command(cmd, args));
    const body = element("div", {className: "node-body"});
    body.append(dictionary, controls);
    this.#root.append(head, body);
  }

  select(key) {
    if (key === this.#key) {
      return;
    }
    this.#key = key;
    this.#loaded = false;
    this.#tree.load([]);
    this.#show(key);
  }

  /** A new session: what was on its way in the old one is asked again. */
  open() {
    if (this.#key !== null && !this.#dictionaries.has(this.#key)) {
      this.#readDictionary(this.#key);
    }
    if (this.#key !== null && !this.#commands.has(this.#key)) {
      this.#readCommands(this.#key);
    }
  }

  shown(visible) {
    this.#visible = visible;
  }

  /** The emulator's tables (web/app.js): the fault forms are made from its kinds of fault. */
  tables(tables) {
    this.#controls.loadFaults(tables.faults);
  }

  /** The tables could not be read. */
  tablesFailed(error) {
    this.#controls.faultsFailed(error.message);
  }

  /** Reads the values in sight: only while the view is shown, a round at a time (dictionary.js ValuePoll). */
  tick(session, ms) {
    if (!this.#visible || !this.#loaded) {
      return;
    }
    const rounds = this.#poll.take(ms, this.#tree.shownObjects(), this.#tree.hasUnread());
    if (rounds.length === 0) {
      return;
    }
    const key = this.#key;
    Promise.allSettled(rounds.map((objects) => session.request("get", {node: nodeRef(key), objects})
      .then((answer) => {
        if (key === this.#key) {
          this.#tree.setValues(answer.values);
        }
      })))
      .then((results) => {
        const failed = results.find((r) => r.status === "rejected");
        if (key === this.#key) {
          this.#dictionaryNote.textContent = failed === undefined ? "" : `get: ${failed.reason.message}`;
        }
        this.#poll.done();
        this.#page.redraw();
      });
  }

  draw(ms) {
    if (!this.#visible) {
      return;
    }
    const rows = this.#page.nodes.rows(ms).filter((r) => !r.heard); // a node only heard has no dictionary here
    this.#drawPicker(rows);
    const row = rows.find((r) => r.key === this.#key);
    for (const [field, dd] of this.#summary) {
      const gone = field === "device" ? "not in the emulator's list of nodes (now)" : "";
      const text = row === undefined ? gone : row.cells[field];
      if (dd.textContent !== text) {
        dd.textContent = text;
      }
    }
    this.#summary.get("heartbeat-age").classList.toggle("overdue", row?.overdue === true);
    if (row !== undefined) {
      this.#summary.get("state").dataset.state = row.state;
      this.#label(row);
    }
    this.#controls.update(row === undefined ? [] : faultsInForce(row.cells.faults));
    this.#root.classList.toggle("plots", typeof this.#page.plot === "function");
    this.#tree.draw();
  }

  /** The tree and the controls of `key`: from what was read before, else asked now. */
  #show(key) {
    if (this.#dictionaries.has(key)) {
      this.#tree.load(this.#dictionaries.get(key));
      this.#loaded = true;
      this.#dictionaryNote.textContent = "";
    } else {
      this.#readDictionary(key);
    }
    if (this.#commands.has(key)) {
      this.#controls.load(this.#commands.get(key));
    } else {
      this.#readCommands(key);
    }
  }

  /** `objects` of the node: its dictionary's structure (once per node: it does not change while it runs). */
  #readDictionary(key) {
    if (this.#loading === key) {
      return;
    }
    this.#loading = key;
    this.#dictionaryNote.textContent = "reading the dictionary…";
    this.#page.session.request("objects", {node: nodeRef(key)})
      .then((answer) => {
        this.#dictionaries.set(key, groupObjects(answer.objects));
        if (key === this.#key) {
          this.#show(key);
        }
      })
      .catch((error) => {
        if (key === this.#key) {
          this.#dictionaryNote.textContent = `objects: ${error.message}`;
        }
      })
      .finally(() => {
        if (this.#loading === key) {
          this.#loading = null;
        }
        this.#page.redraw();
      });
    this.#page.exchangeSoon();
  }

  /** `help NODE`: its device's commands. */
  #readCommands(key) {
    this.#controls.loading();
    if (this.#helpLoading === key) {
      return;
    }
    this.#helpLoading = key;
    this.#page.session.request("help", {node: nodeRef(key)})
      .then((answer) => {
        this.#commands.set(key, answer.commands);
        if (key === this.#key) {
          this.#controls.load(answer.commands);
        }
      })
      .catch((error) => {
        if (key === this.#key) {
          this.#controls.failed(error.message);
        }
      })
      .finally(() => {
        if (this.#helpLoading === key) {
          this.#helpLoading = null;
        }
      });
    this.#page.exchangeSoon();
  }

  /** A value typed into the tree: `set` as the command language's; {value} after the write, or {error}. */
  async #write(entry, text) {
    const parsed = parseInput(text, entry.type);
    if (parsed.error !== undefined) {
      return parsed;
    }
    const answer = this.#page.session.request("set", {node: nodeRef(this.#key), object: entry.object,
      value: parsed.value});
    this.#page.exchangeSoon();
    try {
      return {value: (await answer).value};
    } catch (refusal) {
      return {error: refusal.message};
    } finally {
      this.#page.redraw();
    }
  }

  /** A command of the controls for the node shown; resolves to its answer, rejects with its error. */
  async #command(cmd, args) {
    const fields = {node: nodeRef(this.#key)};
    if (args.length > 0) {
      fields.args = args;
    }
    const answer = this.#page.session.request(cmd, fields);
    this.#page.exchangeSoon();
    try {
      return await answer;
    } finally {
      this.#page.redraw();
    }
  }

  #drawPicker(rows) {
    const keys = rows.map((r) => r.key).join(" ");
    if (keys !== this.#pickerKeys) {
      this.#pickerKeys = keys;
      const buses = new Set(rows.map((r) => r.cells.bus));
      this.#picker.replaceChildren(...rows.map((r) => new Option(
        `${r.cells.node}${buses.size > 1 ? `@${r.cells.bus}` : ""} ${r.cells.device}`, r.key)));
    }
    if (this.#picker.value !== this.#key && this.#key !== null) {
      this.#picker.value = this.#key;
    }
  }

  #label(row) {
    const text = `Node ${row.cells.node} (${row.cells.device.split(" ")[0]})`;
    const button = this.#page.tabs.button("node");
    if (button.textContent !== text) {
      button.textContent = text;
    }
  }
}

/** The node view's panel (web/app.js's contract). */
export function makeNodePanel(page) {
  return new NodePanel(page);
}
