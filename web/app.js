// The web view of canopen-emu (docs/web.md). The page is a control-protocol client (docs/control-protocol.md) over
// one web session: it asks `show all` once a second and takes the events nmt, boot-up, emcy and fault in between.
// Every 250 ms the panels may queue requests; they go out on the session's WebSocket, and answers and events come
// on it as the emulator makes them (drawn at the next animation frame). Where no WebSocket opens, the session's
// stream brings answers and events and the requests are posted with an exchange; without either (broken, refused)
// the page exchanges every 250 ms and tries again after STREAM_RETRY_MS. It asks
// `tables` once: the kinds of protocol fault and the SDO abort texts, which the page has no copy of. The network
// view (the overview) is drawn here; the other views are panels (below), each its own module, sharing the session
// and the exchange loop.

import {Session, poster, streamer} from "./api.js";
import {NodeTable} from "./nodes.js";
import {Overview} from "./overview.js";
import {makePlots} from "./plots.js";
import {Tabs} from "./tabs.js";
import {makeNodePanel} from "./node.js";
import {makeTracePanel} from "./trace.js";

const EXCHANGE_MS = 250;
const SHOW_MS = 1000;
const STREAM_RETRY_MS = 2000;
const EVENTS = ["nmt", "boot-up", "emcy", "fault"];

/*
 * A panel is an object with any of these members, all optional:
 *   events           the event kinds it needs, subscribed with every new session beside the overview's
 *   open(session)    a new session (the first, or one after an expiry): subscribe what else it needs, reload
 *   tick(session, ms)  every 250 ms, before the exchange: queue the requests it wants now (session.request(...))
 *   event(ev, ms)    each event that came (of every kind anyone subscribed: a panel filters)
 *   draw(ms)         in the animation frame after each exchange or piece of the stream (and after select): update
 *                    its DOM there
 *   shown(visible)   its view was shown (true) or left (false)
 *   select(key)      the node `key` (nodes.js nodeKey) was picked in the network view
 *   tables(answer)   the emulator's tables came (the `tables` answer: `faults`, `aborts`; docs/control-protocol.md)
 *   tablesFailed(error)  they could not be read (asked again with the next session)
 *   view             the name of its view (a tab of index.html), for shown()
 * A panel module exports a function that takes the page (below) and returns its panel.
 */
const panelMakers = [makeNodePanel, makePlots, makeTracePanel];

const token = document.querySelector('meta[name="canopen-emu-token"]').content;
const nodes = new NodeTable();
let exchangeProblem = "connecting"; // why the last exchange failed; null: it did not
let requestProblem = null; // why the last show (or the subscribe) failed; null: it did not
let showAsked = false; // a show is on its way: never a second one, however slow the answers come
let lastShow = -Infinity; // performance.now() of the last show asked
let frame = null; // the animation frame asked for; null: none
let panels = [];
let tablesAsked = false; // `tables` was answered or is on its way: it does not change while the emulator runs

function askShow() {
  showAsked = true;
  lastShow = performance.now();
  session.request("show", {node: "all"})
    .then((answer) => {
      nodes.show(answer, performance.now());
      requestProblem = null;
    })
    .catch((error) => { requestProblem = `show all: ${error.message}`; })
    .finally(() => { showAsked = false; });
}

/** The page's WebSocket to path (ws: beside http:), the token as its subprotocol (a WebSocket sends no headers). */
function openSocket(path) {
  const url = new URL(path, location.href);
  url.protocol = url.protocol === "https:" ? "wss:" : "ws:";
  return new WebSocket(url.href, [`canopen-emu.${token}`]);
}

