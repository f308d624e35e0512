// The web view of canopen-emu, first page (docs/web.md): one control session over HTTP, the nodes' list asked for
// every 250 ms. The page is a control-protocol client (docs/control-protocol.md): each exchange posts request
// lines and gets back every line queued for the session since the last one (answers and subscribed events).

const token = document.querySelector('meta[name="canopen-emu-token"]').content;
const statusLine = document.getElementById("status");
const rows = document.querySelector("#nodes tbody");
const PERIOD_MS = 250;

let session = null; // the id of our session; null: make one (at start, or after it expired)
let nextId = 1;

function post(path, body) {
  return fetch(path, {
    method: "POST",
    headers: {"X-Canopen-Emu": token, "Content-Type": "application/x-ndjson"},
    body,
    cache: "no-store",
  });
}

async function openSession() {
  const answer = await post("/api/session", "");
  if (!answer.ok) {
    throw new Error(`no session: HTTP ${answer.status} ${(await answer.json()).error ?? ""}`);
  }
  session = (await answer.json()).session;
}

function showNodes(nodes) {
  const fresh = document.createDocumentFragment();
  for (const node of nodes) {
    const tr = document.createElement("tr");
    for (const value of [node.node, node.device, node.bus, node.state]) {
      const td = document.createElement("td");
      td.textContent = String(value); // text, never markup: nothing the emulator says becomes HTML
      tr.append(td);
    }
    fresh.append(tr);
  }
  rows.replaceChildren(fresh);
  statusLine.textContent = `${nodes.length} node(s)`;
}

async function exchange() {
  if (session === null) {
    await openSession();
  }
  const id = nextId++;
  const answer = await post(`/api/session/${session}`, JSON.stringify({id, cmd: "list"}) + "\n");
  if (answer.status === 404) {
    session = null; // expired or dropped: the next exchange makes a new one
    throw new Error("session expired; reconnecting");
  }
  if (!answer.ok) {
    throw new Error(`HTTP ${answer.status}`);
  }
  for (const line of (await answer.text()).split("\n")) {
    if (line !== "") {
      const message = JSON.parse(line);
      if (message.id === id && message.ok) {
        showNodes(message.nodes);
      }
    }
  }
}

async function loop() {
  try {
    await exchange();
  } catch (error) {
    statusLine.textContent = error.message;
  }
  setTimeout(loop, PERIOD_MS);
}

loop();
