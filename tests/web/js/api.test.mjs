// web/api.js: the page's session over HTTP, against a stand-in for the emulator's /api (docs/web.md "HTTP API").
import {test} from "node:test";
import assert from "node:assert/strict";

import {Session, poster, streamer} from "../../../web/api.js";

/** A stand-in emulator: records every post; answers each with the next of `replies` (a function of the post, or a
 * {status, text}); an Error in replies is thrown as fetch throws when nothing answers. */
function fakeApi(replies) {
  const posts = [];
  const post = async (path, body) => {
    posts.push({path, body});
    const reply = replies.shift();
    assert.ok(reply !== undefined, `no reply left for ${path} ${body}`);
    if (reply instanceof Error) {
      throw reply;
    }
    return typeof reply === "function" ? reply(path, body) : reply;
  };
  return {post, posts};
}

const opened = (id) => ({status: 200, text: JSON.stringify({session: id})});
const lines = (...objects) => ({status: 200, text: objects.map((o) => JSON.stringify(o) + "\n").join("")});

test("poster sends the token and the body, and gives status and text", async () => {
  const calls = [];
  const post = poster("ab".repeat(16), async (path, options) => {
    calls.push({path, options});
    return {status: 200, text: async () => "{}\n"};
  });
  assert.deepEqual(await post("/api/session/x", "line"), {status: 200, text: "{}\n"});
  assert.deepEqual(calls, [{path: "/api/session/x", options: {
    method: "POST", headers: {"X-Canopen-Emu": "ab".repeat(16), "Content-Type": "application/x-ndjson"},
    body: "line", cache: "no-store"}}]);
});

test("opens a session, runs onOpen first, posts the queued requests and matches answers by id", async () => {
  const events = [];
  const api = fakeApi([opened("s1"),
    lines({id: 2, ok: true, events: ["nmt"]}, {event: "nmt", node: 16}, {id: 1, ok: true, nodes: []})]);
  const session = new Session(api.post, {
    onOpen: (s) => { s.request("subscribe", {events: ["nmt"]}).then((a) => events.push(["subscribed", a.events])); },
    onEvent: (e) => events.push(["event", e.node]),
  });
  const shown = session.request("show", {node: "all"});
  await session.exchange();
  assert.deepEqual(await shown, {id: 1, ok: true, nodes: []});
  assert.deepEqual(api.posts, [
    {path: "/api/session", body: ""},
    {path: "/api/session/s1", body: '{"id":2,"cmd":"subscribe","events":["nmt"]}\n{"id":1,"cmd":"show","node":"all"}'},
  ]);
  assert.deepEqual(events, [["event", 16], ["subscribed", ["nmt"]]]); // events at once; answers a microtask later
});

test("an answer that comes with a later exchange still finds its request; errors reject", async () => {
  const stray = [];
  const api = fakeApi([opened("s1"), lines(), lines({id: 1, ok: false, error: "no node 99"}, {id: 2, ok: true}),
    {status: 200, text: "error: web session line 3 is longer than 2047 bytes: ignored\n{\"id\":null,\"ok\":false}\n"}]);
  const session = new Session(api.post, {onStray: (line) => stray.push(line)});
  const refused = session.request("show", {node: 99});
  const later = session.request("hello");
  await session.exchange();
  await session.exchange();
  await assert.rejects(refused, {message: "no node 99"});
  assert.deepEqual(await later, {id: 2, ok: true});
  await session.exchange();
  assert.deepEqual(stray, ["error: web session line 3 is longer than 2047 bytes: ignored", '{"id":null,"ok":false}']);
  assert.deepEqual(api.posts.map((p) => p.body), ["", '{"id":1,"cmd":"show","node":99}\n{"id":2,"cmd":"hello"}', "", ""]);
});

test("a long answer that comes in pieces over several exchanges is taken whole, once complete", async () => {
  const whole = JSON.stringify({id: 1, ok: true, node: 5, objects: Array.from({length: 50}, (_, k) => ({k}))});
  const api = fakeApi([opened("s1"), {status: 200, text: whole.slice(0, 100)}, {status: 200, text: whole.slice(100, 300)},
    {status: 200, text: whole.slice(300) + "\n" + JSON.stringify({event: "nmt", node: 5}) + "\n{\"id\":2,"},
    {status: 200, text: "\"ok\":true}\n"}]);
  const events = [];
  const session = new Session(api.post, {onEvent: (e) => events.push(e)});
  let done = null;
  session.request("objects", {node: 5}).then((answer) => { done = answer; });
  const second = session.request("hello");
  await session.exchange();
  await session.exchange();
  await new Promise((resolve) => setImmediate(resolve));
  assert.equal(done, null); // not yet complete: nothing taken, no stray line
  await session.exchange();
  await new Promise((resolve) => setImmediate(resolve));
  assert.equal(done.objects.length, 50);
  assert.deepEqual(events, [{event: "nmt", node: 5}]);
  await session.exchange();
  assert.deepEqual(await second, {id: 2, ok: true});
});

