// Charts for windmeta's page, drawn as standalone SVG (presentation attributes, no style sheet), so
// that the element on the page is also the file a user downloads. Curves with bands on a linear or
// logarithmic axis, scatter plots with a diagonal, and bar charts with intervals; every chart shows
// the values under the pointer (or under the arrow keys once it has the focus).
const NS = 'http://www.w3.org/2000/svg';
const COLORS = ['#1f5fa8', '#c2571a', '#2e8b57', '#7a3ea1'];
const MARGIN = { left: 78, right: 18, top: 40, bottom: 52 };
const LEGEND_ROW = 16;

function element(name, attributes, parent) {
  const node = document.createElementNS(NS, name);
  for (const [key, value] of Object.entries(attributes || {})) node.setAttribute(key, value);
  if (parent) parent.appendChild(node);
  return node;
}

function text(parent, x, y, content, attributes) {
  const node = element('text', { x, y, 'font-size': 12, fill: '#1b2430', ...attributes }, parent);
  node.textContent = content;
  return node;
}

/** A number to four significant digits, without trailing noise; exponents for the very large or small. */
export function format(value) {
  if (value === null || value === undefined || Number.isNaN(value)) return '–';
  if (value === 0) return '0';
  const magnitude = Math.abs(value);
  if (magnitude >= 1e5 || magnitude < 1e-3) return value.toExponential(3).replace(/\.?0+e/, 'e');
  return String(Number(value.toPrecision(4)));
}

const SUPERSCRIPTS = { '-': '⁻', 0: '⁰', 1: '¹', 2: '²', 3: '³', 4: '⁴', 5: '⁵', 6: '⁶', 7: '⁷', 8: '⁸', 9: '⁹' };
function powerOfTen(exponent) {
  if (exponent === 0) return '1';
  return '10' + String(exponent).split('').map((c) => SUPERSCRIPTS[c]).join('');
}

/** About `count` round ticks covering [low, high]. */
function linearTicks(low, high, count) {
  const span = high - low || Math.abs(high) || 1;
  const raw = span / count;
  const base = Math.pow(10, Math.floor(Math.log10(raw)));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * base).find((s) => span / s <= count) || 10 * base;
  const ticks = [];
  for (let t = Math.ceil(low / step) * step; t <= high + step * 1e-9; t += step) ticks.push(Number(t.toPrecision(12)));
  return ticks;
}

/** An axis over the finite values given: linear (padded to round ticks) or decades. */
function axis(values, log, fixed) {
  const finite = values.filter((v) => Number.isFinite(v) && (!log || v > 0));
  let low = fixed && fixed.min !== undefined ? fixed.min : Math.min(...finite);
  let high = fixed && fixed.max !== undefined ? fixed.max : Math.max(...finite);
  if (!finite.length) { low = log ? 1e-3 : 0; high = 1; }
  if (log) {
    const lowDecade = Math.floor(Math.log10(low));
    const highDecade = Math.max(Math.ceil(Math.log10(high)), lowDecade + 1);
    const ticks = [];
    for (let e = lowDecade; e <= highDecade; e++) ticks.push(Math.pow(10, e));
    return { log, low: Math.pow(10, lowDecade), high: Math.pow(10, highDecade), ticks, label: (v) => powerOfTen(Math.round(Math.log10(v))) };
  }
  if (low === high) { low -= Math.abs(low) * 0.1 || 1; high += Math.abs(high) * 0.1 || 1; }
  const ticks = linearTicks(low, high, 6);
  return { log, low: Math.min(low, ticks[0]), high: Math.max(high, ticks[ticks.length - 1]), ticks, label: format };
}

function scaler(ax, from, to) {
  if (ax.log) {
    const a = Math.log10(ax.low), b = Math.log10(ax.high);
    return (v) => from + (to - from) * (Math.log10(Math.max(v, ax.low)) - a) / (b - a);
  }
  return (v) => from + (to - from) * (v - ax.low) / (ax.high - ax.low);
}

