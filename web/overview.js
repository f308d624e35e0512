// The overview table (docs/web.md): one row per node, its cells from NodeTable.rows(). Everything an exchange
// brought is drawn in one animation frame, and only the cells whose text changed are touched, so that 127 nodes
// redrawn four times a second cost little.

import {COLUMNS} from "./nodes.js";

export class Overview {
  #body;
  #status;
  #rows = new Map(); // key -> {tr, cells: {field: td}}
  #frame = null; // the animation frame asked for, null: none

  constructor(table, status) {
    const head = table.createTHead().insertRow();
    for (const {field, title} of COLUMNS) {
      const th = document.createElement("th");
      th.textContent = title;
      th.dataset.field = field;
      th.scope = "col";
      head.append(th);
    }
    this.#body = table.createTBody();
    this.#status = status;
  }

  /** Draws at the next animation frame what draw() returns then ({rows, problem}): once, however often asked. */
  schedule(draw) {
    if (this.#frame === null) {
      this.#frame = requestAnimationFrame(() => {
        this.#frame = null;
        const {rows, problem} = draw();
        this.#render(rows, problem);
      });
    }
  }

  #render(rows, problem) {
    const keys = new Set(rows.map((r) => r.key));
    for (const [key, {tr}] of this.#rows) {
      if (!keys.has(key)) {
        tr.remove();
        this.#rows.delete(key);
      }
    }
    let previous = null;
    for (const row of rows) {
      const {tr, cells} = this.#rows.get(row.key) ?? this.#add(row.key);
      for (const [field, text] of Object.entries(row.cells)) {
        if (cells[field].textContent !== text) {
          cells[field].textContent = text; // text, never markup: nothing the emulator says becomes HTML
        }
      }
      if (tr.dataset.state !== row.state) {
        tr.dataset.state = row.state; // style.css colours the state by it
      }
      const expected = previous === null ? this.#body.firstElementChild : previous.nextElementSibling;
      if (expected !== tr) {
        if (previous === null) {
          this.#body.prepend(tr);
        } else {
          previous.after(tr);
        }
      }
      previous = tr;
    }
    const count = `${rows.length} ${rows.length === 1 ? "node" : "nodes"}`;
    this.#status.textContent = problem ?? count;
    this.#status.classList.toggle("problem", problem !== null);
  }

  #add(key) {
    const tr = document.createElement("tr");
    tr.dataset.key = key;
    const cells = {};
    for (const {field} of COLUMNS) {
      const td = tr.insertCell();
      td.dataset.field = field;
      cells[field] = td;
    }
    const entry = {tr, cells};
    this.#rows.set(key, entry);
    return entry;
  }
}
