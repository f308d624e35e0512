// The samples of one node's plotted objects (docs/web.md "Plots"): one time axis (the emulator's clock, in seconds:
// the get answers' time_us) and a column of values per object, bounded by count and by age, so that a page left open
// for hours holds no more than the last minutes. No DOM: tested with node --test (tests/web/js).

/** How long samples are kept: 10 minutes of the emulator's clock. */
export const KEEP_S = 600;
/** At most this many samples per node: 10 minutes of an exchange every 250 ms, and room for quicker ones. */
export const KEEP_COUNT = 4096;

/** A value of a get answer as a number to plot: integers and reals as they are, a BOOLEAN as 0/1, an UNSIGNED64
 * given as a decimal string as its (rounded) number; null (a gap) for NaN, infinities and anything else. */
export function plottable(value) {
  if (typeof value === "number") {
    return Number.isFinite(value) ? value : null;
  }
  if (typeof value === "boolean") {
    return value ? 1 : 0;
  }
  if (typeof value === "string" && /^-?\d+$/.test(value)) {
    return Number(value);
  }
  return null;
}

export class SampleBuffer {
  #keepS;
  #keepCount;
  #times = []; // s, increasing
  #columns = new Map(); // object -> values (number|null), as long as #times

  constructor({keepS = KEEP_S, keepCount = KEEP_COUNT} = {}) {
    this.#keepS = keepS;
    this.#keepCount = keepCount;
  }

  get length() {
    return this.#times.length;
  }

  /** The times (s), oldest first. The array is the buffer's own: read it, never change it. */
  get times() {
    return this.#times;
  }

  /** The values of `object` (null where it was not read), or undefined when it has no column. */
  column(object) {
    return this.#columns.get(object);
  }

  /** A column for `object` (its earlier samples null); one it has already stays as it is. */
  addColumn(object) {
    if (!this.#columns.has(object)) {
      this.#columns.set(object, new Array(this.#times.length).fill(null));
    }
  }

  removeColumn(object) {
    this.#columns.delete(object);
  }

  get columns() {
    return [...this.#columns.keys()];
  }

  /**
   * One sample at `timeUs` (µs on the emulator's clock): values, a Map object -> value as the get answer gives it
   * (plottable() turns it into a number); a column without a value gets null. A time not after the last one is
   * refused (false): a late answer never folds the time axis back.
   */
  push(timeUs, values) {
    const t = timeUs / 1e6;
    if (this.#times.length > 0 && t <= this.#times[this.#times.length - 1]) {
      return false;
    }
    this.#times.push(t);
    for (const [object, column] of this.#columns) {
      column.push(values.has(object) ? plottable(values.get(object)) : null);
    }
    this.#trim();
    return true;
  }

  /** The index of the first sample at or after `t` (s); length when there is none. */
  firstAtOrAfter(t) {
    let low = 0;
    let high = this.#times.length;
    while (low < high) {
      const mid = (low + high) >> 1;
      if (this.#times[mid] < t) {
        low = mid + 1;
      } else {
        high = mid;
      }
    }
    return low;
  }

  /** Drops what is beyond the bounds, in batches (a quarter of the count, or 10 s of age, past them): splicing the
   * arrays at every sample would copy them four times a second. */
  #trim() {
    const newest = this.#times[this.#times.length - 1];
    let drop = 0;
    if (this.#times.length > this.#keepCount + (this.#keepCount >> 2)) {
      drop = this.#times.length - this.#keepCount;
    }
    if (this.#times[0] < newest - this.#keepS - 10) {
      drop = Math.max(drop, this.firstAtOrAfter(newest - this.#keepS));
    }
    if (drop > 0) {
      this.#times.splice(0, drop);
      for (const column of this.#columns.values()) {
        column.splice(0, drop);
      }
    }
  }
}
