"""The report's 3D viewer: plain JavaScript on a 2D canvas, embedded once in each page.

No library and no WebGL, so that a report opens offline in any browser and in headless ones:
an orthographic projection of the rotated scene, the mesh's triangles (and a hand's, as it
settled, in a warmer tint) drawn back to front (painter's algorithm) with flat shading, and the
points and arrows sorted into the same depth order. Drag rotates, the wheel zooms, a double click resets the view. The page's data
(:mod:`ogcp.benchmarks.report.scene`) is read from the ``<script id="ogcp-data">`` JSON block; the
canvas gets ``data-drawn="1"`` after its first frame (what the headless-browser test checks).
"""

from __future__ import annotations

VIEWER_JS = r"""
(function () {
  "use strict";
  var DATA = JSON.parse(document.getElementById("ogcp-data").textContent);
  var canvas = document.getElementById("ogcp-canvas");
  var info = document.getElementById("ogcp-info");
  var select = document.getElementById("ogcp-select");
  var ctx = canvas.getContext("2d");
  var state = { grasp: 0, rot: [1, 0, 0, 0, 1, 0, 0, 0, 1], zoom: 1, drag: null };

  function mul(a, b) {
    var r = [];
    for (var i = 0; i < 3; i++) {
      for (var j = 0; j < 3; j++) {
        r.push(a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j]);
      }
    }
    return r;
  }
  function rotX(t) { var c = Math.cos(t), s = Math.sin(t); return [1, 0, 0, 0, c, -s, 0, s, c]; }
  function rotY(t) { var c = Math.cos(t), s = Math.sin(t); return [c, 0, s, 0, 1, 0, -s, 0, c]; }
  function resetView() { state.rot = mul(rotX(0.45), rotY(-0.6)); state.zoom = 1; }

  function fmt(v, digits) { return v === null || v === undefined ? "-" : Number(v).toPrecision(digits || 3); }
  function text(tag, content) { var e = document.createElement(tag); e.textContent = content; return e; }

  // Bounds of a scene: its mesh if it has one, else its points.
  function bounds(g) {
    var set = g.set >= 0 ? DATA.sets[g.set] : null;
    var pts = set ? DATA.meshes[set.mesh].vertices : g.points;
    if (!pts.length) { return { c: [0, 0, 0], r: 0.1 }; }
    var lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (var i = 0; i < pts.length; i += 3) {
      for (var k = 0; k < 3; k++) { lo[k] = Math.min(lo[k], pts[i + k]); hi[k] = Math.max(hi[k], pts[i + k]); }
    }
    var c = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2];
    var r = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) / 2 || 0.1;
    return { c: c, r: r };
  }

  function draw() {
    var g = DATA.grasps[state.grasp];
    var w = canvas.width, h = canvas.height, R = state.rot;
    ctx.fillStyle = "#ffffff";
    ctx.fillRect(0, 0, w, h);
    if (!g) { canvas.setAttribute("data-drawn", "1"); return; }
    var b = bounds(g), scale = state.zoom * 0.42 * Math.min(w, h) / b.r;
    // View space: x right, y up, z towards the viewer; screen y grows downwards.
    function project(x, y, z) {
      var px = x - b.c[0], py = y - b.c[1], pz = z - b.c[2];
      var vx = R[0] * px + R[1] * py + R[2] * pz, vy = R[3] * px + R[4] * py + R[5] * pz;
      var vz = R[6] * px + R[7] * py + R[8] * pz;
      return [w / 2 + scale * vx, h / 2 - scale * vy, scale * vz];
    }
    var items = [], i, set = g.set >= 0 ? DATA.sets[g.set] : null;
    // Depth bias of points and arrows [px]: about one triangle edge, the sorting's error.
    var bias = scale * (set ? 0.6 * (DATA.meshes[set.mesh].edge || 0.1 * b.r) : 0);
    // A surface's triangles, flat shaded in its tint (r, g, b factors of the light).
    function surface(V, F, tint) {
      var P = [], k;
      for (k = 0; k < V.length; k += 3) { P.push(project(V[k], V[k + 1], V[k + 2])); }
      for (k = 0; k < F.length; k += 3) {
        var a = P[F[k]], c = P[F[k + 1]], d = P[F[k + 2]];
        // Flat shading by the face normal's view-space z (two-sided: the mesh may be open);
        // screen coordinates are view space scaled (y flipped, which |nz| ignores).
        var ux = c[0] - a[0], uy = c[1] - a[1], uz = c[2] - a[2];
        var wx = d[0] - a[0], wy = d[1] - a[1], wz = d[2] - a[2];
        var nx = uy * wz - uz * wy, ny = uz * wx - ux * wz, nz = ux * wy - uy * wx;
        var len = Math.sqrt(nx * nx + ny * ny + nz * nz) || 1;
        // A light from the upper left of the eye (screen y points down), so that the sides differ.
        var shade = 0.3 + 0.7 * Math.abs((-0.35 * nx - 0.45 * ny + 0.82 * nz) / len);
        items.push({ z: (a[2] + c[2] + d[2]) / 3, kind: 0, p: [a, c, d], shade: shade, tint: tint });
      }
    }
    if (set) {
      var mesh = DATA.meshes[set.mesh];
      surface(mesh.vertices, mesh.faces, [0.62, 0.7, 0.82]);
      var S = set.points;
      for (i = 0; i < S.length; i += 3) {
        // Biased towards the eye: points lie on the surface, not behind it.
        var q = project(S[i], S[i + 1], S[i + 2]);
        items.push({ z: q[2] + bias, kind: 1, p: q });
      }
    }
    // The hand as it settled (a grasp tested with one), warmer than the object.
    if (g.hand) { surface(g.hand.vertices, g.hand.faces, [0.85, 0.74, 0.62]); }
    var color = !g.simulated ? "#1f6fd1" : (g.valid ? "#1a9b3c" : "#d12a1f");
    var L = 0.35 * b.r;
    for (i = 0; i < g.points.length; i += 3) {
      var x = g.points[i], y = g.points[i + 1], z = g.points[i + 2];
      var n = [g.normals[i] || 0, g.normals[i + 1] || 0, g.normals[i + 2] || 0];
      var tip = project(x, y, z), tail = project(x - L * n[0], y - L * n[1], z - L * n[2]);
      // The inward normal drawn as a finger pressing on the contact, from outside the object.
      items.push({ z: Math.max(tip[2], tail[2]) + bias, kind: 2, p: [tail, tip], color: color });
      items.push({ z: tip[2] + 1.2 * bias, kind: 3, p: tip, color: color });
    }
    if (g.weakest && g.center) {
      var f = g.weakest.force, o = g.center;
      var from = project(o[0], o[1], o[2]), to = project(o[0] + 1.3 * b.r * f[0], o[1] + 1.3 * b.r * f[1], o[2] + 1.3 * b.r * f[2]);
      items.push({ z: Math.max(from[2], to[2]), kind: 2, p: [from, to], color: "#e08a00" });
    }
    items.sort(function (u, v) { return u.z - v.z; });
    for (i = 0; i < items.length; i++) {
      var it = items[i];
      if (it.kind === 0) {
        var s = Math.round(255 * it.shade), t = it.tint;
        ctx.fillStyle = "rgb(" + Math.round(s * t[0]) + "," + Math.round(s * t[1]) + "," + Math.round(s * t[2]) + ")";
        ctx.strokeStyle = ctx.fillStyle;
        ctx.lineWidth = 0.5;
        ctx.beginPath();
        ctx.moveTo(it.p[0][0], it.p[0][1]); ctx.lineTo(it.p[1][0], it.p[1][1]); ctx.lineTo(it.p[2][0], it.p[2][1]);
        ctx.closePath(); ctx.fill(); ctx.stroke();
      } else if (it.kind === 1) {
        ctx.fillStyle = "#333333";
        ctx.fillRect(it.p[0] - 1.5, it.p[1] - 1.5, 3, 3);
      } else if (it.kind === 2) {
        arrow(it.p[0], it.p[1], it.color);
      } else {
        ctx.fillStyle = it.color;
        ctx.beginPath(); ctx.arc(it.p[0], it.p[1], 6, 0, 2 * Math.PI); ctx.fill();
        ctx.strokeStyle = "#000000"; ctx.lineWidth = 1; ctx.stroke();
      }
    }
    canvas.setAttribute("data-drawn", "1");
  }

  function arrow(a, b, color) {
    var dx = b[0] - a[0], dy = b[1] - a[1], len = Math.sqrt(dx * dx + dy * dy);
    ctx.strokeStyle = color; ctx.fillStyle = color; ctx.lineWidth = 3;
    ctx.beginPath(); ctx.moveTo(a[0], a[1]); ctx.lineTo(b[0], b[1]); ctx.stroke();
    if (len < 1) { return; }
    var ux = dx / len, uy = dy / len, head = Math.min(12, 0.4 * len);
    ctx.beginPath();
    ctx.moveTo(b[0], b[1]);
    ctx.lineTo(b[0] - head * ux - 0.5 * head * uy, b[1] - head * uy + 0.5 * head * ux);
    ctx.lineTo(b[0] - head * ux + 0.5 * head * uy, b[1] - head * uy - 0.5 * head * ux);
    ctx.closePath(); ctx.fill();
  }

  function describe() {
    var g = DATA.grasps[state.grasp];
    info.textContent = "";
    if (!g) { info.appendChild(text("p", "No grasp to show.")); return; }
    info.appendChild(text("h3", g.title));
    var lines = ["contacts: " + (g.grasp.length ? g.grasp.join(", ") : "-"), "Q1: " + fmt(g.q1)];
    if (g.simulated) {
      lines.push("simulated: " + (g.error ? "error: " + g.error : (g.valid ? "valid" : "invalid")));
      lines.push("min measured resistance: " + fmt(g.measured_min) + " N");
      if (g.weakest) { lines.push("weakest direction (orange arrow): " + g.weakest.label); }
      if (g.hand) { lines.push("hand: drawn as it settled (its collision geometry)"); }
      for (var i = 0; i < (g.reasons || []).length; i++) { lines.push("invalid: " + g.reasons[i]); }
    } else {
      lines.push("not simulated");
    }
    if (g.set < 0) { lines.push("(object mesh not available)"); }
    for (var j = 0; j < lines.length; j++) { info.appendChild(text("div", lines[j])); }
  }

  function show(index) {
    state.grasp = index;
    if (select) { select.value = String(index); }
    var rows = document.querySelectorAll("tr[data-grasp]");
    for (var i = 0; i < rows.length; i++) {
      rows[i].className = rows[i].getAttribute("data-grasp") === String(index) ? "current" : "";
    }
    describe();
    draw();
  }

  if (select) {
    for (var i = 0; i < DATA.grasps.length; i++) {
      var option = text("option", DATA.grasps[i].title);
      option.value = String(i);
      select.appendChild(option);
    }
    select.addEventListener("change", function () { show(Number(select.value)); });
  }
  var rows = document.querySelectorAll("tr[data-grasp]");
  for (var r = 0; r < rows.length; r++) {
    rows[r].addEventListener("click", function (event) {
      show(Number(event.currentTarget.getAttribute("data-grasp")));
      canvas.scrollIntoView({ block: "nearest" });
    });
  }
  canvas.addEventListener("mousedown", function (e) { state.drag = [e.clientX, e.clientY]; });
  window.addEventListener("mouseup", function () { state.drag = null; });
  window.addEventListener("mousemove", function (e) {
    if (!state.drag) { return; }
    var dx = e.clientX - state.drag[0], dy = e.clientY - state.drag[1];
    state.drag = [e.clientX, e.clientY];
    // Rotations about the screen's axes, applied after the current one: the object follows the mouse.
    state.rot = mul(rotX(dy * 0.01), mul(rotY(dx * 0.01), state.rot));
    draw();
  });
  canvas.addEventListener("wheel", function (e) {
    e.preventDefault();
    state.zoom = Math.min(50, Math.max(0.05, state.zoom * Math.exp(-e.deltaY * 0.001)));
    draw();
  }, { passive: false });
  canvas.addEventListener("dblclick", function () { resetView(); draw(); });
  resetView();
  show(0);
})();
"""
