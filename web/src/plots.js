// Plots on a 2D canvas: the lateness histogram (log-log) and time series of the loop's figures.

const AXIS = '#8a93a0';
const GRID = '#2d333d';
const MARGIN = { left: 46, right: 10, top: 8, bottom: 24 };

function prepare(canvas) {
  const ratio = window.devicePixelRatio || 1;
  const width = canvas.clientWidth || canvas.width;
  const height = canvas.clientHeight || canvas.height;
  if (canvas.width !== Math.round(width * ratio)) {
    canvas.width = Math.round(width * ratio);
    canvas.height = Math.round(height * ratio);
  }
  const g = canvas.getContext('2d');
  g.setTransform(ratio, 0, 0, ratio, 0, 0);
  g.clearRect(0, 0, width, height);
  g.font = '10px system-ui, sans-serif';
  return { g, width, height, plotWidth: width - MARGIN.left - MARGIN.right, plotHeight: height - MARGIN.top - MARGIN.bottom };
}

function message(canvas, text) {
  const { g, width, height } = prepare(canvas);
  g.fillStyle = AXIS;
  g.textAlign = 'center';
  g.fillText(text, width / 2, height / 2);
}

function label(value) {
  if (value >= 1000) return `${+(value / 1000).toPrecision(3)}k`;
  return `${+value.toPrecision(3)}`;
}

/// Decades from 10^low to 10^high for a log axis.
function decades(low, high) {
  const out = [];
  for (let e = Math.floor(low); e <= Math.ceil(high); ++e) out.push(e);
  return out;
}

/// The lateness histogram (a haptic.v1.LatenessHistogram): bars over log µs, counts on a log scale.
export function drawHistogram(canvas, histogram) {
  const counts = (histogram?.counts ?? []).map(Number);
  if (counts.length === 0) {
    message(canvas, 'no lateness samples in the window (a lockstep server records none)');
    return;
  }
  const { g, plotWidth, plotHeight } = prepare(canvas);
  const lower = histogram.bin_lower_us.map(Number);
  const width = histogram.bin_width_us.map(Number);
  // Bins start at 0 µs: the axis starts at 1 µs and the first bin is drawn from there.
  const xLow = 0;
  const xHigh = Math.max(1, Math.log10(Math.max(...lower.map((l, i) => l + width[i]))));
  const yHigh = Math.max(1, Math.log10(Math.max(...counts)) + 0.2);
  const x = (us) => MARGIN.left + (Math.log10(Math.max(1, us)) - xLow) / (xHigh - xLow) * plotWidth;
  const y = (n) => MARGIN.top + plotHeight - (n > 0 ? (Math.log10(n) + 0.2) / (yHigh + 0.2) : 0) * plotHeight;
  g.strokeStyle = GRID;
  g.fillStyle = AXIS;
  g.textAlign = 'center';
  for (const e of decades(xLow, xHigh)) {
    if (e > xHigh) break;
    const at = x(10 ** e);
    g.beginPath(); g.moveTo(at, MARGIN.top); g.lineTo(at, MARGIN.top + plotHeight); g.stroke();
    g.fillText(`${label(10 ** e)} µs`, at, MARGIN.top + plotHeight + 14);
  }
  g.textAlign = 'right';
  for (const e of decades(0, yHigh)) {
    if (e > yHigh) break;
    const at = y(10 ** e);
    g.beginPath(); g.moveTo(MARGIN.left, at); g.lineTo(MARGIN.left + plotWidth, at); g.stroke();
    g.fillText(label(10 ** e), MARGIN.left - 4, at + 3);
  }
  g.fillStyle = '#4fb3ff';
  counts.forEach((count, i) => {
    const left = x(lower[i]);
    const right = Math.max(left + 1, x(lower[i] + width[i]));
    g.fillRect(left, y(count), right - left, MARGIN.top + plotHeight - y(count));
  });
}

/// Time series: `series` is [{name, color, unit, points: [[t_s, value], ...]}], each on its own
/// scale (0 to its maximum), over the last `span_s` seconds.
export function drawSeries(canvas, series, spanS) {
  const { g, plotWidth, plotHeight } = prepare(canvas);
  const now = Math.max(0, ...series.flatMap((s) => s.points.map((p) => p[0])));
  const x = (t) => MARGIN.left + (1 - (now - t) / spanS) * plotWidth;
  g.strokeStyle = GRID;
  g.fillStyle = AXIS;
  g.textAlign = 'center';
  for (let t = 0; t <= spanS; t += spanS / 6) {
    const at = x(now - t);
    g.beginPath(); g.moveTo(at, MARGIN.top); g.lineTo(at, MARGIN.top + plotHeight); g.stroke();
    g.fillText(t === 0 ? 'now' : `−${t.toFixed(0)} s`, at, MARGIN.top + plotHeight + 14);
  }
  series.forEach((s, k) => {
    const values = s.points.map((p) => p[1]).filter(Number.isFinite);
    const top = Math.max(1e-9, ...values) * 1.15;
    const y = (v) => MARGIN.top + plotHeight - (v / top) * plotHeight;
    g.strokeStyle = s.color;
    g.lineWidth = 1.5;
    g.beginPath();
    s.points.forEach(([t, v], i) => (i === 0 ? g.moveTo(x(t), y(v)) : g.lineTo(x(t), y(v))));
    g.stroke();
    g.lineWidth = 1;
    g.fillStyle = s.color;
    g.textAlign = 'left';
    const last = values.length > 0 ? values[values.length - 1] : NaN;
    const scale = Math.max(...values, 0) > 0 ? ` (top ${label(top)})` : '';
    g.fillText(`${s.name}: ${Number.isFinite(last) ? label(last) : '–'} ${s.unit}${scale}`,
               MARGIN.left + 4, MARGIN.top + 10 + 12 * k);
  });
}
