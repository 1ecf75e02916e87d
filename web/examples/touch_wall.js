// touch_wall in a browser: what examples/touch_wall/main.cpp does, over the HTTP face with
// web/src/hapticd.js. It registers a wall (the half-space z < 0) and a weak spring field, has the
// server's simulated hand push the tool into the wall, and prints time, hand target, tool height
// and force at about 20 Hz, the rows formatted as the C++ program's printf formats them. In
// lockstep (the server started with --lockstep) it advances the server with Step and prints the
// same lines as `touch_wall --lockstep` does, character for character; the state it prints comes
// over the WebSocket state stream. touch_wall.html runs it.
import { HapticClient, HapticError } from '../src/hapticd.js';

const START_Z = 0.02;         // hand target at the start. Unit: m.
const END_Z = -0.01;          // 10 mm below the wall's surface. Unit: m.
const DESCENT = 2.0;          // Unit: s.
const HOLD = 1.0;             // Unit: s.
const HAND_STIFFNESS = 200.0; // Unit: N/m.
const HAND_DAMPING = 2.0;     // Unit: N·s/m.

/** The hand's target height at time t (s since the start). Unit: m. */
export function targetAt(t) {
  const s = t < DESCENT ? t / DESCENT : 1.0;
  return START_Z + s * (END_Z - START_Z);
}

/**
 * `value` as C's printf("%*.*f", width, digits, value) writes it: the double's exact value rounded
 * to `digits` decimals, a tie to even (glibc), "-0.000" for a negative that rounds to zero and for
 * −0, right-aligned in `width` characters. (Number.prototype.toFixed rounds ties away from zero
 * and drops the sign of −0.)
 * @param {number} value
 * @param {number} digits 0 ... 100
 * @param {number} [width]
 * @returns {string}
 */
export function fixed(value, digits, width = 0) {
  let text;
  if (Number.isNaN(value)) {
    text = 'nan';
  } else if (!Number.isFinite(value)) {
    text = value < 0 ? '-inf' : 'inf';
  } else {
    // |value| = mantissa × 2^exponent exactly, from its bits.
    const view = new DataView(new ArrayBuffer(8));
    view.setFloat64(0, Math.abs(value));
    const bits = view.getBigUint64(0);
    const biased = Number(bits >> 52n);
    const fraction = bits & ((1n << 52n) - 1n);
    const mantissa = biased === 0 ? fraction : fraction | (1n << 52n);
    const exponent = biased === 0 ? -1074 : biased - 1075;
    const scaled = mantissa * 10n ** BigInt(digits);  // |value| × 10^digits × 2^−exponent
    let units;
    if (exponent >= 0) {
      units = scaled << BigInt(exponent);
    } else {
      const denominator = 1n << BigInt(-exponent);
      units = scaled / denominator;
      const twice = 2n * (scaled % denominator);
      if (twice > denominator || (twice === denominator && (units & 1n) === 1n)) units += 1n;
    }
    const all = units.toString().padStart(digits + 1, '0');
    const sign = value < 0 || Object.is(value, -0) ? '-' : '';
    text = sign + (digits > 0 ? `${all.slice(0, -digits)}.${all.slice(-digits)}` : all);
  }
  return text.padStart(width);
}

function row(t, target, state) {
  return `${fixed(t, 3, 7)}  ${fixed(target * 1e3, 2, 10)}  ${fixed(state.position.z * 1e3, 3, 8)}  ` +
         `${fixed(state.force.z, 3, 9)}  ${state.contactCount > 0 ? 'yes' : 'no'}`;
}

function follow(target) {
  return { mode: 'FOLLOW_TARGET', target: { x: 0, y: 0, z: target }, stiffness: HAND_STIFFNESS, damping: HAND_DAMPING };
}

/**
 * The time column in real time: the server's clock from its first row. Unit: s.
 */
class RowClock {
  constructor() {
    this.first = null;
  }

  at(serverTimeS) {
    if (this.first === null) this.first = serverTimeS;
    return serverTimeS - this.first;
  }
}

