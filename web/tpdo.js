// Which objects a node's TPDOs map (docs/web.md "Plots": the default series), from its own mapping parameters
// (0x1A00..0x1BFF) as `get` reads them: what the node sends now, also after a master remapped it. The `objects`
// list's `tpdo` flag says only what MAY be mapped. No DOM: tested with node --test.

/** At most this many objects in one `get` (the control protocol's limit). */
export const GET_MAX = 64;

/** "0xIIII:SS" as the control protocol writes an object. */
export function objectName(index, sub) {
  return `0x${index.toString(16).toUpperCase().padStart(4, "0")}:${sub.toString(16).toUpperCase().padStart(2, "0")}`;
}

/** The index and sub of "0xIIII:SS" (or "IIII", "6401:1", "0x1017"); null when it is not one. */
export function parseObject(text) {
  const m = /^(?:0x)?([0-9a-f]{1,4})(?::(?:0x)?([0-9a-f]{1,2}))?$/i.exec(String(text).trim());
  return m === null ? null : {index: parseInt(m[1], 16), sub: m[2] === undefined ? 0 : parseInt(m[2], 16)};
}

/** `list` in pieces of at most `size`. */
export function chunks(list, size = GET_MAX) {
  const pieces = [];
  for (let i = 0; i < list.length; i += size) {
    pieces.push(list.slice(i, i + size));
  }
  return pieces;
}

/** The count sub-indices (sub 0) of the TPDO mapping parameters a node has, from its `objects` rows. */
export function mappingCounts(rows) {
  return rows.filter((r) => {
    const o = parseObject(r.object);
    return o.sub === 0 && o.index >= 0x1A00 && o.index <= 0x1BFF;
  }).map((r) => r.object);
}

/** The mapping entries to read: sub 1..count of each mapping parameter, from the `values` of a get of the counts
 * (a count that cannot be read maps nothing). */
export function mappingEntries(values) {
  const entries = [];
  for (const v of values) {
    const {index} = parseObject(v.object);
    const count = typeof v.value === "number" ? Math.min(v.value, 64) : 0;
    for (let sub = 1; sub <= count; sub++) {
      entries.push(objectName(index, sub));
    }
  }
  return entries;
}

/** The objects the entries map (each 0xIIIISSLL: index, sub, length in bits), in mapping order, each once; dummy
 * entries (an index below 0x1000: a data type, only padding) and unreadable ones left out. */
export function mappedObjects(values) {
  const objects = [];
  for (const v of values) {
    if (typeof v.value !== "number") {
      continue;
    }
    const index = Math.floor(v.value / 0x10000);
    const sub = (v.value >>> 8) & 0xFF;
    const name = objectName(index, sub);
    if (index >= 0x1000 && !objects.includes(name)) {
      objects.push(name);
    }
  }
  return objects;
}
