"use strict";
// Live mode of lightgraph's report viewer (`render --serve`): the images come from the server
// (little-endian f32 RGB; window.lightgraphLiveSources maps an image's label to { url, live }) and
// the live ones are fetched anew whenever the film's version changes; the status above the viewer says the frames,
// samples/s and the error against the reference. window.lightgraphLive holds the last status,
// the version drawn and how many times the images were loaded.
(function () {
  const live = { version: -1, drawn: -1, loads: 0, status: null, gone: null };
  window.lightgraphLive = live;

  // Each image's floats, for the version they were fetched at (one fetch per image and
  // version, however many panes show it).
  const kept = new Map();

  window.lightgraphLoader = function (image) {
    const source = window.lightgraphLiveSources[image.label];
    const version = source.live ? live.version : null;
    const held = kept.get(image.id);
    if (held && held.version === version) return held.floats;
    const floats = fetchFloats(source.url, image);
    kept.set(image.id, { version, floats });
    return floats;
  };

  async function fetchFloats(url, image) {
    const response = await fetch(`${url}?v=${live.version}`, { cache: "no-store" });
    if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
    const view = new DataView(await response.arrayBuffer());
    const floats = new Float32Array(view.byteLength / 4);
    for (let i = 0; i < floats.length; i++) floats[i] = view.getFloat32(4 * i, true);
    if (floats.length !== 3 * image.width * image.height)
      throw new Error(`${url}: ${floats.length} floats where ${image.width}x${image.height} RGB are ${3 * image.width * image.height}`);
    live.loads += 1;
    return floats;
  }

  const line = document.createElement("p");
  line.className = "lg-note lg-live";

  async function poll() {
    try {
      const s = await (await fetch("status.json", { cache: "no-store" })).json();
      live.status = s;
      line.textContent = `live: ${s.status || "starting"}${s.finished ? " (the render is over)" : ""}`;
      if (s.version !== live.version) {
        live.version = s.version;
        await window.lightgraph.ready;
        await Promise.all(window.lightgraph.viewers.map((v) => v.set({})));
        live.drawn = s.version;
      }
      if (!s.finished) setTimeout(poll, 1000);
    } catch (e) {
      live.gone = String(e);
      line.textContent += " | the render has ended (no answer from the server); the last image stays";
    }
  }

  window.addEventListener("load", () => {
    document.querySelector(".lightgraph-report").prepend(line);
    poll();
  });
})();
