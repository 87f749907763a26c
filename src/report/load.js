"use strict";
// Image data of a lightgraph report: base64 of little-endian f32 RGB, handed over by scripts
// that call lightgraphData(id, base64), either in the page or in files beside it that are
// loaded with <script src> (fetch() of file:// is blocked in Chromium; scripts load).
(function () {
  const stored = new Map();
  const waiting = new Map();
  const decoded = new Map();

  window.lightgraphData = function (id, base64) {
    stored.set(id, base64);
    (waiting.get(id) || []).forEach((resolve) => resolve());
    waiting.delete(id);
  };

  function decode(base64) {
    const text = atob(base64);
    const bytes = new Uint8Array(text.length);
    for (let i = 0; i < text.length; i++) bytes[i] = text.charCodeAt(i);
    const view = new DataView(bytes.buffer);
    const out = new Float32Array(bytes.length / 4);
    for (let i = 0; i < out.length; i++) out[i] = view.getFloat32(4 * i, true);
    return out;
  }

  function fromScript(image) {
    return new Promise((resolve, reject) => {
      waiting.set(image.id, (waiting.get(image.id) || []).concat([resolve]));
      const script = document.createElement("script");
      script.src = image.src;
      script.onerror = () => reject(new Error(`cannot load ${image.src}: it belongs beside the report`));
      document.head.appendChild(script);
    });
  }

  // The floats of `image` (a manifest entry): a promise of a Float32Array of width × height × 3.
  window.lightgraphLoader = function (image) {
    if (!decoded.has(image.id)) {
      const ready = stored.has(image.id) || !image.src ? Promise.resolve() : fromScript(image);
      decoded.set(image.id, ready.then(() => {
        if (!stored.has(image.id)) throw new Error(`no data for image ${image.label}`);
        return decode(stored.get(image.id));
      }));
    }
    return decoded.get(image.id);
  };
})();