function frame(options, width, height) {
  const svg = element('svg', {
    xmlns: NS, viewBox: `0 0 ${width} ${height}`, width, height, role: 'img', tabindex: 0,
    'font-family': 'system-ui, sans-serif', 'aria-label': options.title,
  });
  element('rect', { x: 0, y: 0, width, height, fill: '#ffffff' }, svg);
  text(svg, MARGIN.left, 20, options.title, { 'font-size': 14, 'font-weight': 600 });
  return svg;
}

function drawAxes(svg, xAxis, yAxis, x, y, box, options) {
  const grid = element('g', { stroke: '#e3e7ec', 'stroke-width': 1 }, svg);
  for (const t of yAxis.ticks) {
    element('line', { x1: box.left, x2: box.right, y1: y(t), y2: y(t) }, grid);
    text(svg, box.left - 6, y(t) + 4, yAxis.label(t), { 'text-anchor': 'end' });
  }
  if (xAxis) {
    for (const t of xAxis.ticks) {
      element('line', { x1: x(t), x2: x(t), y1: box.top, y2: box.bottom }, grid);
      text(svg, x(t), box.bottom + 16, xAxis.label(t), { 'text-anchor': 'middle' });
    }
  }
  element('rect', { x: box.left, y: box.top, width: box.right - box.left, height: box.bottom - box.top, fill: 'none', stroke: '#8a96a3' }, svg);
  text(svg, (box.left + box.right) / 2, box.bottom + 38, options.xLabel || '', { 'text-anchor': 'middle' });
  const middle = (box.top + box.bottom) / 2;
  text(svg, 16, middle, options.yLabel || '', { 'text-anchor': 'middle', transform: `rotate(-90 16 ${middle})` });
}

/** A box in the plot's corner listing the values under the pointer. */
function readout(svg, box) {
  const group = element('g', { visibility: 'hidden', 'pointer-events': 'none' }, svg);
  const guide = element('line', { y1: box.top, y2: box.bottom, stroke: '#5b6675', 'stroke-dasharray': '3 3' }, group);
  const panel = element('rect', { x: box.left + 8, y: box.top + 8, rx: 3, fill: '#ffffff', stroke: '#8a96a3', opacity: 0.95 }, group);
  const lines = element('g', {}, group);
  const markers = element('g', {}, group);
  return {
    show(px, rows, points) {
      group.setAttribute('visibility', 'visible');
      guide.setAttribute('x1', px);
      guide.setAttribute('x2', px);
      guide.setAttribute('visibility', px === null ? 'hidden' : 'visible');
      lines.replaceChildren();
      markers.replaceChildren();
      rows.forEach((row, i) => text(lines, box.left + 16, box.top + 26 + 16 * i, row.text, { fill: row.color || '#1b2430' }));
      const width = Math.max(...rows.map((r) => r.text.length)) * 6.6 + 16;
      panel.setAttribute('width', width);
      panel.setAttribute('height', rows.length * 16 + 12);
      for (const p of points) element('circle', { cx: p.x, cy: p.y, r: 4, fill: p.color, stroke: '#ffffff' }, markers);
    },
    hide() { group.setAttribute('visibility', 'hidden'); },
  };
}

/** Pointer and arrow keys move an index over `count` positions; `onMove(i)` shows it. */
function interact(svg, box, count, indexAt, onMove, onLeave) {
  let current = null;
  const catcher = element('rect', { x: box.left, y: box.top, width: box.right - box.left, height: box.bottom - box.top, fill: 'transparent' }, svg);
  catcher.addEventListener('pointermove', (event) => {
    const bounds = svg.getBoundingClientRect();
    const px = (event.clientX - bounds.left) * (svg.viewBox.baseVal.width / bounds.width);
    const py = (event.clientY - bounds.top) * (svg.viewBox.baseVal.height / bounds.height);
    current = indexAt(px, py);
    if (current !== null) onMove(current);
  });
  catcher.addEventListener('pointerleave', () => { current = null; onLeave(); });
  svg.addEventListener('keydown', (event) => {
    if (event.key !== 'ArrowRight' && event.key !== 'ArrowLeft') return;
    event.preventDefault();
    const step = event.key === 'ArrowRight' ? 1 : -1;
    current = current === null ? 0 : Math.min(count - 1, Math.max(0, current + step));
    onMove(current);
  });
  svg.addEventListener('blur', () => { current = null; onLeave(); });
}

