// Which objects a node's TPDOs map (docs/web.md "Plots": the default series), from its own mapping parameters
// (0x1A00..0x1BFF) as `get` reads them: what the node sends now, also after a master remapped it. The `objects`
// list's `tpdo` flag says only what MAY be mapped. No DOM: tested with node --test.

import {objectName, parseObject} from "./objects.js";

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
