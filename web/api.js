// The page's control session over HTTP (docs/web.md "HTTP API"): request lines of the control protocol
// (docs/control-protocol.md) are queued, posted with the next exchange, and answered by a later one, matched by
// their id. While the session's WebSocket is open (listen()), requests go out on it as messages and every answer
// and event comes on it as the emulator makes them: no exchange at all. Where no WebSocket opens, the session's
// stream brings the answers and events, and an exchange is made only when requests wait; without either, answers
// and events come with the exchanges.
// A session that expired or was dropped (404) is replaced by a new one, and the page's onOpen runs again to
// subscribe anew. No DOM: tested with node --test (tests/web/js).

/** A POST that resolves to {status, text}; `fetchImpl` is the browser's fetch (a stand-in in the tests). */
export function poster(token, fetchImpl = globalThis.fetch) {
  return async (path, body) => {
    const answer = await fetchImpl(path, {
      method: "POST",
      headers: {"X-Canopen-Emu": token, "Content-Type": "application/x-ndjson"},
      body,
      cache: "no-store",
    });
    return {status: answer.status, text: await answer.text()};
  };
}

/** A stream's text as it comes, decoded as UTF-8 across the pieces' boundaries. */
async function* textOf(body) {
  const reader = body.getReader();
  const decoder = new TextDecoder();
  try {
    for (;;) {
      const {value, done} = await reader.read();
      if (done) {
        return;
      }
      yield decoder.decode(value, {stream: true});
    }
  } finally {
    reader.cancel().catch(() => {}); // an abandoned stream's connection is closed
  }
}

/** A POST that opens a stream: resolves to {status: 200, chunks} (an async iterable of its text as it comes) or,
 * refused, to {status, text}; `signal` (an AbortSignal) ends it. */
export function streamer(token, fetchImpl = globalThis.fetch) {
  return async (path, signal) => {
    const answer = await fetchImpl(path, {
      method: "POST",
      headers: {"X-Canopen-Emu": token},
      body: "",
      cache: "no-store",
      signal,
    });
    if (answer.status !== 200) {
      return {status: answer.status, text: await answer.text()};
    }
    return {status: 200, chunks: textOf(answer.body)};
  };
}

/** What an /api answer other than 200 says: its JSON "error", else its text. */
function failure(answer) {
  let said = answer.text.trim();
  try {
    said = JSON.parse(answer.text).error ?? said;
  } catch {
    // not JSON: the text as it is
  }
  return new Error(`HTTP ${answer.status}: ${said}`);
}

/** A stream that brings nothing for this long is given up (the emulator sends an empty line after 5 s of silence). */
export const STREAM_QUIET_MS = 15000;

export class Session {
  #post;
  #openSocket;
  #openStream;
  #onOpen;
  #onEvent;
  #onStray;
  #onData;
  #id = null; // the session's id; null: open one with the next exchange
  #streamOf = null; // the id of the session whose socket or stream is open (or opening); null: none
  #socket = null; // the open WebSocket; null: none (requests go with exchanges)
  #socketRefused = false; // a socket never opened: the stream is used instead
  #nextId = 1; // request ids go on across sessions, so that a late answer never matches a newer request
  #queue = []; // {id, line} of the requests not yet posted
  #waiting = new Map(); // request id -> {resolve, reject} until its answer comes
  #partial = ""; // the start of a line a later exchange completes (a long answer comes in pieces: `objects`)

  /**
   * post: (path, body) => Promise<{status, text}> (poster()). openSocket: path => a WebSocket (or an object with
   * its send, close, onopen, onmessage, onclose); null: none. openStream: (path, signal) => a stream (streamer());
   * null: none. onOpen(session): after each new session, before its first exchange: subscribe here.
   * onEvent(event): each event, in order. onStray(line): a line that is neither an event nor the answer to a request
   * waiting (a refusal of a line the emulator could not read). onData(): after each piece of a stream was taken.
   */
  constructor(post, {openSocket = null, openStream = null, onOpen = () => {}, onEvent = () => {}, onStray = () => {},
    onData = () => {}} = {}) {
    this.#post = post;
    this.#openSocket = openSocket;
    this.#openStream = openStream;
    this.#onOpen = onOpen;
    this.#onEvent = onEvent;
    this.#onStray = onStray;
    this.#onData = onData;
  }

  /** Whether the session's socket or stream is open (or opening): its answers and events come on it. */
  get streaming() {
    return this.#streamOf !== null && this.#streamOf === this.#id;
  }

