// The browser client's pure parts under Node (ctest browser.client): SipHash-2-4 against the
// reference vectors the C++ implementation is tested with (read from
// tests/unit/wire/siphash_test.cpp), the State datagram's decoding and every refusal of it, and the
// example's printf-exact number formatting. web/test/touch_wall.test.mjs runs the rest in Chromium.
import { describe, test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { DatagramError, HapticError, decodeState, siphash24 } from '../src/hapticd.js';
import { fixed, targetAt } from '../examples/touch_wall.js';

const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');

/** The 64 tags of tests/unit/wire/siphash_test.cpp, each 8 bytes, little-endian. */
function referenceTags() {
  const source = fs.readFileSync(path.join(ROOT, 'tests/unit/wire/siphash_test.cpp'), 'utf8');
  const tags = [...source.matchAll(/\{((?:0x[0-9a-f]{2},?\s*){8})\},\s*\/\/\s*(\d+)/g)]
    .map((m) => ({ n: Number(m[2]), bytes: m[1].split(',').map((b) => Number.parseInt(b, 16)) }));
  assert.equal(tags.length, 64, 'the C++ test holds 64 reference tags');
  return tags;
}

const keyOf = (n) => Uint8Array.from({ length: n }, (_, i) => i);

describe('siphash24', () => {
  test('gives the reference tags the C++ implementation is tested with', () => {
    const key = keyOf(16);
    for (const { n, bytes } of referenceTags()) {
      const tag = siphash24(key, keyOf(n));
      const expected = new DataView(Uint8Array.from(bytes).buffer).getBigUint64(0, true);
      assert.equal(tag, expected, `message of ${n} bytes`);
    }
  });

  test('reads a message at an offset into its buffer, and wants a 16-byte key', () => {
    const padded = new Uint8Array(70);
    padded.set(keyOf(63), 7);
    assert.equal(siphash24(keyOf(16), padded.subarray(7, 70)), siphash24(keyOf(16), keyOf(63)));
    assert.throws(() => siphash24(keyOf(8), keyOf(1)), RangeError);
  });
});

/** A State (or StateOriented) datagram as proto/haptic/wire/datagram.cpp writes one. */
function encodeState({ oriented = false, key, tick = 42n, timeNs = 1234567890123n, sequence = 7n,
                       sessionId = 0xfedcba9876543210n } = {}) {
  const payload = oriented ? 172 : 116;
  const bytes = new Uint8Array(40 + payload + 8);
  const view = new DataView(bytes.buffer);
  view.setUint32(0, 0x43545048, true);
  view.setUint16(4, 5, true);
  view.setUint16(6, oriented ? 5 : 1, true);
  view.setBigUint64(8, sessionId, true);
  view.setBigUint64(16, sequence, true);
  view.setBigInt64(24, timeNs, true);
  view.setUint32(32, payload, true);
  view.setBigUint64(40, tick, true);
  for (let i = 0; i < 12; ++i) view.setFloat64(48 + 8 * i, (i + 1) * 0.001 * (i % 2 ? -1 : 1), true);
  view.setUint32(144, 1, true);       // contacts
  view.setUint32(148, 4 | 1, true);   // flags
  view.setUint32(152, 0b101, true);   // buttons
  if (oriented) for (let i = 0; i < 7; ++i) view.setFloat64(156 + 8 * i, 0.5 + i, true);
  if (key) view.setBigUint64(40 + payload, siphash24(key, bytes.subarray(0, 40 + payload)), true);
  return bytes;
}

describe('decodeState', () => {
  const key = keyOf(16).map((b) => b * 3 + 1);

  test('decodes a State datagram whose tag verifies, field by field', () => {
    const state = decodeState(encodeState({ key }).buffer, key);
    assert.equal(state.type, 'State');
    assert.equal(state.sessionId, 0xfedcba9876543210n.toString());
    assert.equal(state.sequence, 7);
    assert.equal(state.serverTimeNs, 1234567890123n);
    assert.ok(Math.abs(state.serverTimeS - 1234.567890123) < 1e-9);
    assert.equal(state.tick, 42);
    assert.deepEqual(state.position, { x: 0.001, y: -0.002, z: 0.003 });
    assert.deepEqual(state.velocity, { x: -0.004, y: 0.005, z: -0.006 });
    assert.deepEqual(state.force, { x: 0.007, y: -0.008, z: 0.009000000000000001 });
    assert.deepEqual(state.proxy, { x: -0.01, y: 0.011, z: -0.012 });
    assert.equal(state.contactCount, 1);
    assert.equal(state.flags, 5);
    assert.equal(state.buttons, 5);
    assert.equal(state.orientation, null);
    assert.equal(state.torque, null);
  });

  test('decodes StateOriented: the orientation and the torque', () => {
    const state = decodeState(encodeState({ key, oriented: true }), key);
    assert.equal(state.type, 'StateOriented');
    assert.deepEqual(state.orientation, { w: 0.5, x: 1.5, y: 2.5, z: 3.5 });
    assert.deepEqual(state.torque, { x: 4.5, y: 5.5, z: 6.5 });
  });

  test('drops what the UDP receiver drops, saying why', () => {
    const refused = (bytes, why, withKey = key) => assert.throws(() => decodeState(bytes, withKey),
      (error) => error instanceof DatagramError && why.test(error.reason), why.source);
    const good = encodeState({ key });
    const changed = (offset, value, bits = 8) => {
      const bytes = good.slice();
      new DataView(bytes.buffer)[`setUint${bits}`](offset, value, true);
      return bytes;
    };
    refused(good.subarray(0, 47), /too short/);
    refused(changed(0, 0x49), /magic/);
    refused(changed(4, 4, 16), /wire version 4/);
    refused(changed(6, 2, 16), /type 2/);
    refused(changed(32, 172, 32), /payload size 172/);
    refused(good.subarray(0, good.length - 1), /length/);
    refused(changed(36, 1, 32), /reserved/);
    refused(changed(60, 0x3f), /tag/);                  // one bit of the position changed
    refused(good, /tag/, key.map((b) => b ^ 1));        // another session's key
    assert.equal(decodeState(changed(60, 0x3f), null).tick, 42, 'without a key, no tag is checked');
  });
});

describe('HapticError', () => {
  test('carries the code by name and by number', () => {
    const error = new HapticError('permission_denied', 'no', { call: 'Step', httpStatus: 403 });
    assert.ok(error instanceof Error);
    assert.equal(error.grpcCode, 7);
    assert.equal(error.call, 'Step');
    assert.equal(new HapticError('something new', '').grpcCode, 2);
  });
});

describe("touch_wall's formatting", () => {
  test('rounds as glibc printf does: ties to even, the exact value of the double, -0', () => {
    // Each as `printf("%.Nf")` printed it (gcc, glibc).
    assert.equal(fixed(0.125, 2), '0.12');
    assert.equal(fixed(0.375, 2), '0.38');
    assert.equal(fixed(2.5, 0), '2');
    assert.equal(fixed(3.5, 0), '4');
    assert.equal(fixed(-0.0, 3), '-0.000');
    assert.equal(fixed(1e-300, 3), '0.000');
    assert.equal(fixed(-1e-9, 3), '-0.000');
    assert.equal(fixed(0.1, 20), '0.10000000000000000555');
    assert.equal(fixed(1e21, 1), '1000000000000000000000.0');
    assert.equal(fixed(-1.3105, 3, 7), ' -1.310');
    assert.equal(fixed(1.005, 2, 10), '      1.00');
    assert.equal(fixed(2.0005, 3), '2.001');
    assert.equal(fixed(-0.125, 2), '-0.12');
    assert.equal(fixed(0.5, 0), '0');
    assert.equal(fixed(123456789.25, 1), '123456789.2');
    assert.equal(fixed(5e-324, 3), '0.000');
    assert.equal(fixed(1000, 0), '1000');
  });

  test('agrees with toFixed wherever the value is no tie', () => {
    let seed = 1;
    const random = () => ((seed = (seed * 48271) % 2147483647) / 2147483647);
    for (let i = 0; i < 20000; ++i) {
      const value = (random() - 0.5) * 10 ** Math.floor(random() * 12 - 4);
      const digits = Math.floor(random() * 6);
      if (Math.abs(value) < 0.5 * 10 ** -digits) continue;  // toFixed drops the sign of what rounds to 0
      assert.equal(fixed(value, digits), value.toFixed(digits), `${value} to ${digits} digits`);
    }
  });

  test("the hand's target descends 30 mm in 2 s and holds", () => {
    const near = (a, b) => Math.abs(a - b) < 1e-15;
    assert.equal(targetAt(0), 0.02);
    assert.ok(near(targetAt(1), 0.005));
    assert.ok(near(targetAt(2), -0.01) && targetAt(2.5) === targetAt(2));
  });
});