test("404: the requests posted fail, a new session is opened and onOpen subscribes again", async () => {
  const subscribed = [];
  const api = fakeApi([opened("s1"), lines(), {status: 404, text: '{"error":"no such session"}'},
    opened("s2"), lines({id: 4, ok: true}, {id: 3, ok: true, nodes: [1]})]);
  const session = new Session(api.post, {
    onOpen: (s) => subscribed.push(s.request("subscribe", {events: ["nmt"]}).then((a) => a.id, (e) => e.message)),
  });
  await session.exchange(); // s1, with its subscribe (id 1, never answered)
  const lost = session.request("show", {node: "all"}); // id 2
  await assert.rejects(session.exchange(), {message: "the session expired; opening a new one"});
  await assert.rejects(lost, {message: "the session ended before it answered"});
  const again = session.request("show", {node: "all"}); // id 3, goes to s2 behind its subscribe (id 4)
  await session.exchange();
  assert.deepEqual(await again, {id: 3, ok: true, nodes: [1]});
  assert.deepEqual(await Promise.all(subscribed), ["the session ended before it answered", 4]);
  assert.deepEqual(api.posts.map((p) => [p.path, p.body]), [
    ["/api/session", ""], ["/api/session/s1", '{"id":1,"cmd":"subscribe","events":["nmt"]}'],
    ["/api/session/s1", '{"id":2,"cmd":"show","node":"all"}'],
    ["/api/session", ""], ["/api/session/s2", '{"id":4,"cmd":"subscribe","events":["nmt"]}\n{"id":3,"cmd":"show","node":"all"}'],
  ]);
});

test("no answer at all: the requests posted fail (never sent twice), the session is kept", async () => {
  const api = fakeApi([opened("s1"), new TypeError("Failed to fetch"), lines({id: 2, ok: true})]);
  const session = new Session(api.post);
  const lost = session.request("set", {node: 16, object: "0x1017", value: 500});
  await assert.rejects(session.exchange(), TypeError);
  await assert.rejects(lost, {message: "no answer: Failed to fetch"});
  const next = session.request("hello");
  await session.exchange();
  assert.deepEqual(await next, {id: 2, ok: true});
  assert.deepEqual(api.posts.map((p) => p.path), ["/api/session", "/api/session/s1", "/api/session/s1"]);
  assert.equal(api.posts[2].body, '{"id":2,"cmd":"hello"}');
});

test("429: the lines were not taken and go again with the next exchange", async () => {
  const api = fakeApi([opened("s1"), {status: 429, text: '{"error":"earlier requests still wait"}'},
    lines({id: 1, ok: true, program: "canopen-emu"})]);
  const session = new Session(api.post);
  const hello = session.request("hello");
  await session.exchange();
  const list = session.request("list");
  await session.exchange();
  assert.equal((await hello).program, "canopen-emu");
  assert.deepEqual(api.posts.slice(1).map((p) => p.body), ['{"id":1,"cmd":"hello"}', '{"id":1,"cmd":"hello"}\n{"id":2,"cmd":"list"}']);
  const pending = Symbol("pending");
  assert.equal(await Promise.race([list, Promise.resolve(pending)]), pending); // list (id 2): no answer yet
});

test("other refusals: the error the emulator gives, and a session that cannot be opened", async () => {
  const api = fakeApi([{status: 503, text: '{"error":"too many web sessions (at most 8)"}'}, opened("s1"),
    {status: 403, text: '{"error":"missing or wrong X-Canopen-Emu token: load the page again"}'},
    {status: 500, text: "not json\n"}]);
  const session = new Session(api.post);
  await assert.rejects(session.exchange(), {message: "HTTP 503: too many web sessions (at most 8)"});
  const refused = session.request("hello");
  await assert.rejects(session.exchange(), {message: "HTTP 403: missing or wrong X-Canopen-Emu token: load the page again"});
  await assert.rejects(refused, {message: "HTTP 403: missing or wrong X-Canopen-Emu token: load the page again"});
  await assert.rejects(session.exchange(), {message: "HTTP 500: not json"});
  assert.deepEqual(api.posts.map((p) => p.path), ["/api/session", "/api/session", "/api/session/s1", "/api/session/s1"]);
});