/**
 * Curves (and points) with optional bands. options: title, xLabel, yLabel, yLog, xLog,
 * yMin/yMax, diagonal (a y = x line), series: [{name, x, y, lower?, upper?, points?, line?}],
 * describe(series, i) → the readout's text for a point.
 */
export function lines(options) {
  const series = options.series;
  const width = options.width || 760, height = (options.height || 400) + LEGEND_ROW * series.length;
  const svg = frame(options, width, height);
  const box = plotBox(width, height, series.length);
  const xs = series.flatMap((s) => s.x);
  const ys = series.flatMap((s) => [...s.y, ...(s.lower || []), ...(s.upper || [])]);
  const xAxis = axis(options.diagonal ? [...xs, ...ys] : xs, options.xLog);
  const yAxis = axis(options.diagonal ? [...xs, ...ys] : ys, options.yLog, { min: options.yMin, max: options.yMax });
  const x = scaler(xAxis, box.left, box.right), y = scaler(yAxis, box.bottom, box.top);
  drawAxes(svg, xAxis, yAxis, x, y, box, options);
  const plot = element('g', {}, svg);
  if (options.diagonal) {
    const lo = Math.max(xAxis.low, yAxis.low), hi = Math.min(xAxis.high, yAxis.high);
    element('line', { x1: x(lo), y1: y(lo), x2: x(hi), y2: y(hi), stroke: '#8a96a3', 'stroke-dasharray': '5 4' }, plot);
  }
  const visible = (v) => Number.isFinite(v) && (!options.yLog || v > 0);
  series.forEach((s, k) => {
    const color = s.color || COLORS[k % COLORS.length];
    if (s.lower && s.upper) {
      const top = s.x.map((v, i) => `${x(v)},${y(Math.min(s.upper[i], yAxis.high))}`);
      const bottom = s.x.map((v, i) => `${x(v)},${y(Math.max(s.lower[i], yAxis.low))}`).reverse();
      element('polygon', { points: [...top, ...bottom].join(' '), fill: color, 'fill-opacity': 0.16, stroke: 'none' }, plot);
    }
    if (s.line !== false) {
      const path = s.x.map((v, i) => (visible(s.y[i]) ? `${x(v)},${y(s.y[i])}` : null)).filter(Boolean);
      if (path.length) element('polyline', { points: path.join(' '), fill: 'none', stroke: color, 'stroke-width': 2, 'data-series': k }, plot);
    }
    if (s.points) {
      s.x.forEach((v, i) => { if (visible(s.y[i])) element('circle', { cx: x(v), cy: y(s.y[i]), r: 3, fill: color, 'fill-opacity': 0.7 }, plot); });
    }
  });
  legend(svg, series.map((s) => s.name));
  const shown = readout(svg, box);
  const first = series[0];
  const nearest = (px, py) => {
    let best = null, distance = Infinity;
    first.x.forEach((v, i) => {
      const d = options.diagonal ? Math.hypot(x(v) - px, y(first.y[i]) - py) : Math.abs(x(v) - px);
      if (d < distance) { distance = d; best = i; }
    });
    return best;
  };
  interact(svg, box, first.x.length, nearest, (i) => {
    const at = first.x[i];
    const rows = [], points = [];
    series.forEach((s, k) => {
      const color = s.color || COLORS[k % COLORS.length];
      let j = i;
      if (k > 0) j = s.x.reduce((b, v, m) => (Math.abs(v - at) < Math.abs(s.x[b] - at) ? m : b), 0);
      rows.push({ text: options.describe ? options.describe(s, j) : `${s.name}: ${format(s.x[j])}, ${format(s.y[j])}`, color });
      if (visible(s.y[j])) points.push({ x: x(s.x[j]), y: y(s.y[j]), color });
    });
    shown.show(options.diagonal ? null : x(at), rows, points);
  }, () => shown.hide());
  return svg;
}

