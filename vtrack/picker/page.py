"""The page of ``vtrack select``: one self-contained HTML document (no external files, works
offline and through an SSH port forward). It shows a frame, lets the user drag a box with the
mouse (or type it), step frames, and confirm; it talks to :mod:`.server` with ``fetch``."""

PAGE = """<!doctype html>
<html lang="en"><head><meta charset="utf-8">
<title>vtrack select</title>
<style>
 body { font: 14px system-ui, sans-serif; margin: 12px; background: #f4f4f4; color: #222; }
 #bar { display: flex; gap: 8px; align-items: center; flex-wrap: wrap; margin-bottom: 8px; }
 #stage { position: relative; display: inline-block; cursor: crosshair; user-select: none;
          touch-action: none; line-height: 0; }
 #frame { max-width: calc(100vw - 30px); max-height: calc(100vh - 110px); display: block; }
 #box { position: absolute; border: 2px solid #ff2d55; background: rgba(255, 45, 85, .15);
        box-sizing: border-box; display: none; pointer-events: none; }
 #init { font-family: monospace; width: 14em; }
 #status { color: #555; }
 button { padding: 4px 10px; }
 #confirm { font-weight: bold; }
</style></head>
<body>
<div id="bar">
 <button id="prev" title="previous frame (left arrow)">&#9664; prev</button>
 <span id="where">frame 0</span>
 <button id="next" title="next frame (right arrow)">next &#9654;</button>
 <label>box x,y,w,h <input id="init" placeholder="drag on the image"></label>
 <button id="confirm" disabled>Use this box</button>
 <span id="status">Drag a box around the target.</span>
</div>
<div id="stage"><img id="frame" alt="frame" draggable="false"><div id="box"></div></div>
<script>
"use strict";
const $ = (id) => document.getElementById(id);
const img = $("frame"), boxDiv = $("box"), field = $("init"), stage = $("stage");
let info = null, index = 0, box = null, start = null;

function scale() { return img.naturalWidth / img.getBoundingClientRect().width; }
function toImage(ev) {
  const r = img.getBoundingClientRect(), s = scale();
  const x = Math.min(Math.max(ev.clientX - r.left, 0), r.width);
  const y = Math.min(Math.max(ev.clientY - r.top, 0), r.height);
  return [x * s, y * s];
}
function show() {
  if (!box || box[2] < 1 || box[3] < 1) { boxDiv.style.display = "none";
    $("confirm").disabled = true; return; }
  const s = scale();
  boxDiv.style.left = box[0] / s + "px"; boxDiv.style.top = box[1] / s + "px";
  boxDiv.style.width = box[2] / s + "px"; boxDiv.style.height = box[3] / s + "px";
  boxDiv.style.display = "block"; $("confirm").disabled = false;
}
// a request vtrack select did not answer: it stopped (Ctrl-C, or a box confirmed on another
// page); the page says so instead of doing nothing, and waits no further
function ask(url, options) {
  return fetch(url, options).catch(() => {
    $("status").textContent = "vtrack select is not running any more (cancelled, or a box " +
      "was confirmed on another page): nothing is taken from this page; run it again";
    ["prev", "next", "confirm"].forEach((id) => { $(id).disabled = true; });
    return new Promise(() => {});
  });
}
function hint() {
  $("status").textContent = box ? "Confirm with 'Use this box'." :
                            "Drag a box around the target.";
}
// the box as shown and sent: from a drag, its corners rounded to whole pixels (so it stays
// within the frame); typed or saved, as given
function setBox(b, typed) {
  box = b && b[2] >= 1 && b[3] >= 1 ? b : null;
  if (!typed) field.value = b ? b.join(",") : "";
  show();
}
function dragged(p, q) {
  const x0 = Math.round(Math.min(p[0], q[0])), y0 = Math.round(Math.min(p[1], q[1]));
  return [x0, y0, Math.round(Math.max(p[0], q[0])) - x0, Math.round(Math.max(p[1], q[1])) - y0];
}
// step: +1 or -1 when stepping, to pass over numbers the input has no picture for
function load(i, step) {
  ask("frame/" + i).then((r) => {
    if (r.ok) return r.blob();
    return r.json().catch(() => ({})).then((e) => {
      if (Number.isInteger(e.frames)) { info.frames = e.frames; where(); }
      const over = step > 0 ? e.next : step < 0 ? e.previous : null;
      if (Number.isInteger(over)) load(over, step);
      else $("status").textContent = e.error || "no frame " + i;
      return null;
    });
  }).then((blob) => {
    if (!blob) return;
    index = i; img.src = URL.createObjectURL(blob); hint(); where();
  });
}
function where() {
  const last = info.frames == null ? "?" : info.frames - 1;
  $("where").textContent = "frame " + index + " of 0.." + last;
}
stage.addEventListener("pointerdown", (ev) => {
  ev.preventDefault(); stage.setPointerCapture(ev.pointerId); start = toImage(ev);
  setBox(null);
});
stage.addEventListener("pointermove", (ev) => {
  if (start) setBox(dragged(start, toImage(ev)));
});
stage.addEventListener("pointerup", () => { start = null; hint(); });
// what --init and the sidecar take: x,y,w,h or x y w h; anything else leaves no box to confirm
const NUMBER = /^[+-]?(\\d+\\.?\\d*|\\.\\d+)(e[+-]?\\d+)?$/i;
field.addEventListener("input", () => {
  const text = field.value.trim(), parts = text.split(/\\s*,\\s*|\\s+/);
  const ok = parts.length === 4 && parts.every((p) => NUMBER.test(p));
  setBox(ok ? parts.map(Number) : null, true);
  if (box || text === "") hint();
  else $("status").textContent = ok ? "The box's width and height must be at least 1." :
    "Type the box as x,y,w,h or x y w h (four numbers), or drag it on the image.";
});
img.addEventListener("load", show);
window.addEventListener("resize", show);
$("prev").onclick = () => { if (index > 0) load(index - 1, -1); };
$("next").onclick = () => load(index + 1, 1);
document.addEventListener("keydown", (ev) => {
  if (ev.target === field) return;
  if (ev.key === "ArrowLeft") $("prev").onclick();
  if (ev.key === "ArrowRight") $("next").onclick();
});
$("confirm").onclick = () => {
  ask("select", { method: "POST", headers: { "Content-Type": "application/json" },
                    body: JSON.stringify({ box: box, frame: index }) })
    .then((r) => r.json()).then((res) => {
      if (res.error) { $("status").textContent = res.error; return; }
      const saved = res.sidecar ? " (saved in " + res.sidecar + ")" :
        index !== 0 ? " --start " + index + " (not saved: the sidecar holds frame 0's box)" :
        " (this input has no sidecar file: give it as --init)";
      $("status").textContent = "Done: --init " + res.init + saved + ". You can close this page.";
      document.body.dataset.done = res.init;
      ["prev", "next", "confirm"].forEach((id) => { $(id).disabled = true; });
    });
};
ask("info").then((r) => r.json()).then((i) => {
  info = i; document.title = "vtrack select: " + i.name;
  // the sidecar's box is frame 0's: offered there only, not as a later frame's box
  if (i.box && i.frame === 0) setBox(i.box);
  load(i.frame);
});
</script>
</body></html>
"""
