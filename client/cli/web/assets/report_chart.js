// The build report's chart and percentages for the geodex viewer
// (viewer.js): the relative error by distance drawn as an inline SVG, and
// relative errors formatted as the core's FormatPercent formats them
// (core/index/index_report.h), so that the viewer shows the report's figures.
// Sets window.geodexReportChart = { formatPercent, formatMiB, drawChart,
// chartLayout }.
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

  // What the chart draws (core/index/report_chart.h, MakeChartLayout): the
  // report's bands by L1000 from 0.25 to 64 on a log axis, vertex and
  // interior p99, the target's limit over the bands it judges only; a
  // report without bands (formats before them) by its bins in its own L.
  function chartLayout(accuracy) {
    const finite = (v) => v !== null && v !== undefined && Number.isFinite(v);
    if (!accuracy.bands || accuracy.bands.length === 0) {
      const min = 0.1, max = 100;
      const layout = {
        min, max, ticks: [[0.1, '0.1L'], [1, 'L'], [3, '3L'], [10, '10L'], [100, '100L']],
        axisLabel: 'distance / L (log scale)',
        series: [{ key: 'p99', label: 'p99', steps: [] }, { key: 'rms', label: 'RMS', steps: [] }],
        limit: [],
      };
      for (const b of accuracy.bins) {
        const range = { key: b.key, from: Math.max(b.from_L, min), to: Math.min(b.to_L === null ? Infinity : b.to_L, max) };
        if (finite(b.p99)) layout.series[0].steps.push({ ...range, value: b.p99 });
        if (finite(b.rms)) layout.series[1].steps.push({ ...range, value: b.rms });
        if (finite(b.p99_limit)) layout.limit.push({ ...range, value: b.p99_limit });
      }
      return layout;
    }
    const min = 0.25, max = 64;
    const layout = {
      min, max, ticks: [[0.25, '0.25'], [1, '1'], [4, '4'], [8, '8'], [16, '16'], [64, '64']],
      axisLabel: 'distance / L1000 (log scale)',
      series: [{ key: 'p99-vertex', label: 'vertex', steps: [] },
               { key: 'p99-interior', label: 'interior', steps: [] }],
      limit: [],
    };
    for (const b of accuracy.bands) {
      const range = { key: b.key, from: Math.max(b.from, min), to: Math.min(b.to === null ? Infinity : b.to, max) };
      if (finite(b.p99_vertex)) layout.series[0].steps.push({ ...range, value: b.p99_vertex });
      if (finite(b.p99_interior)) layout.series[1].steps.push({ ...range, value: b.p99_interior });
      if (finite(b.p99_limit)) layout.limit.push({ ...range, value: b.p99_limit });
    }
    return layout;
  }

  // The error axis: from 0 to the largest figure x 1.1, rounded up to a
  // whole step of 1, 2 or 5 x 10^k giving at most 7 gridlines.
  function chartErrorMax(layout) {
    let top = 0;
    for (const s of layout.series) for (const st of s.steps) top = Math.max(top, st.value);
    for (const st of layout.limit) top = Math.max(top, st.value);
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

  // The layout's series against distance, each range a step with a dot at
  // its geometric middle, and the target's p99 limit dashed. Each drawn
  // figure carries its range and value (data-*), so that a test can compare
  // the chart with the report.
  function drawChart(accuracy, target) {
    const holder = document.getElementById('accuracy-chart');
    holder.innerHTML = '';
    const width = 290, height = 180;
    const frame = { left: 38, right: width - 8, top: 22, bottom: height - 30 };
    const layout = chartLayout(accuracy);
    const { max, step } = chartErrorMax(layout);
    const x = (d) => frame.left + (Math.log10(d) - Math.log10(layout.min)) /
      (Math.log10(layout.max) - Math.log10(layout.min)) * (frame.right - frame.left);
    const y = (e) => frame.bottom - e / max * (frame.bottom - frame.top);
    const root = svg('svg', {
      viewBox: `0 0 ${width} ${height}`, width, height, role: 'img',
      'aria-label': 'relative error by distance', 'data-error-max': max,
      'data-plot-left': frame.left, 'data-plot-right': frame.right,
      'data-plot-top': frame.top, 'data-plot-bottom': frame.bottom,
      'data-axis-min': layout.min, 'data-axis-max': layout.max,
    }, holder);
    const decimals = 100 * step >= 1 ? 0 : Math.ceil(-Math.log10(100 * step) - 1e-9);
    for (let k = 0; k * step <= max * (1 + 1e-9); ++k) {
      svg('line', { x1: frame.left, x2: frame.right, y1: y(k * step), y2: y(k * step), class: k ? 'grid' : 'axis' }, root);
      svg('text', { x: frame.left - 4, y: y(k * step) + 3, 'text-anchor': 'end', class: 'tick' }, root)
        .textContent = `${(100 * k * step).toFixed(decimals)}%`;
    }
    for (const [d, label] of layout.ticks) {
      svg('line', { x1: x(d), x2: x(d), y1: frame.top, y2: frame.bottom, class: d === layout.min ? 'axis' : 'grid' }, root);
      // The last label ends at its line, inside the picture.
      svg('text', { x: x(d), y: frame.bottom + 11, 'text-anchor': d === layout.max ? 'end' : 'middle', class: 'tick' }, root)
        .textContent = label;
    }
    svg('text', { x: (frame.left + frame.right) / 2, y: height - 4, 'text-anchor': 'middle', class: 'tick' }, root)
      .textContent = layout.axisLabel;
    let limit = '';
    layout.limit.forEach((st, i) => {
      const joined = i > 0 && layout.limit[i - 1].to === st.from;
      limit += `${joined ? 'L' : 'M'}${x(st.from)} ${y(st.value)} L${x(st.to)} ${y(st.value)} `;
    });
    svg('path', { d: limit, class: 'limit', 'data-series': 'limit',
                  'data-ranges': layout.limit.map((st) => st.key).join(' '),
                  'data-values': layout.limit.map((st) => st.value).join(' ') }, root);
    // The first series drawn last, on top.
    layout.series.forEach((series, i) => {
      series.cls = i === 0 ? 'p99' : 'rms';
    });
    for (const series of [...layout.series].reverse()) {
      for (const st of series.steps) {
        svg('line', { x1: x(st.from), x2: x(st.to), y1: y(st.value), y2: y(st.value), class: `series ${series.cls}`,
                      'data-series': series.key, 'data-bin': st.key, 'data-value': st.value }, root);
        svg('circle', { cx: x(Math.sqrt(st.from * st.to)), cy: y(st.value), r: 2.5, class: `series ${series.cls}` }, root);
      }
    }
    let lx = frame.left + 4;
    const legend = layout.series.map((s) => [s.cls, s.label]);
    legend.push(['limit', `limit (target ${formatPercent(target.error)})`]);
    for (const [cls, label] of legend) {
      svg('line', { x1: lx, x2: lx + 12, y1: 9, y2: 9, class: cls === 'limit' ? 'limit' : `series ${cls}` }, root);
      svg('text', { x: lx + 15, y: 12, class: 'tick' }, root).textContent = label;
      lx += 22 + 5.2 * label.length;
    }
  }


  window.geodexReportChart = { formatPercent, formatMiB, drawChart, chartLayout };
})();
