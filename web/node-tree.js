// The node view's dictionary table (docs/web.md "The node view"): a row per object, the sub-indices of an object
// of several under it when it is expanded, the values of the rows in sight (an IntersectionObserver says which:
// only those are read), a writable value edited in place. The panel (web/node.js) reads and writes; this draws.

import {tableHead} from "./dom.js";
import * as dictionary from "./dictionary.js";
import {plottableRow} from "./objects.js";

/** The columns, in order: field (the cell's data-field) and title. */
export const TREE_COLUMNS = [
  ["object", "object"], ["name", "name"], ["type", "type"], ["access", "access"], ["unit", "unit"],
  ["limits", "limits"], ["value", "value"], ["actions", ""], ["note", ""],
].map(([field, title]) => ({field, title}));

export class DictionaryTree {
  #body;
  #onEdit;
  #onPlot;
  #groups = [];
  #groupRows = new Map(); // index -> the row of an object of several sub-indices
  #expanded = new Set(); // indices shown with their sub-indices
  #rows = new Map(); // object ("0x1018:01") -> {tr, cells, entry}: the entries' rows in the table now
  #values = new Map(); // object -> {value, type} or {error}: the last read or written
  #changed = new Set(); // objects whose value cell is to be drawn again
  #visible = new Set(); // objects whose row is in sight
  #editing = null; // {object, input, sending} of the value being edited; null: none
  #observer;

