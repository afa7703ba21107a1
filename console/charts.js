// Plots on uPlot (global `uPlot`, from npm, embedded in calstandd): live rolling time series,
// points coloured by group, a line on a log axis, and a lot's control chart. Each returns an
// object with the data setters a page needs and destroy().

/** Colours for series and groups, distinguishable on white and for most colour vision. */
export const PALETTE = ['#1f77b4', '#d62728', '#2ca02c', '#ff7f0e', '#9467bd', '#8c564b', '#e377c2',
  '#17becf', '#7f7f7f', '#bcbd22'];

function widthOf(container) {
  return Math.max(320, container.clientWidth || 600);
}

// Charts follow their container's width (a resized window or panel).
function followWidth(plot, container) {
  const observer = new ResizeObserver(() => plot.setSize({ width: widthOf(container), height: plot.height }));
  observer.observe(container);
  return () => observer.disconnect();
}

/** A live time series of `labels` (one y value each per push), keeping the last `keep` points;
 *  redraws at most once per animation frame however fast pushes come. */
export function liveSeries(container, { title, labels, yLabel, keep = 1200, height = 220 }) {
  const columns = [[], ...labels.map(() => [])];
  const opts = {
    title, width: widthOf(container), height,
    scales: { x: { time: false } },
    axes: [{ label: 'station time [s]' }, { label: yLabel }],
    series: [{ label: 't [s]' }, ...labels.map((label, i) => ({ label, stroke: PALETTE[i % PALETTE.length], width: 1.5 }))],
  };
  const plot = new uPlot(opts, columns, container);
  const unfollow = followWidth(plot, container);
  let pending = false;
  return {
    push(t, values) {
      if (columns[0].length && t < columns[0][columns[0].length - 1]) {
        for (const c of columns) c.length = 0;  // a new run restarts station time
      }
      columns[0].push(t);
      values.forEach((v, i) => columns[i + 1].push(v ?? null));
      if (columns[0].length > keep) for (const c of columns) c.splice(0, columns[0].length - keep);
      if (!pending) {
        pending = true;
        requestAnimationFrame(() => {
          pending = false;
          plot.setData(columns);
        });
      }
    },
    points: () => columns[0].length,
    destroy() {
      unfollow();
      plot.destroy();
    },
  };
}

/** Points (no lines) of y against x, one series per group: `points` = [{x, y, group}]. Groups
 *  keep their colour in `groupOrder`; `xAxisLabel` names what x is this time. */
export function groupedPoints(container, { title, xLabel, yLabel, height = 260 }) {
  let plot = null;
  let unfollow = () => {};
  return {
    set(points, groupOrder, xAxisLabel = xLabel) {
      const sorted = [...points].filter((p) => Number.isFinite(p.x) && Number.isFinite(p.y)).sort((a, b) => a.x - b.x);
      const groups = groupOrder || [...new Set(sorted.map((p) => p.group))];
      const xs = sorted.map((p) => p.x);
      const ys = groups.map((g) => sorted.map((p) => (p.group === g ? p.y : null)));
      if (plot) {
        unfollow();
        plot.destroy();
      }
      plot = new uPlot({
        title, width: widthOf(container), height,
        scales: { x: { time: false } },
        axes: [{ label: xAxisLabel }, { label: yLabel }],
        series: [{ label: xAxisLabel }, ...groups.map((g, i) => ({
          label: String(g), stroke: PALETTE[i % PALETTE.length], fill: PALETTE[i % PALETTE.length],
          paths: () => null, points: { show: true, size: 7 },
        }))],
      }, [xs, ...ys], container);
      unfollow = followWidth(plot, container);
    },
    destroy() {
      unfollow();
      if (plot) plot.destroy();
    },
  };
}

/** A falling curve: y (log scale) against a whole-number x, with points. */
export function logCurve(container, { title, xLabel, yLabel, label, height = 220 }) {
  let plot = null;
  let unfollow = () => {};
  return {
    set(xs, ys) {
      if (plot) {
        unfollow();
        plot.destroy();
      }
      plot = new uPlot({
        title, width: widthOf(container), height,
        scales: { x: { time: false }, y: { distr: 3 } },
        axes: [{ label: xLabel, incrs: [1, 2, 5, 10, 20, 50] }, { label: yLabel }],
        series: [{ label: xLabel }, { label, stroke: PALETTE[0], width: 2, points: { show: true, size: 8 } }],
      }, [xs, ys], container);
      unfollow = followWidth(plot, container);
    },
    destroy() {
      unfollow();
      if (plot) plot.destroy();
    },
  };
}

