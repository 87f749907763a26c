"use strict";
// lightgraph's report viewer: draws a manifest (title; items: Markdown blocks, image viewers,
// plots; images by id) into the page. Image data comes from `load(image)`, a promise of its
// little-endian f32 RGB floats, so the viewer does not care where data lives.
window.LightgraphViewer = (function () {
  const MODES = [["a", "A"], ["b", "B"], ["split", "split"], ["error", "rel. error"], ["tmap", "t-map"]];
  const ERROR_RAMP = [[0, 0, 4], [81, 18, 124], [183, 55, 121], [252, 137, 97], [252, 253, 191]];
  const CANVAS = 640;
  const f32 = Math.fround;

  function el(tag, props, ...children) {
    const e = Object.assign(document.createElement(tag), props || {});
    e.append(...children);
    return e;
  }

  // Text with **bold** and `code`, its HTML escaped.
  function inline(text) {
    const escaped = text.replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" })[c]);
    return escaped.replace(/\*\*(.+?)\*\*/g, "<b>$1</b>").replace(/`([^`]+)`/g, "<code>$1</code>");
  }

  function markdown(blocks) {
    const root = el("div", { className: "lg-text" });
    for (const b of blocks) {
      if (b.kind === "heading") root.append(el(`h${Math.min(b.level, 6)}`, { innerHTML: inline(b.text) }));
      if (b.kind === "paragraph") root.append(el("p", { innerHTML: inline(b.text) }));
      if (b.kind === "list") root.append(el("ul", {}, ...b.items.map((i) => el("li", { innerHTML: inline(i) }))));
      if (b.kind === "table") root.append(table(b));
    }
    return root;
  }

  function table(b) {
    const cell = (tag, text, i) => el(tag, { innerHTML: inline(text), className: b.right[i] ? "lg-right" : "" });
    const head = el("thead", {}, el("tr", {}, ...b.header.map((h, i) => cell("th", h, i))));
    const body = el("tbody", {}, ...b.rows.map((r) => el("tr", {}, ...r.map((c, i) => cell("td", c, i)))));
    return el("div", { className: "lg-table" }, el("table", {}, head, body));
  }

  // A linear value as the PNG previews write it: clamped to [0, 1], the sRGB curve, 8 bits
  // (in f32 steps, as the Rust code computes it).
  function srgb8(v) {
    v = Math.min(Math.max(v, 0), 1);
    const c = v <= 0.0031308 ? f32(12.92 * v) : f32(f32(1.055 * f32(Math.pow(v, f32(1 / 2.4)))) - 0.055);
    return Math.round(f32(c * 255)) || 0;
  }

  const luminance = (d, i) => 0.2126 * d[i] + 0.7152 * d[i + 1] + 0.0722 * d[i + 2];

  function ramp(t) {
    const x = Math.min(Math.max(t, 0), 1) * (ERROR_RAMP.length - 1);
    const i = Math.min(Math.floor(x), ERROR_RAMP.length - 2), f = x - i;
    return ERROR_RAMP[i].map((c, k) => c + f * (ERROR_RAMP[i + 1][k] - c));
  }

  // The relative error of A against B at a pixel: |lum A − lum B| / (lum B + 0.01).
  const relative = (a, b, i) => Math.abs(luminance(a, i) - luminance(b, i)) / (luminance(b, i) + 0.01);

  // The t-map of the pair shown, with the sign for A against B, or null.
  function tmapOf(spec, a, b) {
    for (const m of spec.tmaps) {
      if (m.a === a.label && m.b === b.label) return { map: m, sign: 1 };
      if (m.a === b.label && m.b === a.label) return { map: m, sign: -1 };
    }
    return null;
  }

  // The colour of pixel `p` (index into the floats) at (x, y) in the state's mode.
  function pixel(s, x, y, p) {
    const scale = f32(Math.pow(2, s.exposure));
    const tone = (d) => [srgb8(f32(d[p] * scale)), srgb8(f32(d[p + 1] * scale)), srgb8(f32(d[p + 2] * scale))];
    if (s.mode === "a") return tone(s.A);
    if (s.mode === "b") return tone(s.B);
    if (s.mode === "split") return tone(x < s.split * s.width ? s.A : s.B);
    if (s.mode === "error") return ramp(relative(s.A, s.B, p));
    const grey = 0.5 * srgb8(scale * 0.5 * (luminance(s.A, p) + luminance(s.B, p)));
    const { map, sign } = s.tmap, block = map.block;
    const [bx, by] = [Math.floor(x / block), Math.floor(y / block)];
    const k = by * map.grid[0] + bx, t = sign * map.t[k];
    const edge = x % block === 0 || y % block === 0 || x === s.width - 1 || y === s.height - 1;
    if (map.rejected[k] && edge) return [255, 255, 255];
    const w = Math.min(Math.abs(t) / map.critical, 1), tint = t > 0 ? [255, 26, 26] : [26, 77, 255];
    return tint.map((c) => grey * (1 - w) + c * w);
  }

  // Renders the state into its image-sized canvas.
  function compose(s) {
    const data = new ImageData(s.width, s.height);
    for (let y = 0; y < s.height; y++)
      for (let x = 0; x < s.width; x++) {
        const i = y * s.width + x, rgb = pixel(s, x, y, 3 * i);
        data.data.set([Math.round(rgb[0]), Math.round(rgb[1]), Math.round(rgb[2]), 255], 4 * i);
      }
    s.offscreen.getContext("2d").putImageData(data, 0, 0);
  }

  // Draws the image-sized canvas onto the screen's, nearest neighbour, at the view's zoom.
  function draw(s) {
    const ctx = s.canvas.getContext("2d");
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.fillStyle = "#222"; ctx.fillRect(0, 0, s.canvas.width, s.canvas.height);
    ctx.imageSmoothingEnabled = false;
    ctx.setTransform(s.zoom, 0, 0, s.zoom, s.ox, s.oy);
    ctx.drawImage(s.offscreen, 0, 0);
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    if (s.mode === "split") {
      const sx = s.ox + s.split * s.width * s.zoom;
      ctx.strokeStyle = "#fff"; ctx.beginPath(); ctx.moveTo(sx, 0); ctx.lineTo(sx, s.canvas.height); ctx.stroke();
    }
  }

  function readout(s, e) {
    const r = s.canvas.getBoundingClientRect();
    const x = Math.floor(((e.clientX - r.left) * s.canvas.width / r.width - s.ox) / s.zoom);
    const y = Math.floor(((e.clientY - r.top) * s.canvas.height / r.height - s.oy) / s.zoom);
    if (!s.A || x < 0 || y < 0 || x >= s.width || y >= s.height) { s.readout.textContent = ""; return; }
    const p = 3 * (y * s.width + x), n = LightgraphPlot.number;
    const rgb = (d) => `${n(d[p])} ${n(d[p + 1])} ${n(d[p + 2])}`;
    let text = `(${x}, ${y})  A ${s.a.label}: ${rgb(s.A)}  B ${s.b.label}: ${rgb(s.B)}  rel. error ${n(relative(s.A, s.B, p))}`;
    if (s.tmap) {
      const m = s.tmap.map, k = Math.floor(y / m.block) * m.grid[0] + Math.floor(x / m.block);
      text += `  block t ${n(s.tmap.sign * m.t[k])} (critical ${n(m.critical)})`;
    }
    s.readout.textContent = text;
  }

  // Zooms by a power of two about the canvas point (cx, cy).
  function zoomAbout(s, factor, cx, cy) {
    const zoom = Math.min(Math.max(s.zoom * factor, 1 / 16), 256);
    s.ox = cx - (cx - s.ox) * zoom / s.zoom;
    s.oy = cy - (cy - s.oy) * zoom / s.zoom;
    s.zoom = zoom;
    draw(s);
  }

  function canvasPoint(s, e) {
    const r = s.canvas.getBoundingClientRect();
    return [(e.clientX - r.left) * s.canvas.width / r.width, (e.clientY - r.top) * s.canvas.height / r.height];
  }

  function interact(s) {
    s.canvas.addEventListener("wheel", (e) => { e.preventDefault(); zoomAbout(s, e.deltaY < 0 ? 2 : 0.5, ...canvasPoint(s, e)); });
    s.canvas.addEventListener("mousedown", (e) => { s.drag = canvasPoint(s, e); });
    window.addEventListener("mouseup", () => { s.drag = null; });
    s.canvas.addEventListener("mousemove", (e) => {
      const [cx, cy] = canvasPoint(s, e);
      if (s.drag) { s.ox += cx - s.drag[0]; s.oy += cy - s.drag[1]; s.drag = [cx, cy]; draw(s); }
      readout(s, e);
    });
    s.canvas.addEventListener("dblclick", () => { fit(s); draw(s); });
  }

  // The largest power-of-two zoom that fits the canvas, the image centred.
  function fit(s) {
    s.zoom = Math.pow(2, Math.floor(Math.log2(CANVAS / Math.max(s.width, s.height))));
    s.canvas.width = Math.max(1, Math.round(s.width * s.zoom));
    s.canvas.height = Math.max(1, Math.round(s.height * s.zoom));
    s.ox = 0; s.oy = 0;
  }

  function select(images, chosen, onchange) {
    const options = images.map((im, i) => el("option", { value: i, textContent: im.label, selected: i === chosen }));
    return el("select", { onchange }, ...options);
  }

  function range(min, max, step, value, oninput) {
    return el("input", { type: "range", min, max, step, value, oninput });
  }

  // The controls of a viewer: A and B, the mode, flip, exposure and split.
  function controls(s, images, update) {
    s.selectA = select(images, 0, (e) => { s.a = images[+e.target.value]; update(); });
    s.selectB = select(images, Math.min(1, images.length - 1), (e) => { s.b = images[+e.target.value]; update(); });
    s.modeButtons = MODES.map(([mode, label]) => el("button", { textContent: label, value: mode, onclick: () => { s.mode = mode; update(); } }));
    s.flip = el("button", { textContent: "flip A/B", className: "lg-flip", onclick: () => { s.mode = s.mode === "a" ? "b" : "a"; update(); } });
    s.exposureLabel = el("span", { textContent: "exposure 0" });
    s.exposureInput = range(-12, 12, 0.1, 0, (e) => { s.exposure = +e.target.value; update(); });
    s.splitInput = range(0, 1, 0.01, 0.5, (e) => { s.split = +e.target.value; s.mode = "split"; update(); });
    return el("div", { className: "lg-controls" },
      el("label", {}, "A ", s.selectA), el("label", {}, "B ", s.selectB), ...s.modeButtons, s.flip,
      el("label", {}, s.exposureLabel, s.exposureInput), el("label", {}, "split ", s.splitInput));
  }

  // An image viewer of `spec` (title, image ids, t-maps): its element and state.
  function imageViewer(spec, byId, load) {
    const images = spec.images.map((id) => byId.get(id));
    const s = { spec, a: images[0], b: images[Math.min(1, images.length - 1)], mode: "a", exposure: 0, split: 0.5 };
    s.width = s.a.width; s.height = s.a.height;
    s.canvas = el("canvas", { className: "lg-image" });
    s.offscreen = el("canvas", { width: s.width, height: s.height });
    s.readout = el("div", { className: "lg-readout" });
    s.legend = el("div", { className: "lg-note" });
    fit(s);
    let shown = Promise.resolve();
    const update = () => { shown = show(s, load); return shown; };
    s.element = el("section", { className: "lg-viewer" }, el("h2", { textContent: spec.title }),
      controls(s, images, update), s.canvas, s.readout, s.legend);
    interact(s);
    document.addEventListener("keydown", (e) => {
      if (e.key === "f" && s.element.contains(document.activeElement)) s.flip.click();
    });
    s.ready = () => shown;
    s.set = (changes) => { Object.assign(s, changes); return update(); };
    s.screenPoint = (x, y) => [s.ox + (x + 0.5) * s.zoom, s.oy + (y + 0.5) * s.zoom];
    update();
    return s;
  }

  async function show(s, load) {
    [s.A, s.B] = await Promise.all([load(s.a), load(s.b)]);
    s.tmap = tmapOf(s.spec, s.a, s.b);
    if (s.mode === "tmap" && !s.tmap) s.mode = "a";
    if (s.a.width !== s.width || s.b.width !== s.width || s.a.height !== s.height || s.b.height !== s.height)
      throw new Error(`${s.a.label} and ${s.b.label} differ in size from the viewer's ${s.width}x${s.height}`);
    s.modeButtons.forEach((b) => {
      b.classList.toggle("lg-on", b.value === s.mode);
      b.disabled = b.value === "tmap" && !s.tmap;
    });
    s.exposureLabel.textContent = `exposure ${s.exposure >= 0 ? "+" : ""}${s.exposure.toFixed(1)} `;
    s.legend.innerHTML = legendText(s);
    compose(s);
    draw(s);
  }

  function legendText(s) {
    if (s.mode === "error")
      return `relative error |A − B| / (B + 0.01) of the luminance: <span class="lg-ramp"></span> 0 to ≥ 1`;
    if (s.mode === "tmap")
      return `block t-scores of A against B: red where A is brighter, blue where darker, full at |t| ≥ ${s.tmap.map.critical.toFixed(2)}; significant blocks outlined white`;
    return "wheel: zoom (nearest neighbour), drag: pan, double-click: fit; f: flip A/B";
  }

  // Draws `manifest` into `root`; `load(image)` gives an image's floats. Sets
  // window.lightgraph to { viewers, plots, ready } (ready: a promise of the first drawing).
  function mount(root, manifest, load) {
    const byId = new Map(manifest.images.map((im) => [im.id, im]));
    const viewers = [], plots = [];
    const first = manifest.items[0];
    if (!(first && first.kind === "markdown" && first.blocks[0] && first.blocks[0].level === 1))
      root.append(el("h1", { textContent: manifest.title }));
    for (const item of manifest.items) {
      if (item.kind === "markdown") root.append(markdown(item.blocks));
      if (item.kind === "viewer" && item.images.length) {
        viewers.push(imageViewer(item, byId, load));
        root.append(viewers[viewers.length - 1].element);
      }
      if (item.kind === "plot") {
        plots.push(LightgraphPlot.create(item));
        root.append(plots[plots.length - 1].element);
      }
    }
    const ready = Promise.all(viewers.map((v) => v.ready()));
    ready.catch((e) => root.prepend(el("p", { className: "lg-error", textContent: String(e) })));
    window.lightgraph = { viewers, plots, ready };
    return window.lightgraph;
  }

  return { mount, srgb8 };
})();
