// Plots on uPlot (global `uPlot`, from npm, embedded in calstandd): live rolling time series,
// points coloured by group, and a line on a log axis. Each returns an object with the data
// setters a page needs and destroy().

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
