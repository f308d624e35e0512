// The tables the page is served (the emulator's `tables` answer: `faults`, `aborts`), as the program answered them
// when ctest ran web/tables before these tests (tests/web/capture-tables.cmake; CO_WEB_TABLES names the file). The
// tests take them from there, never from a list of their own: a kind of fault or an abort code added to the program
// is tested with the rest. Without the file (node --test by hand, without the program built) the tests that need
// it are skipped, and say why.
import {readFileSync} from "node:fs";

const path = process.env.CO_WEB_TABLES;

/** The `tables` answer, or null when there is none to read. */
export const served = path ? JSON.parse(readFileSync(path, "utf8")) : null;

/** node:test options of a test that needs the served tables. */
export const needsServed = served === null ?
  {skip: "no served tables (CO_WEB_TABLES: ctest runs web/tables first, tests/web/CMakeLists.txt)"} : {};
