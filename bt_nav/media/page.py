"""The browser view's one page (HTML + JavaScript, no external assets: it works offline).

Kept as a Python string so it installs with the package without package-data rules. The page reads
``/world`` once, then follows ``/stream`` (server-sent events); in bag mode a slider and a play button
post to ``/control``. After each drawing it writes the robot's pixel position to ``#robot``'s
``data-px``/``data-py`` (the browser test reads them).
"""

PAGE = """<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>bt_nav view</title>
<style>
 body { font-family: sans-serif; margin: 0; display: grid; grid-template-columns: 640px 1fr;
        grid-template-rows: auto 1fr auto; height: 100vh; background: #f6f6f2; }
 header { grid-column: 1 / 3; padding: 6px 10px; background: #20242a; color: #eee; }
 #map { background: #fafaf7; border-right: 1px solid #bbb; }
 #tree { font-family: monospace; font-size: 13px; overflow: auto; padding: 6px; }
 .row { white-space: pre; } .active { background: #fff3be; }
 .SUCCESS { color: #1e8c32; } .FAILURE { color: #c82828; } .RUNNING { color: #1e5adc; font-weight: bold; }
 .INVALID { color: #999; }
 #console { grid-column: 1 / 3; background: #16181c; color: #d2d7dc; font-family: monospace; font-size: 12px;
            height: 150px; overflow: auto; padding: 4px 8px; white-space: pre; }
 #controls { display: none; } #controls.bag { display: inline; }
</style></head>
<body>
<header><b>bt_nav</b> <span id="mode"></span> &nbsp; t = <span id="time">-</span> s &nbsp;
 cmd <span id="cmd">-</span> <span id="robot" data-px="" data-py=""></span>
 <span id="controls"><button id="play">play</button>
 <input id="slider" type="range" min="0" max="1" step="0.05" value="0" style="width: 420px"></span>
 <span id="status"></span></header>
<canvas id="map" width="640" height="560"></canvas>
<div id="tree">waiting for the executive's tree...</div>
<div id="console"></div>
<script>
"use strict";
let world = null, view = null, last = null;
const canvas = document.getElementById("map"), ctx = canvas.getContext("2d");
function fit(b) {
  const m = 14, s = Math.min((canvas.width - 2 * m) / (b[2] - b[0]), (canvas.height - 2 * m) / (b[3] - b[1]));
  const ox = (canvas.width - s * (b[2] - b[0])) / 2, oy = (canvas.height + s * (b[3] - b[1])) / 2;
  return { px: (x, y) => [ox + (x - b[0]) * s, oy - (y - b[1]) * s], s: s };
}
function drawWorld() {
  ctx.fillStyle = "#fafaf7"; ctx.fillRect(0, 0, canvas.width, canvas.height);
  ctx.strokeStyle = "#464646"; ctx.lineWidth = 3; ctx.fillStyle = "#6e6e6e";
  for (const [x1, y1, x2, y2] of world.segments) {
    const a = view.px(x1, y1), b = view.px(x2, y2);
    ctx.beginPath(); ctx.moveTo(a[0], a[1]); ctx.lineTo(b[0], b[1]); ctx.stroke();
  }
  for (const [cx, cy, r] of world.circles) {
    const c = view.px(cx, cy); ctx.beginPath(); ctx.arc(c[0], c[1], r * view.s, 0, 7); ctx.fill();
  }
}
function draw(st) {
  last = st;
  drawWorld();
  if (st.trail.length) {
    const s0 = view.px(st.trail[0][0], st.trail[0][1]);
    ctx.strokeStyle = "#1f77b4"; ctx.lineWidth = 1.5; ctx.setLineDash([6, 4]);
    if (st.circle) { ctx.beginPath(); ctx.arc(s0[0], s0[1], 1.5 * view.s, 0, 7); ctx.stroke(); }
    ctx.setLineDash([]);
    ctx.strokeStyle = "#2ca02c"; ctx.lineWidth = 3; ctx.beginPath();
    st.trail.forEach(([x, y], i) => { const p = view.px(x, y); i ? ctx.lineTo(p[0], p[1]) : ctx.moveTo(p[0], p[1]); });
    ctx.stroke();
  }
  ctx.fillStyle = "#f0aad7"; ctx.strokeStyle = "#c83c96"; ctx.lineWidth = 2;
  for (const [x, y, r] of (st.walkers || [])) {
    const c = view.px(x, y); ctx.beginPath(); ctx.arc(c[0], c[1], r * view.s, 0, 7); ctx.fill(); ctx.stroke();
  }
  ctx.fillStyle = "#e62828";
  for (const [x, y] of st.scan) { const p = view.px(x, y); ctx.fillRect(p[0] - 1.5, p[1] - 1.5, 3, 3); }
  if (st.pose) {
    const [x, y, yaw] = st.pose, p = view.px(x, y), h = view.px(x + 0.23 * Math.cos(yaw), y + 0.23 * Math.sin(yaw));
    ctx.fillStyle = "#282828"; ctx.beginPath(); ctx.arc(p[0], p[1], Math.max(4, 0.105 * view.s), 0, 7); ctx.fill();
    ctx.strokeStyle = "#ffc800"; ctx.lineWidth = 3; ctx.beginPath(); ctx.moveTo(p[0], p[1]); ctx.lineTo(h[0], h[1]);
    ctx.stroke();
    const r = document.getElementById("robot"); r.dataset.px = p[0].toFixed(1); r.dataset.py = p[1].toFixed(1);
  }
  document.getElementById("time").textContent = st.t.toFixed(2);
  document.getElementById("cmd").textContent = st.cmd.map(v => v.toFixed(2)).join(" m/s, ") + " rad/s";
  const tree = document.getElementById("tree");
  if (st.tree.length) {
    tree.replaceChildren(...st.tree.map(r => {
      const d = document.createElement("div");
      d.className = "row " + r.status + (r.active ? " active" : "");
      d.textContent = "  ".repeat(r.depth) + r.name + " [" + r.status + "]" + (r.feedback ? " - " + r.feedback : "");
      return d;
    }));
  }
  const con = document.getElementById("console");
  con.textContent = st.events.join("\\n"); con.scrollTop = con.scrollHeight;
  if (st.mode === "bag") {
    const sl = document.getElementById("slider");
    sl.min = st.start; sl.max = st.end; if (document.activeElement !== sl) sl.value = st.t;
    document.getElementById("play").textContent = st.playing ? "pause" : "play";
  }
}
function control(msg) {
  fetch("/control", { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(msg) });
}
async function main() {
  world = await (await fetch("/world")).json();
  view = fit(world.bounds);
  document.getElementById("mode").textContent = world.mode === "bag" ? "(bag playback)" : "(live)";
  if (world.mode === "bag") {
    document.getElementById("controls").className = "bag";
    document.getElementById("slider").addEventListener("input", e => control({ t: Number(e.target.value) }));
    document.getElementById("play").addEventListener("click", () => control({ play: !(last && last.playing) }));
  }
  drawWorld();
  const es = new EventSource("/stream");
  es.onmessage = e => draw(JSON.parse(e.data));
  es.onerror = () => { document.getElementById("status").textContent = " (reconnecting...)"; };
  es.onopen = () => { document.getElementById("status").textContent = ""; };
}
main();
</script></body></html>
"""