// The lot report's colours (analysis/src/lot_html.cpp), so that the console's chart and the
// printed one read alike: units blue, the mean green, limits and outliers red.
const CONTROL_COLOURS = { unit: '#1f77b4', mean: '#2ca02c', limit: '#d62728' };
// Below this many units the x axis names each unit by its serial; beyond, by its number.
const SERIALS_ON_AXIS = 12;

// The ticks of an axis `incr` apart, with the digits that tell them apart and no more (uPlot's
// own rounds 1.5e-5 to 0, and 0.0015 and 0.002 to the same text); one form for the whole axis,
// chosen by its largest tick.
function tickTexts(splits, incr) {
  const largest = Math.max(incr, ...splits.map((v) => Math.abs(v)));
  const step = Math.floor(Math.log10(incr) + 1e-9);  // the decade of the increment
  const clamp = (digits) => Math.min(Math.max(0, digits), 12);
  if (largest >= 1e-3 && largest < 1e6) return splits.map((v) => v.toFixed(clamp(-step)));
  const digits = clamp(Math.floor(Math.log10(largest) + 1e-9) - step);
  return splits.map((v) => (v === 0 ? '0' : v.toExponential(digits)));
}

/** An individuals control chart of one lot parameter (GET /lot's `parameters[i]`): each unit's
 *  value in calibration order joined by a line, the mean, the upper and lower control limits
 *  (UCL, LCL: dashed) and the flagged outliers ringed. The legend names the unit under the
 *  cursor. */
export function controlChart(container, parameter, { height = 230 } = {}) {
  const values = parameter.values.map((v) => v.value);
  const serials = parameter.values.map((v) => v.serial);
  const flagged = new Set(parameter.outliers.map((o) => o.serial));
  const n = values.length;
  const xs = values.map((_, i) => i + 1);
  const flat = (y) => xs.map(() => y);
  const data = [xs, values, flat(parameter.mean), flat(parameter.control.upper), flat(parameter.control.lower),
    values.map((v, i) => (flagged.has(serials[i]) ? v : null))];
  const line = (label, stroke, extra = {}) => ({ label, stroke, width: 1.5, points: { show: false }, ...extra });
  const plot = new uPlot({
    width: widthOf(container), height,
    scales: { x: { time: false, range: () => [0.5, n + 0.5] } },
    axes: [
      { label: 'unit, in calibration order', incrs: [1, 2, 5, 10, 20, 50, 100, 200, 500],
        values: (u, splits) => splits.map((x) => (Number.isInteger(x) && x >= 1 && x <= n
          ? (n <= SERIALS_ON_AXIS ? serials[x - 1] : String(x)) : '')) },
      // The panel's title names the parameter; the axis says its unit, its ticks as wide as
      // their text.
      { label: parameter.unit, values: (u, splits, axis, space, incr) => tickTexts(splits, incr),
        size: (u, texts) => 24 + 7 * Math.max(3, ...(texts || []).map((t) => String(t).length)) },
    ],
    series: [
      { label: 'unit', value: (u, x) => (x === null || x === undefined ? '–' : `${x}: ${serials[x - 1] ?? ''}`) },
      line('value', CONTROL_COLOURS.unit, { points: { show: true, size: 6 } }),
      line('mean', CONTROL_COLOURS.mean, { width: 1 }),
      line('UCL', CONTROL_COLOURS.limit, { dash: [6, 4] }),
      line('LCL', CONTROL_COLOURS.limit, { dash: [6, 4] }),
      { label: 'outlier', stroke: CONTROL_COLOURS.limit, paths: () => null,
        points: { show: true, size: 13, width: 2, stroke: CONTROL_COLOURS.limit, fill: 'rgba(0,0,0,0)' } },
    ],
  }, data, container);
  // What is drawn, for whoever checks the page (the browser test): units and outliers marked.
  container.dataset.units = String(n);
  container.dataset.outliers = String(data[5].filter((v) => v !== null).length);
  const unfollow = followWidth(plot, container);
  return {
    destroy() {
      unfollow();
      plot.destroy();
    },
  };
}
