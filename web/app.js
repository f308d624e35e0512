// The web view of canopen-emu (docs/web.md): the overview of every node. The page is a control-protocol client
// (docs/control-protocol.md) over one web session: it exchanges every 250 ms, asks `show all` once a second, and
// takes the events nmt, boot-up, emcy and fault in between, so that a change shows with the next exchange.

import {Session, poster} from "./api.js";
import {NodeTable} from "./nodes.js";
import {Overview} from "./overview.js";

const EXCHANGE_MS = 250;
const SHOW_MS = 1000;
const EVENTS = ["nmt", "boot-up", "emcy", "fault"];

const token = document.querySelector('meta[name="canopen-emu-token"]').content;
const nodes = new NodeTable();
const view = new Overview(document.getElementById("nodes"), document.getElementById("status"));
let exchangeProblem = "connecting"; // why the last exchange failed; null: it did not
let requestProblem = null; // why the last show (or the subscribe) failed; null: it did not
let showAsked = false; // a show is on its way: never a second one, however slow the answers come
let lastShow = -Infinity; // performance.now() of the last show asked

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

const session = new Session(poster(token), {
  onOpen: (s) => {
    s.request("subscribe", {events: EVENTS}).catch((error) => { requestProblem = `subscribe: ${error.message}`; });
    lastShow = -Infinity; // a new session: everything anew, at once
  },
  onEvent: (event) => nodes.event(event, performance.now()),
  onStray: (line) => console.warn("canopen-emu: a line no request of this page asked for:", line),
});

async function loop() {
  try {
    if (!showAsked && performance.now() - lastShow >= SHOW_MS) {
      askShow();
    }
    await session.exchange();
    exchangeProblem = null;
  } catch (error) {
    // fetch's TypeError: no HTTP answer at all
    exchangeProblem = error instanceof TypeError ? "the emulator does not answer (stopped?)" : error.message;
  }
  view.schedule(() => ({rows: nodes.rows(performance.now()), problem: exchangeProblem ?? requestProblem}));
  setTimeout(loop, EXCHANGE_MS);
}

loop();