/** A stand-in stream: the test pushes text pieces and ends it; records the path and the signal it was opened with. */
function fakeStream() {
  const pieces = [];
  let wake = null;
  let ended = false;
  const opened = [];
  const push = (text) => {
    pieces.push(text);
    wake?.();
  };
  const end = () => {
    ended = true;
    wake?.();
  };
  async function* chunks(signal) {
    for (;;) {
      while (pieces.length > 0) {
        yield pieces.shift();
      }
      if (ended || signal.aborted) {
        return;
      }
      await new Promise((resolve) => {
        wake = resolve;
        signal.addEventListener("abort", resolve, {once: true});
      });
      wake = null;
    }
  }
  const open = async (path, signal) => {
    opened.push({path, signal});
    return {status: 200, chunks: chunks(signal)};
  };
  return {open, push, end, opened};
}

const tick = () => new Promise((resolve) => setTimeout(resolve, 0));

test("streamer sends the token and an empty body with the signal, and gives the text as it comes", async () => {
  const calls = [];
  const euro = new TextEncoder().encode("€\n"); // three bytes: split across two pieces
  const body = new ReadableStream({
    start(controller) {
      controller.enqueue(new TextEncoder().encode('{"event":"nmt"}\n'));
      controller.enqueue(euro.slice(0, 2));
      controller.enqueue(euro.slice(2));
      controller.close();
    },
  });
  const open = streamer("cd".repeat(16), async (path, options) => {
    calls.push({path, options});
    return {status: 200, body};
  });
  const signal = new AbortController().signal;
  const answer = await open("/api/session/s1/stream", signal);
  assert.equal(answer.status, 200);
  const texts = [];
  for await (const text of answer.chunks) {
    texts.push(text);
  }
  assert.equal(texts.join(""), '{"event":"nmt"}\n€\n');
  assert.deepEqual(calls, [{path: "/api/session/s1/stream", options: {
    method: "POST", headers: {"X-Canopen-Emu": "cd".repeat(16)}, body: "", cache: "no-store", signal}}]);
  const refused = streamer("cd".repeat(16), async () => ({status: 404, text: async () => '{"error":"gone"}'}));
  assert.deepEqual(await refused("/api/session/s2/stream", signal), {status: 404, text: '{"error":"gone"}'});
});

test("with the stream open, answers and events come on it and an exchange posts only when requests wait", async () => {
  const stream = fakeStream();
  const api = fakeApi([opened("s1"), lines({id: 1, ok: true}), lines()]);
  const seen = [];
  let data = 0;
  const session = new Session(api.post, {openStream: stream.open, onEvent: (e) => seen.push(e.node),
    onData: () => { data++; }});
  const first = session.request("hello");
  await session.exchange(); // opens s1, posts hello: answered with the exchange (no stream yet)
  assert.deepEqual(await first, {id: 1, ok: true});
  const listening = session.listen();
  assert.equal(session.streaming, true);
  assert.deepEqual(stream.opened.map((o) => o.path), ["/api/session/s1/stream"]);
  await session.exchange(); // nothing queued: nothing posted
  assert.equal(api.posts.length, 2);
  stream.push('{"event":"nmt","node":16}\n{"event":"nmt",');
  stream.push('"node":17}\n\n'); // a line across two pieces; an empty line (the keep-alive)
  await tick();
  assert.deepEqual(seen, [16, 17]);
  assert.equal(data, 2);
  const second = session.request("show", {node: 16});
  await session.exchange(); // a request waits: posted, answered empty, its answer comes on the stream
  assert.deepEqual(api.posts.map((p) => p.body), ["", '{"id":1,"cmd":"hello"}', '{"id":2,"cmd":"show","node":16}']);
  stream.push('{"id":2,"ok":true,"node":16}\n');
  assert.deepEqual(await second, {id: 2, ok: true, node: 16});
  stream.end(); // the emulator ended it: exchanges carry everything again
  await listening;
  assert.equal(session.streaming, false);
  await assert.rejects(session.exchange(), /no reply left/); // posted although nothing was queued
});

test("a stream that brings nothing for quietMs is given up; one that is refused rejects", async () => {
  const stream = fakeStream();
  const api = fakeApi([opened("s1"), lines()]);
  const session = new Session(api.post, {openStream: stream.open});
  await session.exchange();
  await session.listen({quietMs: 20}); // resolves once the watchdog aborted it
  assert.equal(stream.opened[0].signal.aborted, true);
  assert.equal(session.streaming, false);
  const refused = new Session(fakeApi([opened("s2"), lines()]).post,
    {openStream: async () => ({status: 404, text: '{"error":"no such session (expired or dropped): open a new one"}'})});
  await refused.exchange();
  await assert.rejects(refused.listen(), {message: "HTTP 404: no such session (expired or dropped): open a new one"});
  assert.equal(refused.streaming, false);
  const none = new Session(fakeApi([]).post); // no openStream: listen does nothing
  await none.listen();
  assert.equal(none.streaming, false);
});

