// A bounded ring buffer: the trace keeps the last `capacity` frames, pushing out the oldest, and counts what it
// pushed out. No DOM: tested with node --test (tests/web/js).

export class Ring {
  #items;
  #start = 0; // index in #items of the oldest item
  #length = 0;
  dropped = 0; // items pushed out since the last clear()

  constructor(capacity) {
    if (!Number.isInteger(capacity) || capacity < 1) {
      throw new RangeError(`a ring holds at least one item, not ${capacity}`);
    }
    this.#items = new Array(capacity);
  }

  get capacity() {
    return this.#items.length;
  }

  get length() {
    return this.#length;
  }

  /** Adds `item` as the newest; when full, the oldest goes (counted in `dropped`). */
  push(item) {
    if (this.#length < this.#items.length) {
      this.#items[(this.#start + this.#length) % this.#items.length] = item;
      this.#length++;
      return;
    }
    this.#items[this.#start] = item;
    this.#start = (this.#start + 1) % this.#items.length;
    this.dropped++;
  }

  /** The item `i` places from the oldest (0: the oldest; length - 1: the newest); undefined outside. */
  at(i) {
    if (!Number.isInteger(i) || i < 0 || i >= this.#length) {
      return undefined;
    }
    return this.#items[(this.#start + i) % this.#items.length];
  }

  /** Empties the ring and its count of dropped items. */
  clear() {
    this.#items.fill(undefined);
    this.#start = 0;
    this.#length = 0;
    this.dropped = 0;
  }

  /** Oldest first. */
  * [Symbol.iterator]() {
    for (let i = 0; i < this.#length; i++) {
      yield this.#items[(this.#start + i) % this.#items.length];
    }
  }
}
