// The report's page: its data (serialized by hyst) drawn with uPlot and three.js.
(function () {
  "use strict";
  const D = JSON.parse(document.getElementById("report-data").textContent);
  const fmt = (v, d) => (v === null || v === undefined ? "—" : v.toFixed(d));
  document.getElementById("summary").textContent = D.summary.join(" ");

  // --- the stabilization diagram ---------------------------------------------------------
  const GROUPS = [
    ["stable", "stable (frequency, damping, shape)", "#1f77b4", 6],
    ["frequency", "stable in frequency (and damping)", "#2ca02c", 5],
    ["real", "stable real pole", "#9467bd", 6],
    ["rejected", "rejected", "#bbbbbb", 3],
  ];
  function diagram(d) {
    const el = document.getElementById("diagram");
    // uPlot aligns every series on one x: the union of the spectrum's lines and the poles'
    // frequencies, each series null where it has no point.
    const xs = Array.from(new Set(d.spectrum_hz.concat(d.poles.map((p) => p.f)))).sort((a, b) => a - b);
    const at = new Map(xs.map((x, i) => [x, i]));
    const empty = () => new Array(xs.length).fill(null);
    const data = [xs];
    const series = [{ label: "frequency (Hz)", value: (u, v) => fmt(v, 4) }];
    d.singular_values.forEach((sv, k) => {
      const col = empty();
      d.spectrum_hz.forEach((f, i) => { if (sv[i] > 0) col[at.get(f)] = sv[i]; });
      data.push(col);
      series.push({ label: "s" + (k + 1), scale: "psd", spanGaps: true, width: 1,
                    stroke: ["#d62728", "#ff9896", "#f7b6d2"][k] || "#ccc", points: { show: false } });
    });
    GROUPS.forEach(([g, label, color, size]) => {
      const col = empty();
      d.poles.forEach((p) => { if (p.group === g) col[at.get(p.f)] = p.order; });
      data.push(col);
      series.push({ label: label, scale: "order", paths: () => null,
                    points: { show: true, size: size, fill: color, stroke: color } });
    });
    const tip = document.getElementById("tip");
    const u = new uPlot({
      width: Math.min(960, el.clientWidth || 960), height: 420,
      scales: { x: { time: false }, psd: { distr: 3 }, order: {} },
      axes: [
        { label: "frequency (Hz)" },
        { scale: "order", label: "model order" },
        { scale: "psd", side: 1, label: "singular values", grid: { show: false },
          values: (u, vals) => vals.map((v) => (v === null || v === undefined ? "" : v.toExponential(0))) },
      ],
      series: series,
      cursor: { points: { show: false } },
      hooks: { setCursor: [(u) => hover(u, d, tip)] },
    }, data, el);
    el.dataset.poles = String(d.poles.length);
    el.dataset.ready = "1";
    return u;
  }
  function hover(u, d, tip) {
    const { left, top } = u.cursor;
    if (left === undefined || left < 0) { tip.style.display = "none"; return; }
    let best = null, bestDist = 12;
    for (const p of d.poles) {
      const dx = u.valToPos(p.f, "x") - left, dy = u.valToPos(p.order, "order") - top;
      const dist = Math.hypot(dx, dy);
      if (dist < bestDist) { bestDist = dist; best = p; }
    }
    if (!best) { tip.style.display = "none"; return; }
    tip.innerHTML = `<b>${best.f.toFixed(4)} Hz</b>, damping ratio ${(100 * best.zeta).toFixed(3)} %, order ${best.order}<br>${best.reason}`;
    const box = u.over.getBoundingClientRect(), host = tip.parentElement.getBoundingClientRect();
    tip.style.left = (box.left - host.left + left + 14) + "px";
    tip.style.top = (box.top - host.top + top + 14) + "px";
    tip.style.display = "block";
  }
  if (D.diagram) { diagram(D.diagram); } else if (D.setup_diagrams.length) {
    // Merged setups: each setup's diagram, one at a time, chosen by name.
    const pickDiagram = document.getElementById("diagram-pick");
    D.setup_diagrams.forEach((s, i) => {
      const o = document.createElement("option");
      o.value = String(i);
      o.textContent = s.name;
      pickDiagram.appendChild(o);
    });
    document.getElementById("diagram-pick-label").hidden = false;
    let shown = diagram(D.setup_diagrams[0].diagram);
    pickDiagram.addEventListener("change", () => {
      shown.destroy();
      shown = diagram(D.setup_diagrams[Number(pickDiagram.value)].diagram);
    });
  } else {
    document.getElementById("diagram-section").style.display = "none";
  }

  // --- a campaign: each mode against time -----------------------------------------------
  function track(T) {
    const host = document.getElementById("track");
    let charts = 0, points = 0;
    T.modes.forEach((m) => {
      [["frequency_hz", "frequency_se_hz", "frequency (Hz)", 1], ["damping_ratio", "damping_se", "damping ratio (%)", 100]].forEach(([key, se, label, k]) => {
        const div = document.createElement("div");
        div.className = "series";
        host.appendChild(div);
        const v = m[key].map((x) => k * x);
        const lo = m[key].map((x, i) => (m[se][i] === null ? null : k * (x - m[se][i])));
        const hi = m[key].map((x, i) => (m[se][i] === null ? null : k * (x + m[se][i])));
        // Alarms as points on the series at the records nearest their times.
        const alarm = v.map(() => null);
        m.alarm_days.forEach((t) => {
          let best = 0;
          m.days.forEach((d, i) => { if (Math.abs(d - t) < Math.abs(m.days[best] - t)) best = i; });
          alarm[best] = v[best];
        });
        const end = T.training_end_days;
        new uPlot({
          title: `${m.label}: ${label}`, width: Math.min(960, host.clientWidth || 960), height: 220,
          scales: { x: { time: false } },
          axes: [{ label: "time (days)" }, { label: label }],
          series: [{ label: "days", value: (u, x) => fmt(x, 3) },
            { label: "+1 se", stroke: "#9ecae1", points: { show: false } },
            { label: "-1 se", stroke: "#9ecae1", points: { show: false } },
            { label: label, stroke: "#1f77b4", width: 1, points: { show: true, size: 3 } },
            { label: "alarm", paths: () => null, points: { show: true, size: 9, fill: "#d62728", stroke: "#d62728" } }],
          bands: [{ series: [1, 2], fill: "rgba(31,119,180,0.15)" }],
          hooks: { draw: [(u) => {
            if (end === null || end === undefined) return;
            const x = u.valToPos(end, "x", true), ctx = u.ctx;
            ctx.save(); ctx.setLineDash([6, 4]); ctx.strokeStyle = "#555";
            ctx.beginPath(); ctx.moveTo(x, u.bbox.top); ctx.lineTo(x, u.bbox.top + u.bbox.height); ctx.stroke(); ctx.restore();
          }] },
        }, [m.days, hi, lo, v, alarm], div);
        charts += 1;
        points += v.length;
      });
    });
    host.dataset.charts = String(charts);
    host.dataset.points = String(points);
    host.dataset.alarms = String(T.modes.reduce((n, m) => n + m.alarm_days.length, 0));
  }
  if (D.track) { track(D.track); } else {
    document.getElementById("track-section").style.display = "none";
  }

  // A mode's name is the user's (an estimates table's column): text, never markup.
  const esc = (t) => String(t).replace(/[&<>"']/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" })[c]);

  // --- the modes' table ------------------------------------------------------------------
  const table = document.getElementById("modes");
  const efdd = D.modes.some((m) => m.efdd), seen = D.modes.some((m) => m.seen);
  table.innerHTML = "<tr><th>mode</th><th>frequency (Hz)</th><th>± (Hz)</th><th>damping ratio (%)</th><th>± (%)</th><th>MPC</th><th>MPD (°)</th>" +
    (efdd ? "<th>EFDD frequency (Hz)</th><th>EFDD damping (%)</th>" : "") + (seen ? "<th>seen in</th>" : "") + "</tr>";
  D.modes.forEach((m, i) => {
    const tr = document.createElement("tr");
    tr.className = "mode";
    tr.innerHTML = `<td>${esc(m.name)}</td><td>${fmt(m.frequency_hz, 4)}</td><td>${fmt(m.frequency_se_hz, 4)}</td>` +
      `<td>${fmt(100 * m.damping_ratio, 3)}</td><td>${m.damping_se === null ? "—" : fmt(100 * m.damping_se, 3)}</td><td>${fmt(m.mpc, 3)}</td><td>${fmt(m.mpd, 1)}</td>` +
      (efdd ? `<td>${m.efdd ? fmt(m.efdd[0], 4) : "—"}</td><td>${m.efdd ? fmt(100 * m.efdd[1], 3) : "—"}</td>` : "") +
      (seen ? `<td>${m.seen || ""}</td>` : "");
    table.appendChild(tr);
  });

  // --- the MAC matrix --------------------------------------------------------------------
  const mac = document.getElementById("mac");
  if (D.mac.length) {
    mac.innerHTML = "<tr><th></th>" + D.modes.map((m) => `<th>${esc(m.name)}</th>`).join("") + "</tr>" +
      D.mac.map((row, i) => `<tr><th>${esc(D.modes[i].name)}: ${fmt(D.modes[i].frequency_hz, 3)} Hz</th>` + row.map((v) =>
        `<td style="background: rgba(31,119,180,${v.toFixed(3)}); color: ${v > 0.5 ? "#fff" : "#222"}">${v.toFixed(2)}</td>`).join("") + "</tr>").join("");
  }

  // --- the mode shapes, animated ---------------------------------------------------------
  const S = D.shapes, pick = document.getElementById("mode-pick"), host = document.getElementById("shape");
  D.modes.forEach((m, i) => {
    const o = document.createElement("option");
    o.value = String(i);
    o.textContent = `${m.name}: ${m.frequency_hz.toFixed(3)} Hz`;
    pick.appendChild(o);
  });
  if (!S.xyz.length || !D.modes.length) { host.textContent = "no mode to draw"; return; }
  const lo = [0, 1, 2].map((k) => Math.min(...S.xyz.map((p) => p[k])));
  const hi = [0, 1, 2].map((k) => Math.max(...S.xyz.map((p) => p[k])));
  const centre = lo.map((v, k) => (v + hi[k]) / 2);
  const size = Math.max(1e-9, ...hi.map((v, k) => v - lo[k]));
  // Lines between nodes; a node on no line gets a short vertical tick so that it shows.
  const onLine = new Set(S.lines.flat());
  const segs = S.lines.slice();
  const ticks = [];
  S.xyz.forEach((p, i) => { if (!onLine.has(i)) ticks.push(i); });
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xffffff);
  const camera = new THREE.PerspectiveCamera(40, 700 / 450, size / 100, size * 100);
  camera.up.set(0, 0, 1);
  camera.position.set(centre[0] + 1.2 * size, centre[1] - 1.5 * size, centre[2] + 0.8 * size);
  const renderer = new THREE.SVGRenderer();
  renderer.setSize(700, 450);
  host.appendChild(renderer.domElement);
  const controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.target.set(centre[0], centre[1], centre[2]);
  controls.update();
  function lineGeometry(count) {
    const g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.Float32BufferAttribute(new Float32Array(count * 6), 3));
    return g;
  }
  const nSeg = segs.length + ticks.length;
  const rest = new THREE.LineSegments(lineGeometry(nSeg), new THREE.LineBasicMaterial({ color: 0xbbbbbb }));
  const moving = new THREE.LineSegments(lineGeometry(nSeg), new THREE.LineBasicMaterial({ color: 0xd62728 }));
  scene.add(rest, moving);
  function place(geometry, pos) {
    const a = geometry.attributes.position.array;
    let j = 0;
    const put = (p) => { a[j++] = p[0]; a[j++] = p[1]; a[j++] = p[2]; };
    segs.forEach(([i, k]) => { put(pos[i]); put(pos[k]); });
    ticks.forEach((i) => { put(pos[i]); put([pos[i][0], pos[i][1], pos[i][2] + 0.02 * size]); });
    geometry.attributes.position.needsUpdate = true;
  }
  place(rest.geometry, S.xyz);
  let mode = 0, frames = 0, scale = 1;
  function setMode(i) {
    mode = i;
    const top = Math.max(1e-12, ...S.motion[i].flat().map(([re, im]) => Math.hypot(re, im)));
    scale = 0.2 * size / top;
  }
  pick.addEventListener("change", () => setMode(Number(pick.value)));
  setMode(0);
  const start = performance.now();
  function frame(now) {
    // One cycle every 1.5 s whatever the mode's frequency: the motion Re(φ e^{iθ}).
    const th = 2 * Math.PI * ((now - start) / 1500);
    const c = Math.cos(th), s = Math.sin(th);
    const pos = S.xyz.map((p, n) => p.map((v, k) => {
      const [re, im] = S.motion[mode][n][k];
      return v + scale * (re * c - im * s);
    }));
    place(moving.geometry, pos);
    renderer.render(scene, camera);
    frames += 1;
    host.dataset.frames = String(frames);
    host.dataset.phase = th.toFixed(3);
    requestAnimationFrame(frame);
  }
  requestAnimationFrame(frame);
})();