/** One row per series under the title, each with its colour. */
function legend(svg, names) {
  names.forEach((name, k) => {
    const y = MARGIN.top + LEGEND_ROW * k;
    element('line', { x1: MARGIN.left, x2: MARGIN.left + 22, y1: y - 4, y2: y - 4, stroke: COLORS[k % COLORS.length], 'stroke-width': 3 }, svg);
    text(svg, MARGIN.left + 28, y, name);
  });
}

/** The plot's box under the title and the legend's rows. */
function plotBox(width, height, rows, extraBottom) {
  return { left: MARGIN.left, right: width - MARGIN.right, top: MARGIN.top + LEGEND_ROW * rows, bottom: height - MARGIN.bottom - (extraBottom || 0) };
}

/**
 * Grouped bars with intervals. options: title, yLabel, categories, groups: [{name, values,
 * lower, upper}], yMin, yMax.
 */
export function bars(options) {
  const width = options.width || 760, height = (options.height || 380) + LEGEND_ROW * options.groups.length;
  const svg = frame(options, width, height);
  const box = plotBox(width, height, options.groups.length, 16);
  const all = options.groups.flatMap((g) => [...g.values, ...g.lower, ...g.upper]);
  const yAxis = axis([0, ...all], false, { min: options.yMin, max: options.yMax });
  const y = scaler(yAxis, box.bottom, box.top);
  drawAxes(svg, null, yAxis, null, y, box, options);
  const slot = (box.right - box.left) / options.categories.length;
  const barWidth = (slot * 0.7) / options.groups.length;
  options.categories.forEach((name, c) => {
    const centre = box.left + slot * (c + 0.5);
    text(svg, centre, box.bottom + 16, name, { 'text-anchor': 'middle', 'font-size': 11 });
    options.groups.forEach((g, k) => {
      const left = centre - slot * 0.35 + barWidth * k;
      const value = g.values[c];
      const top = y(Math.max(value, 0)), bottom = y(Math.min(value, 0));
      element('rect', { x: left, y: top, width: barWidth - 2, height: Math.max(bottom - top, 0.5), fill: COLORS[k % COLORS.length], 'fill-opacity': 0.8 }, svg);
      const mid = left + (barWidth - 2) / 2;
      element('line', { x1: mid, x2: mid, y1: y(g.lower[c]), y2: y(g.upper[c]), stroke: '#1b2430', 'stroke-width': 1.2 }, svg);
    });
  });
  legend(svg, options.groups.map((g) => g.name));
  const shown = readout(svg, box);
  interact(svg, box, options.categories.length, (px) => Math.min(options.categories.length - 1, Math.max(0, Math.floor((px - box.left) / slot))), (c) => {
    const rows = [{ text: options.categories[c] }, ...options.groups.map((g, k) => ({
      text: `${g.name}: ${format(g.values[c])} [${format(g.lower[c])}, ${format(g.upper[c])}]`, color: COLORS[k % COLORS.length],
    }))];
    shown.show(null, rows, []);
  }, () => shown.hide());
  return svg;
}

/** The chart as a standalone SVG file's text (the readout hidden). */
export function serialize(svg) {
  const copy = svg.cloneNode(true);
  copy.querySelectorAll('[visibility="visible"]').forEach((node) => node.setAttribute('visibility', 'hidden'));
  return '<?xml version="1.0" encoding="UTF-8"?>\n' + new XMLSerializer().serializeToString(copy);
}
