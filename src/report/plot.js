"use strict";
// Line plots of a lightgraph report on a canvas: logarithmic or linear axes, each line's
// uncertainty as a band, and the values of the point nearest the cursor.
window.LightgraphPlot = (function () {
  const COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#7f7f7f", "#bcbd22"];
  const MARGIN = { left: 70, right: 20, top: 30, bottom: 50 };

  function number(v) {
    if (v === null || v === undefined || !isFinite(v)) return "–";
    const a = Math.abs(v);
    return a !== 0 && (a < 1e-3 || a >= 1e5) ? v.toExponential(3) : String(+v.toPrecision(4));
  }

  // A tick label: three significant digits at most, no float noise.
  const tick = (v) => String(+v.toPrecision(3));

  // The axis over `values`: its range and ticks, and a map from value to 0..1.
  function axis(values, log) {
    const ok = values.filter((v) => isFinite(v) && (!log || v > 0));
    let lo = Math.min(...ok), hi = Math.max(...ok);
    if (!ok.length) { lo = log ? 1 : 0; hi = log ? 10 : 1; }
    if (log) {
      lo = Math.pow(10, Math.floor(Math.log10(lo) * 4) / 4);
      hi = Math.pow(10, Math.ceil(Math.log10(hi) * 4) / 4);
      if (hi <= lo) hi = lo * 10;
      const f = (v) => (Math.log10(v) - Math.log10(lo)) / (Math.log10(hi) - Math.log10(lo));
      const ticks = [];
      const steps = hi / lo > 1e3 ? [1] : [1, 2, 5];
      for (let e = Math.floor(Math.log10(lo)); e <= Math.ceil(Math.log10(hi)); e++)
        steps.forEach((m) => { const t = m * Math.pow(10, e); if (t >= lo && t <= hi) ticks.push(t); });
      return { f, ticks };
    }
    lo = Math.min(lo, 0);
    hi = hi > lo ? hi * 1.05 : lo + 1;
    const step = Math.pow(10, Math.floor(Math.log10((hi - lo) / 4)));
    const ticks = [];
    for (let t = Math.ceil(lo / step) * step; t <= hi; t += step) ticks.push(t);
    return { f: (v) => (v - lo) / (hi - lo), ticks: ticks.length > 8 ? ticks.filter((_, i) => i % 2 === 0) : ticks };
  }

  function drawAxes(ctx, spec, x, y, w, h) {
    ctx.strokeStyle = "#ccc"; ctx.fillStyle = "#333"; ctx.font = "12px sans-serif";
    ctx.textAlign = "center";
    x.ticks.forEach((t) => {
      const px = MARGIN.left + x.f(t) * w;
      ctx.beginPath(); ctx.moveTo(px, MARGIN.top); ctx.lineTo(px, MARGIN.top + h); ctx.stroke();
      ctx.fillText(tick(t), px, MARGIN.top + h + 16);
    });
    ctx.textAlign = "right";
    y.ticks.forEach((t) => {
      const py = MARGIN.top + (1 - y.f(t)) * h;
      ctx.beginPath(); ctx.moveTo(MARGIN.left, py); ctx.lineTo(MARGIN.left + w, py); ctx.stroke();
      ctx.fillText(tick(t), MARGIN.left - 6, py + 4);
    });
    ctx.strokeStyle = "#333"; ctx.strokeRect(MARGIN.left, MARGIN.top, w, h);
    ctx.textAlign = "center";
    ctx.fillText(spec.x_label, MARGIN.left + w / 2, MARGIN.top + h + 38);
    ctx.save(); ctx.translate(16, MARGIN.top + h / 2); ctx.rotate(-Math.PI / 2);
    ctx.fillText(spec.y_label, 0, 0); ctx.restore();
  }

  function drawLine(ctx, line, colour, at) {
    const pts = line.points.filter((p) => at(p[0], p[1]));
    const band = pts.filter((p) => p[2] !== null && p[3] !== null && at(p[0], p[2]) && at(p[0], p[3]));
    if (band.length > 1) {
      ctx.globalAlpha = 0.18; ctx.fillStyle = colour; ctx.beginPath();
      band.forEach((p, i) => { const [sx, sy] = at(p[0], p[3]); i ? ctx.lineTo(sx, sy) : ctx.moveTo(sx, sy); });
      band.slice().reverse().forEach((p) => ctx.lineTo(...at(p[0], p[2])));
      ctx.fill(); ctx.globalAlpha = 1;
    }
    ctx.strokeStyle = colour; ctx.fillStyle = colour; ctx.lineWidth = 2;
    ctx.setLineDash(line.dashed ? [6, 4] : []);
    ctx.beginPath();
    pts.forEach((p, i) => { const [sx, sy] = at(p[0], p[1]); i ? ctx.lineTo(sx, sy) : ctx.moveTo(sx, sy); });
    ctx.stroke(); ctx.setLineDash([]); ctx.lineWidth = 1;
    if (!line.dashed) pts.forEach((p) => { const [sx, sy] = at(p[0], p[1]); ctx.fillRect(sx - 2.5, sy - 2.5, 5, 5); });
  }

  // A plot of `spec` (title, axis labels and scales, lines of [x, y, lo, hi] points, a note on
  // the bands): its element, and `pointAt(line, index)`, the canvas position of a point.
  function create(spec) {
    const canvas = Object.assign(document.createElement("canvas"), { width: 720, height: 420 });
    const tip = Object.assign(document.createElement("div"), { className: "lg-tip" });
    const w = canvas.width - MARGIN.left - MARGIN.right, h = canvas.height - MARGIN.top - MARGIN.bottom;
    const all = spec.lines.flatMap((l) => l.points);
    const x = axis(all.map((p) => p[0]), spec.log_x);
    const y = axis(all.flatMap((p) => [p[1], p[2], p[3]]).filter((v) => v !== null), spec.log_y);
    const usable = (vx, vy) => isFinite(vx) && isFinite(vy) && (!spec.log_x || vx > 0) && (!spec.log_y || vy > 0);
    const at = (vx, vy) => usable(vx, vy) && [MARGIN.left + x.f(vx) * w, MARGIN.top + (1 - y.f(vy)) * h];
    const ctx = canvas.getContext("2d");
    ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, canvas.width, canvas.height);
    drawAxes(ctx, spec, x, y, w, h);
    spec.lines.forEach((l, i) => drawLine(ctx, l, COLOURS[i % COLOURS.length], at));
    canvas.addEventListener("mousemove", (e) => hover(e, canvas, spec, at, tip));
    canvas.addEventListener("mouseleave", () => { tip.style.display = "none"; });
    const legend = document.createElement("div");
    legend.className = "lg-legend";
    spec.lines.forEach((l, i) => {
      const item = document.createElement("span");
      item.innerHTML = `<i style="background:${COLOURS[i % COLOURS.length]}"></i>`;
      item.append(l.label);
      legend.append(item);
    });
    const root = document.createElement("figure");
    root.className = "lg-plot";
    const title = Object.assign(document.createElement("figcaption"), { textContent: spec.title });
    const note = Object.assign(document.createElement("p"), { className: "lg-note", textContent: spec.note });
    const holder = Object.assign(document.createElement("div"), { className: "lg-plot-canvas" });
    holder.append(canvas, tip);
    root.append(title, holder, legend, note);
    return { element: root, canvas, tip, pointAt: (line, index) => at(...spec.lines[line].points[index].slice(0, 2)) };
  }

  function hover(e, canvas, spec, at, tip) {
    const r = canvas.getBoundingClientRect();
    const mx = (e.clientX - r.left) * canvas.width / r.width, my = (e.clientY - r.top) * canvas.height / r.height;
    let best = null, bestD = 15 * 15;
    spec.lines.forEach((l) => l.points.forEach((p) => {
      const s = at(p[0], p[1]);
      const d = s && (s[0] - mx) ** 2 + (s[1] - my) ** 2;
      if (s && d < bestD) { best = { l, p, s }; bestD = d; }
    }));
    if (!best) { tip.style.display = "none"; return; }
    const [vx, vy, lo, hi] = best.p;
    const range = lo !== null && hi !== null ? ` [${number(lo)}, ${number(hi)}]` : "";
    tip.textContent = `${best.l.label}: ${spec.x_label} ${number(vx)}, ${spec.y_label} ${number(vy)}${range}`;
    tip.style.display = "block";
    tip.style.left = `${best.s[0] * r.width / canvas.width + 10}px`;
    tip.style.top = `${best.s[1] * r.height / canvas.height + 10}px`;
  }

  return { create, number };
})();
