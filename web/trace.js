// The trace view (docs/web.md "The trace"): every frame on the buses, decoded in CANopen terms, newest at the bottom.
// It subscribes to all frames (frame events, COB-ID filters 0x000/0x000 and 0x00000000x/0x0: 11-bit and 29-bit ones)
// while its view is shown, or always with "record while hidden"; frames go into a ring of 20,000 (web/tracelog.js) as
// they come, and the table is drawn once an exchange, with at most the last ROWS matching rows in the DOM. Pause and
// scrolling up stop the table, not the recording. The PDOs' values come from their nodes' mapping, read as PDOs
// appear (web/pdoreader.js); the SDOs' expedited values are read by their objects' data types, from the dictionaries
// of the nodes as their SDOs appear; the abort codes' texts come from the emulator (`tables`: the core's table).

import {element, tableHead} from "./dom.js";
import * as candump from "./candump.js";
import {KINDS, abortTexts} from "./decode.js";
import {PdoMaps} from "./pdomap.js";
import {PdoReader, mappingMayChange} from "./pdoreader.js";
import {COLUMNS, TraceLog, cells, parseFilter} from "./tracelog.js";

/** Rows in the DOM at most: the newest that match. */
export const ROWS = 500;
// mask 0: every COB-ID matches; a filter takes one format, so 11-bit frames, and with x the 29-bit ones
const ALL_FRAMES = ["0x000/0x000", "0x00000000x/0x0"];