test("a stream of a session that ended gives nothing more to the new one", async () => {
  const stream = fakeStream();
  const api = fakeApi([opened("s1"), lines(), {status: 404, text: '{"error":"no such session"}'}, opened("s2"),
    lines()]);
  const seen = [];
  const session = new Session(api.post, {openStream: stream.open, onEvent: (e) => seen.push(e.node)});
  await session.exchange();
  const listening = session.listen();
  const lost = session.request("hello");
  await assert.rejects(session.exchange(), {message: "the session expired; opening a new one"});
  await assert.rejects(lost, {message: "the session ended before it answered"});
  assert.equal(session.streaming, false); // its stream was s1's
  await session.exchange(); // s2
  stream.push('{"event":"nmt","node":5}\n'); // a late line of s1's stream
  await listening;
  assert.deepEqual(seen, []);
});

/** A stand-in WebSocket: records the paths opened and the messages sent; the test opens, feeds and closes it. */
function fakeSockets() {
  const made = [];
  const open = (path) => {
    const socket = {path, sent: [], closed: false, onopen: null, onmessage: null, onclose: null,
      send(text) { this.sent.push(text); },
      close() { if (!this.closed) { this.closed = true; this.onclose?.({code: 1000}); } }};
    made.push(socket);
    return socket;
  };
  return {open, made};
}

test("with the WebSocket open, requests go out on it, answers and events come on it, nothing is posted", async () => {
  const sockets = fakeSockets();
  const api = fakeApi([opened("s1"), lines(), lines(), lines()]);
  const seen = [];
  let data = 0;
  const session = new Session(api.post, {openSocket: sockets.open, onEvent: (e) => seen.push(e.node),
    onData: () => { data++; }});
  await session.exchange(); // opens s1
  const listening = session.listen();
  assert.equal(session.streaming, true);
  const socket = sockets.made[0];
  assert.equal(socket.path, "/api/session/s1/socket");
  const early = session.request("hello");
  await session.exchange(); // not open yet: posted
  assert.deepEqual(api.posts.map((p) => p.body), ["", "", '{"id":1,"cmd":"hello"}']);
  const queued = session.request("show", {node: 16});
  socket.onopen();
  assert.deepEqual(socket.sent, ['{"id":2,"cmd":"show","node":16}']); // what waited goes at once
  socket.onmessage({data: '{"id":1,"ok":true}\n{"event":"nmt","node":16}\n{"id":2,'});
  socket.onmessage({data: '"ok":true}\n\n'});
  assert.deepEqual(await early, {id: 1, ok: true});
  assert.deepEqual(await queued, {id: 2, ok: true});
  assert.deepEqual(seen, [16]);
  assert.equal(data, 2);
  const third = session.request("list");
  const fourth = session.request("hello");
  await session.exchange(); // on the socket, as one message; no post
  assert.deepEqual(socket.sent.slice(1), ['{"id":3,"cmd":"list"}\n{"id":4,"cmd":"hello"}']);
  assert.equal(api.posts.length, 3);
  await session.exchange(); // nothing queued: nothing sent
  assert.equal(socket.sent.length, 2);
  socket.onmessage({data: '{"id":3,"ok":true}\n'});
  assert.deepEqual(await third, {id: 3, ok: true});
  socket.close(); // the emulator closed it: what it did not answer fails, the exchanges carry everything again
  await assert.rejects(fourth, {message: "no answer: the socket closed"});
  await listening;
  assert.equal(session.streaming, false);
  await session.exchange();
  assert.equal(api.posts.length, 4);
});

test("a WebSocket that does not open: the stream is used instead, until a new session", async () => {
  const sockets = fakeSockets();
  const stream = fakeStream();
  const api = fakeApi([opened("s1"), lines()]);
  const session = new Session(api.post, {openSocket: sockets.open, openStream: stream.open});
  await session.exchange();
  const first = session.listen();
  sockets.made[0].close(); // refused: closed before it opened
  await assert.rejects(first, {message: "the WebSocket did not open"});
  assert.equal(session.streaming, false);
  const second = session.listen();
  assert.deepEqual(stream.opened.map((o) => o.path), ["/api/session/s1/stream"]);
  assert.equal(sockets.made.length, 1);
  stream.end();
  await second;
});

test("a WebSocket silent for quietMs is closed and the exchanges carry everything again", async () => {
  const sockets = fakeSockets();
  const api = fakeApi([opened("s1"), lines(), lines()]);
  const session = new Session(api.post, {openSocket: sockets.open});
  await session.exchange();
  const quiet = session.listen({quietMs: 20});
  sockets.made[0].onopen();
  await quiet; // the watchdog closed it
  assert.equal(sockets.made[0].closed, true);
  assert.equal(session.streaming, false);
  await session.exchange();
  assert.equal(api.posts.length, 3);
});