  /**
   * table: the <table>. onEdit(entry, text): a value typed and Enter pressed; resolves to {value} (written: the
   * value after the write) or {error} (refused). onPlot(entry): its plot button.
   */
  constructor(table, {onEdit, onPlot}) {
    this.#onEdit = onEdit;
    this.#onPlot = onPlot;
    tableHead(table, TREE_COLUMNS);
    this.#body = table.createTBody();
    this.#observer = new IntersectionObserver((changes) => {
      for (const change of changes) {
        const object = change.target.dataset.object;
        if (change.isIntersecting) {
          this.#visible.add(object);
        } else {
          this.#visible.delete(object);
        }
      }
    });
  }

  /** Shows the groups of dictionary.groupObjects(), all collapsed; [] empties the table. */
  load(groups) {
    this.#observer.disconnect();
    this.#body.replaceChildren();
    this.#groups = groups;
    this.#groupRows.clear();
    this.#expanded.clear();
    this.#rows.clear();
    this.#values.clear();
    this.#changed.clear();
    this.#visible.clear();
    this.#editing = null;
    for (const group of groups) {
      if (dictionary.isSingle(group)) {
        this.#body.append(this.#entryRow(group.entries[0], group.index, false));
      } else {
        this.#body.append(this.#groupRow(group));
      }
    }
  }

  /** The objects whose rows are in sight (the only ones read). */
  shownObjects() {
    return [...this.#visible];
  }

  /** Whether one of them has never been read (just expanded or scrolled to): read at once rather than in a second. */
  hasUnread() {
    for (const object of this.#visible) {
      if (!this.#values.has(object)) {
        return true;
      }
    }
    return false;
  }

  /** The `values` of a `get` answer ({object, value, type} or {object, error} each). */
  setValues(values) {
    for (const v of values) {
      this.#values.set(v.object, v);
      this.#changed.add(v.object);
    }
  }

  /** Expands (true) or collapses every object of several sub-indices. */
  expandAll(expand) {
    for (const group of this.#groups) {
      if (this.#groupRows.has(group.index) && this.#expanded.has(group.index) !== expand) {
        this.#toggle(group);
      }
    }
  }

  /** Writes the value cells that changed since the last draw. */
  draw() {
    for (const object of this.#changed) {
      const row = this.#rows.get(object);
      if (row !== undefined && this.#editing?.object !== object) {
        this.#drawValue(row);
      }
    }
    this.#changed.clear();
  }

  #drawValue({cells, entry}) {
    const read = this.#values.get(entry.object);
    const cell = cells.value;
    const text = read === undefined ? "" : read.error ?? dictionary.valueText(read.value, entry);
    if (cell.textContent !== text || cell.firstElementChild !== null) {
      cell.textContent = text; // text, never markup
    }
    cell.classList.toggle("unreadable", read?.error !== undefined);
    cell.title = read?.error === undefined ? dictionary.valueHint(read?.value, entry) : "";
  }

  #groupRow(group) {
    const tr = document.createElement("tr");
    tr.className = "group";
    tr.dataset.index = group.index;
    const objectCell = tr.insertCell();
    objectCell.dataset.field = "object";
    const toggle = document.createElement("button");
    toggle.type = "button";
    toggle.className = "toggle";
    toggle.setAttribute("aria-expanded", "false");
    toggle.textContent = group.index;
    toggle.title = `${group.entries.length} sub-indices`;
    toggle.addEventListener("click", () => this.#toggle(group));
    objectCell.append(toggle);
    const nameCell = tr.insertCell();
    nameCell.dataset.field = "name";
    nameCell.colSpan = TREE_COLUMNS.length - 1;
    nameCell.textContent = group.name;
    this.#groupRows.set(group.index, {tr, toggle});
    return tr;
  }

  #toggle(group) {
    const {tr, toggle} = this.#groupRows.get(group.index);
    if (this.#expanded.delete(group.index)) {
      for (const entry of group.entries) {
        this.#removeRow(entry.object);
      }
    } else {
      this.#expanded.add(group.index);
      tr.after(...group.entries.map((entry) => this.#entryRow(entry, entry.object, true)));
    }
    toggle.setAttribute("aria-expanded", String(this.#expanded.has(group.index)));
  }

  #removeRow(object) {
    const row = this.#rows.get(object);
    if (this.#editing?.object === object) {
      this.#editing = null;
    }
    this.#observer.unobserve(row.tr);
    row.tr.remove();
    this.#rows.delete(object);
    this.#visible.delete(object);
  }

  /** The row of one entry: `label` in its object cell ("0x1017" alone, "0x1018:01" under its object). */
  #entryRow(entry, label, sub) {
    const tr = document.createElement("tr");
    tr.className = sub ? "entry sub" : "entry";
    tr.dataset.object = entry.object;
    const cells = {};
    for (const {field} of TREE_COLUMNS) {
      cells[field] = tr.insertCell();
      cells[field].dataset.field = field;
    }
    cells.object.textContent = label;
    cells.name.textContent = entry.name ?? "";
    cells.type.textContent = entry.type;
    cells.access.textContent = entry.access;
    cells.unit.textContent = entry.unit ?? "";
    cells.limits.textContent = dictionary.limits(entry);
    if (dictionary.isWritable(entry)) {
      cells.value.classList.add("editable");
      cells.value.tabIndex = 0;
      cells.value.title = "click to edit";
      cells.value.addEventListener("click", () => this.#edit(entry.object));
      cells.value.addEventListener("keydown", (e) => {
        if ((e.key === "Enter" || e.key === "F2") && e.target === cells.value) {
          this.#edit(entry.object);
        }
      });
    }
    if (plottableRow(entry)) {
      const plot = document.createElement("button");
      plot.type = "button";
      plot.className = "plot";
      plot.textContent = "plot";
      plot.title = `plot ${entry.object}`;
      plot.addEventListener("click", () => this.#onPlot(entry));
      cells.actions.append(plot);
    }
    const row = {tr, cells, entry};
    this.#rows.set(entry.object, row);
    if (this.#values.has(entry.object)) {
      this.#drawValue(row);
    }
    this.#observer.observe(tr);
    return tr;
  }

  #edit(object) {
    if (this.#editing?.object === object) {
      return;
    }
    this.#closeEditor();
    const {cells, entry} = this.#rows.get(object);
    const input = document.createElement("input");
    input.type = "text";
    input.className = "editor";
    input.setAttribute("aria-label", `new value of ${object}`);
    const read = this.#values.get(object);
    // as shown (a COB-ID in hex, which `set` reads as typed: parseInput)
    input.value = read === undefined || read.error !== undefined ? "" : dictionary.valueText(read.value, entry);
    const editing = {object, input, sending: false};
    this.#editing = editing;
    input.addEventListener("keydown", (e) => {
      if (e.key === "Enter") {
        e.preventDefault();
        this.#commit(editing, entry, cells);
      } else if (e.key === "Escape") {
        e.preventDefault();
        this.#closeEditor();
        cells.value.focus();
      }
    });
    input.addEventListener("blur", () => {
      if (!editing.sending && this.#editing === editing) {
        this.#closeEditor();
      }
    });
    cells.note.textContent = "";
    cells.note.className = "";
    cells.value.replaceChildren(input);
    input.focus();
    input.select();
  }

  async #commit(editing, entry, cells) {
    if (editing.sending) {
      return;
    }
    editing.sending = true;
    editing.input.readOnly = true;
    cells.note.textContent = "writing…";
    const result = await this.#onEdit(entry, editing.input.value);
    if (this.#rows.get(entry.object)?.cells !== cells) {
      return; // collapsed or another node meanwhile
    }
    if (result.error === undefined) {
      this.#values.set(entry.object, {object: entry.object, value: result.value, type: entry.type});
      cells.note.textContent = "";
    } else {
      cells.note.textContent = result.error; // the refusal; the value stays as it was
      cells.note.className = "refusal";
    }
    if (this.#editing === editing) {
      this.#closeEditor();
    }
  }

  #closeEditor() {
    const editing = this.#editing;
    if (editing === null) {
      return;
    }
    this.#editing = null;
    const row = this.#rows.get(editing.object);
    if (row !== undefined) {
      row.cells.value.replaceChildren();
      this.#drawValue(row);
    }
  }
}