class TracePanel {
  view = "trace";
  events = ["nmt"]; // a node gone to pre-operational by a command of the emulator's: its mapping is read again
  #page;
  #maps = new PdoMaps();
  #log = new TraceLog(undefined, (frame, bytes) => this.#maps.lookup(frame, bytes),
    (frame, node, index, sub) => this.#reader.typeOf(frame.bus, node, index, sub));
  #reader = new PdoReader(this.#maps, (bus) => {
    if (this.#log.redecode(bus)) {
      this.#rebuild = true;
    }
  });
  #session = null; // the session opened last; null: none yet
  #recording = false; // subscribed to frames (asked)
  #since = null; // the emulator's time when the subscription was made (null: not answered yet)
  #held = []; // frame events that came before #since was known: the subscription's, or from one before it
  #subscriptions = 0; // the subscriptions asked: the answer of an earlier one's hello is not this one's
  #visible = false;
  #paused = false;
  #follow = true; // the table is scrolled to its bottom: it follows new frames
  #rebuild = true; // the rows must be made anew (filter, clear, time, a mapping came, shown again)
  #shownSeq = 0; // the newest entry the table has looked at
  #match = parseFilter().match;
  #filterError = null;
  #clock = null; // hello's {time_us, unix_us}
  #problem = null; // a request that failed
  #ui = {};

  constructor(page) {
    this.#page = page;
    this.#build(document.getElementById("view-trace"));
  }

  #build(section) {
    const ui = this.#ui;
    ui.text = element("input", {type: "search", id: "trace-text", placeholder: "text, e.g. 1018 or 712#05"});
    ui.kind = element("select", {id: "trace-kind"}, element("option", {value: "", textContent: "all"}),
      ...KINDS.map((k) => element("option", {value: k, textContent: k})));
    ui.node = element("input", {type: "text", id: "trace-node", inputMode: "numeric", size: 4, placeholder: "all"});
    ui.time = element("select", {id: "trace-time"}, element("option", {value: "start", textContent: "since start (s)"}),
      element("option", {value: "wall", textContent: "wall clock"}));
    ui.pause = element("button", {type: "button", id: "trace-pause", textContent: "Pause"});
    ui.pause.setAttribute("aria-pressed", "false");
    ui.clear = element("button", {type: "button", id: "trace-clear", textContent: "Clear"});
    ui.download = element("button", {type: "button", id: "trace-download", textContent: "Download candump log"});
    ui.background = element("input", {type: "checkbox", id: "trace-background"});
    ui.count = element("span", {id: "trace-count"});
    ui.problem = element("span", {id: "trace-problem", className: "problem"});
    const label = (text, control) => element("label", {}, `${text} `, control);
    section.append(element("div", {className: "trace-controls"},
      label("filter", ui.text), label("kind", ui.kind), label("node", ui.node), label("time", ui.time),
      ui.pause, ui.clear, ui.download, element("label", {}, ui.background, " record while hidden")),
    element("p", {className: "trace-status"}, ui.count, " ", ui.problem));
    const table = element("table", {id: "trace"});
    tableHead(table, COLUMNS);
    ui.body = table.createTBody();
    ui.scroller = element("div", {className: "trace-scroll"}, table);
    section.append(ui.scroller);

    for (const control of [ui.text, ui.kind, ui.node]) {
      control.addEventListener("input", () => this.#filterChanged());
      control.addEventListener("change", () => this.#filterChanged()); // a select changed by a script has no input
    }
    ui.time.addEventListener("change", () => this.#changed());
    ui.pause.addEventListener("click", () => {
      this.#paused = !this.#paused;
      ui.pause.textContent = this.#paused ? "Resume" : "Pause";
      ui.pause.setAttribute("aria-pressed", String(this.#paused));
      this.#page.redraw();
    });
    ui.clear.addEventListener("click", () => {
      this.#log.clear();
      this.#reader.clear();
      this.#changed();
    });
    ui.download.addEventListener("click", () => this.#download());
    ui.background.addEventListener("change", () => {
      if (!ui.background.checked && !this.#visible) {
        this.#unsubscribe();
      }
    });
    ui.scroller.addEventListener("scroll", () => {
      const s = ui.scroller;
      const bottom = s.scrollTop + s.clientHeight >= s.scrollHeight - 4;
      if (bottom !== this.#follow) {
        this.#follow = bottom;
        this.#page.redraw(); // following again: what came meanwhile is drawn now
      }
    });
  }

  open(session) {
    this.#session = session;
    this.#recording = false; // a new session has no subscription
    this.#reader.reset();
    if (this.#visible || this.#ui.background.checked) {
      this.#subscribe();
    }
  }

  /** The emulator's tables (web/app.js): the abort texts, for the aborts kept and to come. */
  tables(tables) {
    if (this.#log.useAbortTexts(abortTexts(tables.aborts))) {
      this.#rebuild = true;
    }
    this.#page.redraw();
  }

  shown(visible) {
    this.#visible = visible;
    if (visible) {
      this.#rebuild = true;
      this.#follow = true;
      if (this.#session !== null && !this.#recording) {
        this.#subscribe();
        this.#page.exchangeSoon();
      }
    } else if (!this.#ui.background.checked) {
      this.#unsubscribe();
    }
  }

  /**
   * Subscribes to every frame, and asks hello right after: its clock dates the log, and its time_us is when the
   * subscription was made. Frames of an earlier subscription may still come with the exchange that answers (the view
   * left and shown again at once): those are older and are not taken. An answer is handed out once its exchange's
   * lines are all read, so the frames of that exchange are held until then.
   */
  #subscribe() {
    this.#recording = true;
    this.#since = null;
    this.#held = [];
    const subscription = ++this.#subscriptions;
    this.#session.request("subscribe", {events: ["frame"], frames: ALL_FRAMES})
      .catch((error) => { this.#problem = `subscribe to frames: ${error.message}`; });
    this.#session.request("hello").then((answer) => {
      this.#clock = answer.clock;
      this.#problem = null;
      this.#start(subscription, answer.clock.time_us);
    }).catch((error) => {
      this.#problem = `hello: ${error.message}`;
      this.#start(subscription, -Infinity);
    });
  }

  #start(subscription, since) {
    if (subscription !== this.#subscriptions || !this.#recording || this.#since !== null) {
      return;
    }
    this.#since = since;
    for (const ev of this.#held) {
      if (ev.time_us >= since) {
        this.#record(ev);
      }
    }
    this.#held = [];
    this.#page.redraw();
  }

  #unsubscribe() {
    if (this.#recording) {
      this.#recording = false;
      this.#held = [];
      this.#session.request("unsubscribe", {events: ["frame"]})
        .catch((error) => { this.#problem = `unsubscribe from frames: ${error.message}`; });
    }
  }

  tick(session) {
    this.#reader.tick(session);
  }

  event(ev) {
    if (ev.event === "nmt" && ev.to === "PRE-OPERATIONAL") {
      this.#reader.stale(ev.bus, ev.node);
      return;
    }
    if (ev.event !== "frame" || !this.#recording) {
      return;
    }
    if (this.#since === null) {
      this.#held.push(ev);
    } else {
      this.#record(ev);
    }
  }

  #record(ev) {
    const entry = this.#log.add(ev);
    if (entry.kind === "PDO" && entry.about !== null) {
      this.#reader.want(entry.bus, entry.about);
    } else if (entry.kind === "SDO" && entry.about !== null) {
      this.#reader.wantTypes(entry.bus, entry.about); // its objects' data types read its values
    }
    const change = mappingMayChange(entry);
    if (change !== null) {
      this.#reader.stale(change.bus, change.node);
    }
  }

  #filterChanged() {
    const {match, error} = parseFilter({text: this.#ui.text.value, kind: this.#ui.kind.value,
      node: this.#ui.node.value});
    this.#filterError = error;
    this.#ui.node.setCustomValidity(error ?? "");
    if (match !== null) {
      this.#match = match;
      this.#changed();
    } else {
      this.#page.redraw();
    }
  }

  #changed() {
    this.#rebuild = true;
    this.#follow = true;
    this.#page.redraw();
  }

  draw() {
    if (!this.#visible) {
      return;
    }
    const waiting = this.#log.newest - this.#shownSeq;
    const frozen = this.#paused || (!this.#follow && !this.#rebuild);
    this.#status(frozen ? waiting : 0);
    if (frozen) {
      return;
    }
    const opts = {wall: this.#ui.time.value === "wall", clock: this.#clock};
    let fresh;
    if (this.#rebuild) {
      fresh = this.#log.lastMatching(this.#match, ROWS);
      this.#ui.body.replaceChildren();
      this.#rebuild = false;
    } else {
      fresh = this.#log.since(this.#shownSeq).filter(this.#match);
      if (fresh.length >= ROWS) {
        fresh = fresh.slice(-ROWS);
        this.#ui.body.replaceChildren();
      }
    }
    this.#shownSeq = this.#log.newest;
    if (fresh.length > 0) {
      const rows = document.createDocumentFragment();
      for (const entry of fresh) {
        rows.append(this.#row(entry, opts));
      }
      this.#ui.body.append(rows);
      for (let extra = this.#ui.body.rows.length - ROWS; extra > 0; extra--) {
        this.#ui.body.firstElementChild.remove();
      }
    }
    this.#ui.scroller.scrollTop = this.#ui.scroller.scrollHeight;
  }

  #row(entry, opts) {
    const tr = document.createElement("tr");
    tr.dataset.kind = entry.kind;
    tr.dataset.dir = entry.dir;
    const texts = cells(entry, opts);
    for (const {field} of COLUMNS) {
      const td = tr.insertCell();
      td.dataset.field = field;
      td.textContent = texts[field]; // text, never markup
    }
    return tr;
  }

  #status(waiting) {
    const ring = this.#log.ring;
    let count = `${ring.length} frames kept, ${ring.dropped} dropped (at most ${ring.capacity})`;
    if (!this.#recording) {
      count += "; not recording";
    } else if (this.#since === null) {
      count += "; subscribing";
    } else if (this.#paused) {
      count += `; paused: ${waiting} new not shown`;
    } else if (waiting > 0) {
      count += `; scrolled up: ${waiting} new not shown`;
    }
    if (this.#ui.count.textContent !== count) {
      this.#ui.count.textContent = count;
    }
    const problem = this.#filterError ?? this.#problem ?? this.#reader.problem ?? "";
    if (this.#ui.problem.textContent !== problem) {
      this.#ui.problem.textContent = problem;
    }
  }

  #download() {
    if (this.#clock === null) {
      this.#problem = "download: the emulator's clock is not known yet (no answer to hello)";
      this.#page.redraw();
      return;
    }
    const text = candump.log(this.#log.ring, this.#clock);
    const url = URL.createObjectURL(new Blob([text], {type: "text/plain"}));
    const link = element("a", {href: url, download: candump.fileName(new Date())});
    document.body.append(link);
    link.click();
    link.remove();
    setTimeout(() => URL.revokeObjectURL(url), 60_000);
  }
}

/** The trace panel (web/app.js panelMakers). */
export function makeTracePanel(page) {
  return new TracePanel(page);
}
