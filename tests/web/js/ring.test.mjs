// web/ring.js: the trace's bounded buffer.
import {test} from "node:test";
import assert from "node:assert/strict";

import {Ring} from "../../../web/ring.js";

test("a ring keeps its items oldest first until it is full", () => {
  const ring = new Ring(3);
  assert.equal(ring.capacity, 3);
  assert.deepEqual([...ring], []);
  ring.push("a");
  ring.push("b");
  assert.equal(ring.length, 2);
  assert.deepEqual([...ring], ["a", "b"]);
  assert.equal(ring.at(0), "a");
  assert.equal(ring.at(1), "b");
  assert.equal(ring.at(2), undefined);
  assert.equal(ring.at(-1), undefined);
  assert.equal(ring.dropped, 0);
});

test("a full ring pushes out its oldest items and counts them", () => {
  const ring = new Ring(3);
  for (let i = 1; i <= 10; i++) {
    ring.push(i);
  }
  assert.equal(ring.length, 3);
  assert.deepEqual([...ring], [8, 9, 10]);
  assert.deepEqual([0, 1, 2].map((i) => ring.at(i)), [8, 9, 10]);
  assert.equal(ring.dropped, 7);
});

test("20,000 frames bound: 25,000 pushed keep the last 20,000", () => {
  const ring = new Ring(20_000);
  for (let i = 0; i < 25_000; i++) {
    ring.push(i);
  }
  assert.equal(ring.length, 20_000);
  assert.equal(ring.dropped, 5_000);
  assert.equal(ring.at(0), 5_000);
  assert.equal(ring.at(19_999), 24_999);
  const all = [...ring];
  assert.equal(all.length, 20_000);
  assert.ok(all.every((v, i) => v === 5_000 + i));
});

test("clear empties the ring and its count; it fills again from the start", () => {
  const ring = new Ring(2);
  for (const v of ["a", "b", "c"]) {
    ring.push(v);
  }
  ring.clear();
  assert.equal(ring.length, 0);
  assert.equal(ring.dropped, 0);
  assert.deepEqual([...ring], []);
  ring.push("d");
  assert.deepEqual([...ring], ["d"]);
});

test("a ring needs room for one item at least", () => {
  assert.throws(() => new Ring(0), RangeError);
  assert.throws(() => new Ring(1.5), RangeError);
  assert.equal(new Ring(1).capacity, 1);
});
