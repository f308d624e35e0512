// One chart of the plots view (docs/web.md "Plots"): the series of one node that share a unit, drawn by uPlot
// (web/vendor/uplot: the global uPlot of its classic script), over a window of the emulator's clock, with the node's
// EMCYs and NMT changes as vertical lines labelled on the time axis. Its element carries what the tests read:
// data-points (the samples the node has) and data-marks (the labels of the marks in the window).

/** The series' colours: none of them the marks' (the tests find a mark by its colour). */
const COLORS = ["#1a7f37", "#8250df", "#bc4c00", "#0a7ea4", "#bf3989", "#4d2d00", "#116329", "#6639ba", "#953800",
  "#0550ae"];
/** The marks' colours: an EMCY red and solid, an NMT change grey and dashed. */
export const MARK_COLORS = {emcy: "#cf222e", nmt: "#57606a"};
const HEIGHT = 200;

export class PlotChart {
  element;
  signature; // what the chart was made for: the same series in the same order keep it, anything else remakes it
  #plot;
  #from = null; // the window on the time axis (s), null: the data's own range
  #to = null;
  #marks = [];

  /** chart: Plotting.charts()'s {id, key, unit, series}; title: its heading; width in CSS pixels. */
  constructor(chart, title, width) {
    this.signature = PlotChart.signatureOf(chart);
    this.element = document.createElement("div");
    this.element.className = "plot";
    this.element.dataset.chart = chart.id;
    this.element.dataset.node = chart.key;
    const heading = document.createElement("h3");
    heading.textContent = title;
    this.element.append(heading);
    this.#plot = new uPlot({
      width,
      height: HEIGHT,
      scales: {x: {time: false, range: (u, min, max) => this.#range(min, max)}},
      axes: [{label: "s on the emulator's clock"}, {label: chart.unit, size: 60}],
      series: [
        {label: "time (s)", value: (u, v) => (v === null ? "--" : v.toFixed(3))},
        ...chart.series.map((s, i) => ({label: s.label, stroke: COLORS[i % COLORS.length], width: 1.5})),
      ],
      cursor: {drag: {x: false, y: false}, sync: {key: "canopen-emu-plots"}},
      hooks: {draw: [(u) => this.#drawMarks(u)]},
    }, [[], ...chart.series.map(() => [])], this.element);
  }

  static signatureOf(chart) {
    return JSON.stringify(chart.series.map((s) => [s.object, s.label]));
  }

  /** Shows the samples of `buffer` (web/samples.js) for `objects` from `from` to `to` (s; null: all of them), and
   * `marks` (web/marks.js) in that window. */
  update(buffer, objects, from, to, marks) {
    this.#from = from;
    this.#to = to;
    this.#marks = marks;
    // The window's samples and the one before (the line enters the window from the left edge).
    const first = from === null ? 0 : Math.max(0, buffer.firstAtOrAfter(from) - 1);
    this.#plot.setData([buffer.times.slice(first), ...objects.map((o) => buffer.column(o).slice(first))]);
    const points = String(buffer.length);
    if (this.element.dataset.points !== points) {
      this.element.dataset.points = points;
    }
    const labels = marks.map((m) => m.label).join(", ");
    if (this.element.dataset.marks !== labels) {
      this.element.dataset.marks = labels;
    }
  }

  resize(width) {
    if (this.#plot.width !== width) {
      this.#plot.setSize({width, height: HEIGHT});
    }
  }

  destroy() {
    this.#plot.destroy();
    this.element.remove();
  }

  #range(min, max) {
    if (this.#from !== null) {
      return [this.#from, this.#to];
    }
    return min === null || min === max ? [(min ?? 0) - 1, (max ?? 0) + 1] : [min, max];
  }

  /** The marks as vertical lines across the plotting area, their labels at the top (staggered in three rows, so
   * that marks close in time stay readable). Canvas pixels: a line on a whole pixel, in its exact colour. */
  #drawMarks(u) {
    const {ctx} = u;
    const {left, top, width, height} = u.bbox;
    const ratio = uPlot.pxRatio;
    ctx.save();
    ctx.font = `${Math.round(11 * ratio)}px system-ui, sans-serif`;
    ctx.textAlign = "left"; // uPlot leaves the context as its last axis had it
    ctx.textBaseline = "top";
    ctx.lineWidth = Math.max(1, Math.round(ratio));
    this.#marks.forEach((mark, i) => {
      const x = Math.round(u.valToPos(mark.t, "x", true)) + 0.5;
      if (x < left || x > left + width) {
        return;
      }
      ctx.strokeStyle = MARK_COLORS[mark.kind];
      ctx.fillStyle = MARK_COLORS[mark.kind];
      ctx.setLineDash(mark.kind === "nmt" ? [4 * ratio, 3 * ratio] : []);
      ctx.beginPath();
      ctx.moveTo(x, top);
      ctx.lineTo(x, top + height);
      ctx.stroke();
      ctx.fillText(mark.label, x + 3 * ratio, top + (2 + (i % 3) * 13) * ratio);
    });
    ctx.restore();
  }
}
