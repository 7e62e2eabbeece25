// REPORT.html's script (inlined by crates/report/src/html.rs): the image viewers,
// sortable tables and the table of contents' highlight. Plain JavaScript, no framework.
"use strict";

(function () {
  // ---- Image viewers --------------------------------------------------------------------
  // Each section.viewer holds one button.viewer-pick per image (the reference first), with
  // the file of each layer in data-image, data-ids and data-flip (empty where the result is
  // identical to the reference, so the map is derived from the reference image by a filter),
  // and data-visits, the heat map of node visits per pixel (empty where none was written).
  const ZOOMS = [1, 2, 4, 8, 16];

  function setUpViewer(viewer) {
    const picks = Array.from(viewer.querySelectorAll(".viewer-pick"));
    const layerButtons = Array.from(viewer.querySelectorAll(".viewer-layer"));
    const img = viewer.querySelector(".viewer-image");
    const stats = viewer.querySelector(".viewer-stats");
    const caption = viewer.querySelector(".viewer-caption");
    const pixel = viewer.querySelector(".viewer-pixel");
    const zoomLevel = viewer.querySelector(".viewer-zoom-level");
    const templates = Array.from(viewer.querySelectorAll("template.viewer-stats-for"));
    const width = Number(img.dataset.width);
    const height = Number(img.dataset.height);
    const reference = picks[0];
    const state = { pick: 0, layer: "image", zoom: Number(img.dataset.zoom) || 1 };

    function show() {
      const pick = picks[state.pick];
      const backend = pick.dataset.backend;
      const file = state.layer === "image" ? pick.dataset.image : pick.dataset[state.layer];
      let derived = "";
      let note = "";
      if (state.layer === "visits" && !file) {
        // No heat map for this backend: it counts no node visits, or its rays traced one at a
        // time do other work than in its batches (a packet traversal).
        derived = state.layer;
        note = "No visits heat map for this backend: it has no per-ray cost distribution.";
      } else if (state.layer !== "image" && !file) {
        // No map was written: this result equals the reference, whose own map against itself
        // is the reference darkened (ids) or zero everywhere (FLIP).
        derived = state.layer;
        note = pick === reference
          ? "The reference compared with itself: no differences."
          : "Identical to the reference: no differences (the map is derived, not stored).";
      } else if (state.layer === "image" && pick !== reference && pick.dataset.image === reference.dataset.image) {
        note = "Bit-identical to the reference: the same image.";
      }
      const src = file || reference.dataset.image;
      if (img.getAttribute("src") !== src) img.setAttribute("src", src);
      img.dataset.backend = backend;
      img.dataset.layer = state.layer;
      img.dataset.zoom = String(state.zoom);
      if (derived) img.dataset.derived = derived; else delete img.dataset.derived;
      img.alt = viewer.dataset.scene + " " + state.layer + " of " + backend;
      img.width = width * state.zoom;
      img.height = height * state.zoom;
      viewer.dataset.layer = state.layer;
      picks.forEach((p, i) => p.setAttribute("aria-pressed", String(i === state.pick)));
      layerButtons.forEach((b) => b.setAttribute("aria-pressed", String(b.dataset.layer === state.layer)));
      const template = templates.find((t) => t.dataset.backend === backend);
      if (template) stats.innerHTML = template.innerHTML;
      stats.dataset.backend = backend;
      caption.textContent = note;
      zoomLevel.textContent = state.zoom + "x";
    }

    function pickAt(i) {
      state.pick = (i + picks.length) % picks.length;
      show();
    }

    function zoomBy(step) {
      const i = ZOOMS.indexOf(state.zoom);
      const next = ZOOMS[Math.min(ZOOMS.length - 1, Math.max(0, (i < 0 ? 0 : i) + step))];
      state.zoom = next;
      show();
    }

    picks.forEach((p, i) => p.addEventListener("click", () => { pickAt(i); viewer.focus({ preventScroll: true }); }));
    layerButtons.forEach((b) => b.addEventListener("click", () => {
      state.layer = b.dataset.layer;
      show();
      viewer.focus({ preventScroll: true });
    }));
    viewer.querySelector(".viewer-zoom-in").addEventListener("click", () => zoomBy(1));
    viewer.querySelector(".viewer-zoom-out").addEventListener("click", () => zoomBy(-1));

    viewer.addEventListener("keydown", (e) => {
      if (e.altKey || e.ctrlKey || e.metaKey) return;
      const k = e.key;
      if (k === "ArrowRight" || k === "j") pickAt(state.pick + 1);
      else if (k === "ArrowLeft" || k === "k") pickAt(state.pick - 1);
      else if (k >= "1" && k <= "9" && k.length === 1) {
        const i = Number(k) - 1;
        if (i < picks.length) pickAt(i);
      } else if (k === "r") pickAt(0);
      else if (k === "i") { state.layer = "image"; show(); }
      else if (k === "d") { state.layer = "ids"; show(); }
      else if (k === "f") { state.layer = "flip"; show(); }
      else if (k === "v" && layerButtons.some((b) => b.dataset.layer === "visits")) { state.layer = "visits"; show(); }
      else if (k === "+" || k === "=") zoomBy(1);
      else if (k === "-" || k === "_") zoomBy(-1);
      else return;
      e.preventDefault();
    });

    img.addEventListener("mousemove", (e) => {
      const x = Math.floor(e.offsetX / state.zoom);
      const y = Math.floor(e.offsetY / state.zoom);
      if (x >= 0 && y >= 0 && x < width && y < height) {
        pixel.textContent = "pixel: x " + x + ", y " + y + " (of " + width + " x " + height + ")";
      }
    });
    show();
  }

  document.querySelectorAll("section.viewer").forEach(setUpViewer);

  // ---- Sortable tables ------------------------------------------------------------------
  // A cell's value: its first number, scaled by a unit right after it (so "3.1 MiB" sorts
  // above "900 KiB"), Infinity for "inf"; null for "-" and text without a number.
  const UNITS = { ns: 1e-9, "µs": 1e-6, us: 1e-6, ms: 1e-3, s: 1, B: 1, KiB: 1024, MiB: 1048576, GiB: 1073741824, "%": 1 };
  // The number is taken whole (never "2.6" of "2.65x"); a unit only when a word ends there
  // ("1 s", not the "s" of "spp").
  const NUMBER = /^[^0-9+\-.]*?([-+]?(?:\d+\.?\d*|\.\d+)(?:e[-+]?\d+)?)(?![\d.])(?:\s*(ns|µs|us|ms|s|B|KiB|MiB|GiB|%)(?![A-Za-z]))?/;

  function cellValue(text) {
    // Thousands separators out: "6,320" is 6320.
    const t = text.replace(/†/g, "").replace(/(\d),(?=\d{3}(?!\d))/g, "$1").trim();
    if (t === "" || t === "-") return null;
    if (/^inf\b/i.test(t)) return Infinity;
    const m = NUMBER.exec(t);
    if (!m) return null;
    const unit = m[2] ? UNITS[m[2]] || 1 : 1;
    return Number(m[1]) * unit;
  }

  function sortTable(table, column, th) {
    const body = table.tBodies[0];
    if (!body) return;
    const rows = Array.from(body.rows);
    const texts = rows.map((r) => (r.cells[column] ? r.cells[column].textContent : ""));
    const values = texts.map(cellValue);
    const numeric = values.filter((v) => v !== null).length >= Math.max(1, texts.filter((t) => t.trim() !== "" && t.trim() !== "-").length / 2);
    const ascending = th.getAttribute("aria-sort") !== "ascending";
    const order = rows.map((row, i) => i);
    order.sort((a, b) => {
      let c;
      if (numeric) {
        const va = values[a];
        const vb = values[b];
        if (va === null && vb === null) c = 0;
        else if (va === null) return 1; // "-" and text last, whatever the direction
        else if (vb === null) return -1;
        else c = va - vb;
      } else {
        const ta = texts[a].trim();
        const tb = texts[b].trim();
        if ((ta === "" || ta === "-") !== (tb === "" || tb === "-")) return ta === "" || ta === "-" ? 1 : -1;
        c = ta.localeCompare(tb, undefined, { numeric: true });
      }
      if (c === 0) return a - b; // stable
      return ascending ? c : -c;
    });
    order.forEach((i) => body.appendChild(rows[i]));
    table.querySelectorAll("th").forEach((h) => h.removeAttribute("aria-sort"));
    th.setAttribute("aria-sort", ascending ? "ascending" : "descending");
  }

  document.querySelectorAll("table.sortable").forEach((table) => {
    const head = table.tHead;
    if (!head) return;
    Array.from(head.rows[0].cells).forEach((th, column) => {
      th.addEventListener("click", () => sortTable(table, column, th));
      th.addEventListener("keydown", (e) => {
        if (e.key === "Enter" || e.key === " ") { e.preventDefault(); sortTable(table, column, th); }
      });
    });
  });

  // ---- The table of contents follows the reading position --------------------------------
  const links = new Map();
  document.querySelectorAll("#toc a[href^='#']").forEach((a) => links.set(a.getAttribute("href").slice(1), a));
  if ("IntersectionObserver" in window && links.size > 0) {
    let current = null;
    const observer = new IntersectionObserver((entries) => {
      entries.forEach((entry) => {
        if (!entry.isIntersecting) return;
        const a = links.get(entry.target.id);
        if (!a) return;
        if (current) current.classList.remove("current");
        a.classList.add("current");
        current = a;
      });
    }, { rootMargin: "0px 0px -70% 0px" });
    document.querySelectorAll("main h2[id], main h3[id]").forEach((h) => observer.observe(h));
  }
})();