/**
 * Runs touch_wall against the HTTP face at `url`, handing each line to `print`.
 * @param {string} url 'http://127.0.0.1:8081'
 * @param {{lockstep?: boolean, token?: string, print: (line: string) => void}} options
 *        lockstep: the server runs in lockstep time, and this advances it with Step.
 */
export async function touchWall(url, { lockstep = false, token, print }) {
  const client = await HapticClient.open(url, { token, clientName: 'touch_wall' });
  try {
    const device = client.device;
    if (!device.simulated) {
      throw new HapticError('failed_precondition', `${device.name} has no simulated hand to push the tool; ` +
                            'the C++ touch_wall (examples/touch_wall) watches a real device');
    }
    const rate = device.loop_rate_hz;
    const ticksPerRow = Math.trunc(rate / 20.0);  // ~20 Hz output
    // Lockstep: a sample as soon as a Step has made it; in real time, one a row.
    const stream = client.streamState({ rateHz: lockstep ? Math.min(1000, rate) : rate / ticksPerRow });

    await client.createObject({ pose: { position: { x: 0, y: 0, z: 0 } }, half_space: { normal: { x: 0, y: 0, z: 1 } },
                                impedance: { stiffness: 1000.0, damping: 1.0 } });
    await client.createField({ spring_to_point: { anchor: { x: 0, y: 0, z: START_Z }, stiffness: 20.0, damping: 0.0,
                                                  max_force: 2.0 } });

    print(`touch_wall: ${device.name} at ${fixed(rate, 0)} Hz, ${lockstep ? 'lockstep' : 'real'} time; ` +
          'wall z < 0 with K = 1000 N/m, B = 1 N*s/m');
    print(`${'time_s'.padStart(7)}  ${'target_mm'.padStart(10)}  ${'z_mm'.padStart(8)}  ${'force_N'.padStart(9)}  contact`);

    const duration = DESCENT + HOLD;
    let lastTick = 0;
    if (lockstep) {
      // 10 ms steps, the hand's target moved between them; rows timed from the first step.
      const ticksPerStep = Math.max(1, Math.trunc(rate / 100.0));
      let firstTick = null;
      let nextRowTick = 0;
      let t = 0.0;
      while (t < duration) {
        const target = targetAt(t);
        await client.setOperator(follow(target));
        const tick = Number((await client.step(ticksPerStep)).tick);
        lastTick = tick;
        if (firstTick === null) {
          firstTick = tick;
          nextRowTick = tick;
        }
        t = (tick - firstTick + ticksPerStep) / rate;
        if (tick >= nextRowTick) {
          // Nothing steps the server while this waits: the stream's newest sample is this tick's.
          const state = await stream.waitFor((s) => s.tick >= tick, 10000);
          print(row(t, target, state));
          nextRowTick = tick + ticksPerRow;
        }
      }
    } else {
      const start = performance.now();
      let nextUpdate = start;
      let t = 0.0;
      const clock = new RowClock();
      let printed = null;
      while (t < duration) {
        t = (performance.now() - start) / 1000;
        await client.setOperator(follow(targetAt(t)));
        const state = stream.latest;
        if (state && state !== printed) {
          printed = state;
          print(row(clock.at(state.serverTimeS), targetAt(t), state));
        }
        nextUpdate += 10;
        await new Promise((resolve) => setTimeout(resolve, Math.max(0, nextUpdate - performance.now())));
      }
    }
    await client.setOperator({ mode: 'NONE' });
    if (lockstep) {
      print(`touch_wall: done; server at tick ${lastTick}`);
    } else {
      try {
        const stats = await client.call('GetStats');
        print(`touch_wall: done; server loop ${fixed(stats.achieved_rate_hz ?? 0, 1)} Hz, lateness p99 ` +
              `${fixed(stats.lateness_p99_us ?? 0, 0)} us, ${stream.received} datagrams received`);
      } catch (error) {
        if (!(error instanceof HapticError && error.code === 'permission_denied')) throw error;
        print(`touch_wall: done; ${stream.received} datagrams received`);  // the loop's figures are an ADMIN's
      }
    }
  } finally {
    await client.close().catch(() => {});
  }
}
