// web/vendor/: the third-party files the page serves are exactly those tools/vendor-web took from npm (their
// SHA-256 in web/vendor/uplot/VERSION), and nothing else lies beside them.
import {test} from "node:test";
import assert from "node:assert/strict";
import {createHash} from "node:crypto";
import {readdirSync, readFileSync} from "node:fs";
import {fileURLToPath} from "node:url";

const VENDOR = fileURLToPath(new URL("../../../web/vendor/uplot/", import.meta.url));

function versionFile() {
  const lines = readFileSync(VENDOR + "VERSION", "utf8").split("\n").filter((l) => l !== "" && !l.startsWith("#"));
  const fields = {sha256: {}};
  for (const line of lines) {
    const [key, value, name] = line.split(" ");
    if (key === "sha256") {
      fields.sha256[name] = value;
    } else {
      fields[key] = value;
    }
  }
  return fields;
}

test("VERSION names uPlot's version, its npm tarball and a SHA-256 for each vendored file", () => {
  const v = versionFile();
  assert.match(v.version, /^\d+\.\d+\.\d+$/);
  assert.equal(v.tarball, `https://registry.npmjs.org/uplot/-/uplot-${v.version}.tgz`);
  assert.deepEqual(Object.keys(v.sha256).sort(), ["LICENSE", "uPlot.iife.min.js", "uPlot.min.css"]);
  assert.deepEqual(readdirSync(VENDOR).sort(), ["LICENSE", "VERSION", "uPlot.iife.min.js", "uPlot.min.css"]);
});

test("each vendored file has the SHA-256 VERSION gives it (not edited by hand)", () => {
  for (const [name, sha] of Object.entries(versionFile().sha256)) {
    const actual = createHash("sha256").update(readFileSync(VENDOR + name)).digest("hex");
    assert.equal(actual, sha, `${name}: run tools/vendor-web to refresh it, never edit it`);
  }
});

test("the minified script names its version and the license is MIT", () => {
  const {version} = versionFile();
  const head = readFileSync(VENDOR + "uPlot.iife.min.js", "utf8").slice(0, 200);
  assert.ok(head.startsWith(`/*! https://github.com/leeoniya/uPlot (v${version}) */`), head);
  assert.match(readFileSync(VENDOR + "LICENSE", "utf8"), /^The MIT License \(MIT\)\n\nCopyright \(c\) \d{4} Leon Sorokin/);
});