  /** Queues a JSON request; resolves to its answer (ok true), rejects with its error (ok false) or when the
   * session ends before it answered. */
  request(cmd, fields = {}) {
    const id = this.#nextId++;
    this.#queue.push({id, line: JSON.stringify({id, cmd, ...fields})});
    return new Promise((resolve, reject) => this.#waiting.set(id, {resolve, reject}));
  }

  /** One round trip: opens a session first if there is none, posts the queued requests, hands out what came back.
   * Rejects when the emulator cannot be reached or refuses the exchange; the next exchange tries again. */
  async exchange() {
    if (this.#socket !== null) {
      this.#sendQueued();
      return;
    }
    if (this.streaming && this.#queue.length === 0) {
      return; // nothing to ask: what the emulator has comes on the stream
    }
    if (this.#id === null) {
      const opened = await this.#post("/api/session", "");
      if (opened.status !== 200) {
        throw failure(opened);
      }
      this.#id = JSON.parse(opened.text).session;
      this.#socketRefused = false; // a new session tries its WebSocket again
      const queued = this.#queue;
      this.#queue = [];
      this.#onOpen(this); // its requests (subscribe) go before those queued while there was no session
      this.#queue.push(...queued);
    }
    const sent = this.#queue;
    this.#queue = [];
    let answer;
    try {
      answer = await this.#post(`/api/session/${this.#id}`, sent.map((r) => r.line).join("\n"));
    } catch (error) {
      this.#endPosted(new Error(`no answer: ${error.message}`)); // they may or may not have run: never sent twice
      throw error;
    }
    if (answer.status === 429) {
      this.#queue = sent.concat(this.#queue); // not taken (earlier lines still wait): they go with the next one
      return;
    }
    if (answer.status === 404) {
      this.#id = null;
      this.#partial = "";
      this.#endPosted(new Error("the session ended before it answered"));
      throw new Error("the session expired; opening a new one");
    }
    if (answer.status !== 200) {
      this.#endPosted(failure(answer));
      throw failure(answer);
    }
    this.#takeText(answer.text);
  }

  /**
   * Opens the session's WebSocket (or, where none opened before, its stream) and takes what comes on it until it
   * ends: the emulator ended it (the session ended), the connection broke, nothing came for quietMs, or a newer
   * session replaced this one. Resolves then (the exchanges carry everything again); rejects when it was refused.
   * Does nothing without a session or a way to open either, or when one is open already.
   */
  async listen({quietMs = STREAM_QUIET_MS} = {}) {
    const socket = this.#openSocket !== null && !this.#socketRefused;
    if ((!socket && this.#openStream === null) || this.#id === null || this.streaming) {
      return;
    }
    const id = this.#id;
    this.#streamOf = id;
    if (socket) {
      await this.#listenSocket(id, quietMs);
      return;
    }
    const ending = new AbortController();
    let quiet = setTimeout(() => ending.abort(), quietMs);
    try {
      const answer = await this.#openStream(`/api/session/${id}/stream`, ending.signal);
      if (answer.status !== 200) {
        throw failure(answer);
      }
      for await (const text of answer.chunks) {
        if (this.#id !== id) {
          break; // lines of a session that ended
        }
        clearTimeout(quiet);
        quiet = setTimeout(() => ending.abort(), quietMs);
        this.#takeText(text);
        this.#onData();
      }
    } catch (error) {
      if (!ending.signal.aborted) {
        throw error;
      }
    } finally {
      clearTimeout(quiet);
      ending.abort();
      if (this.#streamOf === id) {
        this.#streamOf = null;
      }
    }
  }

  /** The WebSocket's life: requests out as messages once it is open, lines in as they come. */
  #listenSocket(id, quietMs) {
    return new Promise((resolve, reject) => {
      let socket;
      try {
        socket = this.#openSocket(`/api/session/${id}/socket`);
      } catch (error) { // no WebSocket here (a policy forbids it)
        this.#socketRefused = true;
        this.#streamOf = null;
        reject(error);
        return;
      }
      let opened = false;
      let quiet = null;
      const rearm = () => {
        clearTimeout(quiet);
        quiet = setTimeout(() => socket.close(), quietMs);
      };
      rearm();
      socket.onopen = () => {
        opened = true;
        if (this.#id !== id) {
          socket.close();
          return;
        }
        this.#socket = socket;
        this.#sendQueued();
      };
      socket.onmessage = (message) => {
        if (this.#id !== id) {
          socket.close(); // lines of a session that ended
          return;
        }
        rearm();
        this.#takeText(message.data);
        this.#onData();
      };
      socket.onclose = () => {
        clearTimeout(quiet);
        if (this.#socket === socket) {
          this.#socket = null;
          this.#endPosted(new Error("no answer: the socket closed")); // they may or may not have run
        }
        if (this.#streamOf === id) {
          this.#streamOf = null;
        }
        if (opened) {
          resolve();
        } else {
          this.#socketRefused = true;
          reject(new Error("the WebSocket did not open"));
        }
      };
    });
  }

  /** The queued requests as one message on the socket. */
  #sendQueued() {
    if (this.#queue.length > 0) {
      this.#socket.send(this.#queue.map((r) => r.line).join("\n"));
      this.#queue = [];
    }
  }

  /** Text of an exchange or a stream: its whole lines taken, the start of a line a later piece completes kept. */
  #takeText(text) {
    const lines = (this.#partial + text).split("\n");
    this.#partial = lines.pop(); // "" when the text ended with a whole line
    for (const line of lines) {
      if (line !== "") { // "": the stream's keep-alive
        this.#take(line);
      }
    }
  }

  #take(line) {
    let message = null;
    try {
      message = line.startsWith("{") ? JSON.parse(line) : null;
    } catch {
      // not an answer of ours: a stray line
    }
    if (message !== null && "event" in message) {
      this.#onEvent(message);
      return;
    }
    const waiting = message === null ? undefined : this.#waiting.get(message.id);
    if (waiting === undefined) {
      this.#onStray(line);
      return;
    }
    this.#waiting.delete(message.id);
    if (message.ok) {
      waiting.resolve(message);
    } else {
      waiting.reject(new Error(message.error));
    }
  }

  /** Every request posted and not answered fails with `error`; those queued since go with the next exchange. */
  #endPosted(error) {
    const queued = new Set(this.#queue.map((r) => r.id));
    for (const [id, {reject}] of this.#waiting) {
      if (!queued.has(id)) {
        this.#waiting.delete(id);
        reject(error);
      }
    }
  }
}
