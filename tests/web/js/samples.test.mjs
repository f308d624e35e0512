// web/samples.js: a node's samples for the plots, bounded by count and age; the values as numbers to plot.
import {test} from "node:test";
import assert from "node:assert/strict";

import {SampleBuffer, plottable} from "../../../web/samples.js";

test("plottable: numbers, BOOLEAN as 0/1, UNSIGNED64 strings; a gap for what is no finite number", () => {
  assert.equal(plottable(1234), 1234);
  assert.equal(plottable(-2.5), -2.5);
  assert.equal(plottable(true), 1);
  assert.equal(plottable(false), 0);
  assert.equal(plottable("18446744073709551615"), 18446744073709551615);
  for (const gap of ["nan", "inf", "-inf", "ES61", "0A1B", undefined, null, NaN, Infinity]) {
    assert.equal(plottable(gap), null, String(gap));
  }
});

test("a sample adds a time (s) and a value to each column; a column added later is null before", () => {
  const b = new SampleBuffer();
  b.addColumn("0x6401:01");
  assert.equal(b.push(1_000_000, new Map([["0x6401:01", 230], ["0x9999:00", 5]])), true);
  b.addColumn("0x6000:01");
  b.addColumn("0x6401:01"); // already there: kept as it is
  assert.equal(b.push(1_250_000, new Map([["0x6401:01", 231], ["0x6000:01", "nan"]])), true);
  assert.equal(b.push(1_500_000, new Map([["0x6000:01", 7]])), true); // 0x6401:01 not answered: a gap
  assert.deepEqual(b.times, [1, 1.25, 1.5]);
  assert.deepEqual(b.column("0x6401:01"), [230, 231, null]);
  assert.deepEqual(b.column("0x6000:01"), [null, null, 7]);
  assert.equal(b.column("0x9999:00"), undefined);
  assert.deepEqual(b.columns, ["0x6401:01", "0x6000:01"]);
  b.removeColumn("0x6401:01");
  assert.deepEqual(b.columns, ["0x6000:01"]);
  assert.equal(b.length, 3);
});

test("a sample not after the last one is refused: the time axis never folds back", () => {
  const b = new SampleBuffer();
  b.addColumn("0x1017:00");
  assert.equal(b.push(2_000_000, new Map([["0x1017:00", 1]])), true);
  assert.equal(b.push(2_000_000, new Map([["0x1017:00", 2]])), false);
  assert.equal(b.push(1_000_000, new Map([["0x1017:00", 3]])), false);
  assert.deepEqual(b.column("0x1017:00"), [1]);
});

test("at most keepCount samples (dropped in batches), the newest kept", () => {
  const b = new SampleBuffer({keepCount: 8});
  b.addColumn("a");
  for (let i = 1; i <= 10; i++) {
    b.push(i * 250_000, new Map([["a", i]]));
  }
  assert.equal(b.length, 10); // 8 plus a quarter: not yet
  b.push(11 * 250_000, new Map([["a", 11]]));
  assert.equal(b.length, 8);
  assert.deepEqual(b.column("a"), [4, 5, 6, 7, 8, 9, 10, 11]);
  assert.equal(b.times[0], 1);
});

test("samples older than keepS before the newest are dropped once 10 s more have passed", () => {
  const b = new SampleBuffer({keepS: 60});
  b.addColumn("a");
  for (let s = 0; s <= 70; s++) {
    b.push(s * 1e6, new Map([["a", s]]));
  }
  assert.equal(b.times[0], 0); // 70 s: within 60 + 10
  b.push(71e6, new Map([["a", 71]]));
  assert.equal(b.times[0], 11); // the last 60 s
  assert.equal(b.column("a")[0], 11);
  assert.equal(b.length, 61);
});

test("firstAtOrAfter: the first sample of a window", () => {
  const b = new SampleBuffer();
  for (const t of [1, 2, 3, 5]) {
    b.push(t * 1e6, new Map());
  }
  assert.equal(b.firstAtOrAfter(0), 0);
  assert.equal(b.firstAtOrAfter(2), 1);
  assert.equal(b.firstAtOrAfter(4), 3);
  assert.equal(b.firstAtOrAfter(6), 4);
});