const session = new Session(poster(token), {
  openSocket,
  openStream: streamer(token),
  onData: () => scheduleDraw(),
  onOpen: (s) => {
    const events = new Set([...EVENTS, ...panels.flatMap((p) => p.events ?? [])]);
    s.request("subscribe", {events: [...events]}).catch((error) => { requestProblem = `subscribe: ${error.message}`; });
    if (!tablesAsked) {
      tablesAsked = true;
      s.request("tables")
        .then((answer) => panels.forEach((p) => p.tables?.(answer)))
        .catch((error) => {
          tablesAsked = false;
          panels.forEach((p) => p.tablesFailed?.(error));
        })
        .finally(scheduleDraw);
    }
    lastShow = -Infinity; // a new session: everything anew, at once
    for (const p of panels) {
      p.open?.(s);
    }
  },
  onEvent: (event) => {
    const ms = performance.now();
    nodes.event(event, ms);
    for (const p of panels) {
      p.event?.(event, ms);
    }
  },
  onStray: (line) => console.warn("canopen-emu: a line no request of this page asked for:", line),
});

/** Draws everything at the next animation frame: once, however often asked. */
function scheduleDraw() {
  if (frame === null) {
    frame = requestAnimationFrame(() => {
      frame = null;
      const ms = performance.now();
      overview.render(nodes.rows(ms), exchangeProblem ?? requestProblem, nodes.buses());
      for (const p of panels) {
        p.draw?.(ms);
      }
    });
  }
}

/** What panels share: the session, the nodes, the views, the picked node. */
const page = {
  session,
  nodes,
  tabs: null,
  selected: null, // the key of the node picked in the network view; null: none yet
  /** Picks the node `key` and shows the node view. */
  select(key) {
    page.selected = key;
    page.tabs.enable("node", true);
    for (const p of panels) {
      p.select?.(key);
    }
    page.tabs.show("node");
    scheduleDraw();
  },
  /** Plots an object of a node (set by the plots panel; null without one): plot(key, object). */
  plot: null,
  /** Draws soon (after a user's action, not only after the next exchange). */
  redraw: scheduleDraw,
  /** Runs an exchange now rather than at the next tick (after a user's action, so its answer comes sooner). */
  exchangeSoon: () => exchangeNow(),
};

const overview = new Overview(document.getElementById("nodes"), document.getElementById("status"),
  (key) => {
    if (!nodes.isHeard(key)) {
      page.select(key);
    }
  });
page.tabs = new Tabs(document.getElementById("tabs"), (name, previous) => {
  for (const p of panels) {
    if (p.view === previous) {
      p.shown?.(false);
    }
    if (p.view === name) {
      p.shown?.(true);
    }
  }
  scheduleDraw();
});
panels = panelMakers.map((make) => make(page));
for (const p of panels) {
  if (p.view === page.tabs.current) {
    p.shown?.(true);
  }
}

let streamTried = -Infinity; // performance.now() when the stream was last opened

/** Opens the session's WebSocket (or stream) if it has none (at most once per STREAM_RETRY_MS): from then on
 * answers and events come as they are made, and an idle page sends nothing. */
function listen(ms) {
  if (session.streaming || ms - streamTried < STREAM_RETRY_MS) {
    return;
  }
  streamTried = ms;
  session.listen()
    .catch((error) => console.warn("canopen-emu: no WebSocket or stream:", error.message))
    .finally(scheduleDraw);
}

let running = null; // the exchange under way; null: none
let again = false; // an exchange was asked for while one ran: one more right after it
let timer = null;

async function exchangeNow() {
  if (running !== null) {
    again = true;
    return running;
  }
  clearTimeout(timer);
  running = (async () => {
    const ms = performance.now();
    try {
      if (!showAsked && ms - lastShow >= SHOW_MS) {
        askShow();
      }
      for (const p of panels) {
        p.tick?.(session, ms);
      }
      await session.exchange();
      exchangeProblem = null;
      listen(ms);
    } catch (error) {
      // fetch's TypeError: no HTTP answer at all
      exchangeProblem = error instanceof TypeError ? "the emulator does not answer (stopped?)" : error.message;
    }
    scheduleDraw();
  })();
  await running;
  running = null;
  if (again) {
    again = false;
    return exchangeNow();
  }
  timer = setTimeout(exchangeNow, EXCHANGE_MS);
  return undefined;
}

exchangeNow();
