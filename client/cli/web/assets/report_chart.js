// The build report's chart and percentages for the geodex viewer
// (viewer.js): the relative error by distance drawn as an inline SVG, and
// relative errors formatted as the core's FormatPercent formats them
// (core/index/index_report.h), so that the viewer shows the report's figures.
// Sets window.geodexReportChart = { formatPercent, formatMiB, drawChart }.
(function () {
  'use strict';

  function formatPercent(fraction) {
    if (fraction === null || fraction === undefined || Number.isNaN(fraction)) return 'n/a';
    const v = 100 * fraction;
    if (v === 0) return '0%';
    if (v < 0.001) return '<0.001%';
    const decimals = v >= 100 ? 0 : v >= 10 ? 1 : v >= 1 ? 2 : v >= 0.1 ? 3 : v >= 0.01 ? 4 : 5;
    return `${v.toFixed(decimals)}%`;
  }
  const formatMiB = (bytes) => {
    const mib = bytes / 1048576;
    return `${mib.toFixed(mib >= 0.1 || bytes === 0 ? 2 : 3)} MiB`;
  };

  // The chart's frame (core/index/report_chart.h): distance / L from 0.1 to
  // 100 on a log axis; error from 0 to the largest figure x 1.1, rounded up
  // to a whole step of 1, 2 or 5 x 10^k giving at most 7 gridlines.
  const CHART_MIN_L = 0.1, CHART_MAX_L = 100;
  function chartErrorMax(bins) {
    let top = 0;
    for (const b of bins) {
      for (const v of [b.p99, b.rms, b.p99_limit]) if (Number.isFinite(v)) top = Math.max(top, v);
    }
    top = top > 0 ? 1.1 * top : 0.01;
    const decade = Math.pow(10, Math.floor(Math.log10(top / 7)));
    let step = decade;
    for (const f of [1, 2, 5, 10]) {
      step = f * decade;
      if (top / step <= 7) break;
    }
    return { max: Math.ceil(top / step - 1e-9) * step, step };
  }

  const SVG = 'http://www.w3.org/2000/svg';
  function svg(tag, attrs, parent) {
    const e = document.createElementNS(SVG, tag);
    for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, String(v));
    if (parent) parent.appendChild(e);
    return e;
  }

  // The calibration's p99 and RMS against distance, each bin a step over its
  // range with a dot at its geometric middle, and the target's p99 limit
  // dashed. Each drawn figure carries its bin and value (data-*), so that a
  // test can compare the chart with the report.
  function drawChart(accuracy, target) {
    const holder = document.getElementById('accuracy-chart');
    holder.innerHTML = '';
    const width = 290, height = 180;
    const frame = { left: 38, right: width - 8, top: 22, bottom: height - 30 };
    const { max, step } = chartErrorMax(accuracy.bins);
    const x = (l) => frame.left + (Math.log10(l) - Math.log10(CHART_MIN_L)) /
      (Math.log10(CHART_MAX_L) - Math.log10(CHART_MIN_L)) * (frame.right - frame.left);
    const y = (e) => frame.bottom - e / max * (frame.bottom - frame.top);
    const root = svg('svg', {
      viewBox: `0 0 ${width} ${height}`, width, height, role: 'img',
      'aria-label': 'relative error by distance', 'data-error-max': max,
      'data-plot-left': frame.left, 'data-plot-right': frame.right,
      'data-plot-top': frame.top, 'data-plot-bottom': frame.bottom,
    }, holder);
    const decimals = 100 * step >= 1 ? 0 : Math.ceil(-Math.log10(100 * step) - 1e-9);
    for (let k = 0; k * step <= max * (1 + 1e-9); ++k) {
      svg('line', { x1: frame.left, x2: frame.right, y1: y(k * step), y2: y(k * step), class: k ? 'grid' : 'axis' }, root);
      svg('text', { x: frame.left - 4, y: y(k * step) + 3, 'text-anchor': 'end', class: 'tick' }, root)
        .textContent = `${(100 * k * step).toFixed(decimals)}%`;
    }
    for (const [l, label] of [[0.1, '0.1L'], [1, 'L'], [3, '3L'], [10, '10L'], [100, '100L']]) {
      svg('line', { x1: x(l), x2: x(l), y1: frame.top, y2: frame.bottom, class: l === 0.1 ? 'axis' : 'grid' }, root);
      // The last label ends at its line, inside the picture.
      svg('text', { x: x(l), y: frame.bottom + 11, 'text-anchor': l === CHART_MAX_L ? 'end' : 'middle', class: 'tick' }, root)
        .textContent = label;
    }
    svg('text', { x: (frame.left + frame.right) / 2, y: height - 4, 'text-anchor': 'middle', class: 'tick' }, root)
      .textContent = 'distance / L (log scale)';
    const range = (b) => [Math.max(b.from_L, CHART_MIN_L), Math.min(b.to_L === null ? Infinity : b.to_L, CHART_MAX_L)];
    let limit = '';
    for (const b of accuracy.bins) {
      const [from, to] = range(b);
      limit += `${limit ? 'L' : 'M'}${x(from)} ${y(b.p99_limit)} L${x(to)} ${y(b.p99_limit)} `;
    }
    svg('path', { d: limit, class: 'limit', 'data-series': 'limit', 'data-values': accuracy.bins.map((b) => b.p99_limit).join(' ') }, root);
    for (const series of ['rms', 'p99']) {
      for (const b of accuracy.bins) {
        const v = b[series];
        if (!Number.isFinite(v)) continue;
        const [from, to] = range(b);
        svg('line', { x1: x(from), x2: x(to), y1: y(v), y2: y(v), class: `series ${series}`,
                      'data-series': series, 'data-bin': b.key, 'data-value': v }, root);
        svg('circle', { cx: x(Math.sqrt(from * to)), cy: y(v), r: 2.5, class: `series ${series}` }, root);
      }
    }
    let lx = frame.left + 4;
    for (const [cls, label] of [['p99', 'p99'], ['rms', 'RMS'], ['limit', `limit (target ${formatPercent(target.error)})`]]) {
      svg('line', { x1: lx, x2: lx + 12, y1: 9, y2: 9, class: cls === 'limit' ? 'limit' : `series ${cls}` }, root);
      svg('text', { x: lx + 15, y: 12, class: 'tick' }, root).textContent = label;
      lx += 22 + 5.2 * label.length;
    }
  }


  window.geodexReportChart = { formatPercent, formatMiB, drawChart };
})();
