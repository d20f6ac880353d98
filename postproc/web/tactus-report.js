// The tactus interactive report (written by tactus-post beside index.html). Loads data/model.js
// and data/state_NNNN.js as <script> files (Chromium blocks reading sibling files from file://),
// draws the bodies' boundary surface with three.js and colours it by the chosen field on one
// colour scale fixed over the run. The state of the page is mirrored as JSON in
// #tactus-status, which the browser test reads.
"use strict";
(function () {
  const status = { ready: false, errors: [], missing: [] };
  const report = (message) => {
    status.errors.push(String(message));
    writeStatus();
  };
  window.addEventListener("error", (e) => report(e.message || e));
  const consoleError = console.error.bind(console);
  console.error = (...args) => {
    report(args.join(" "));
    consoleError(...args);
  };
  window.addEventListener("unhandledrejection", (e) => report(e.reason && e.reason.message ? e.reason.message : e.reason));

  let model = null;
  const states = [];
  window.tactusModel = (m) => {
    model = m;
  };
  window.tactusState = (k, s) => {
    states[k] = s;
  };

  const $ = (id) => document.getElementById(id);
  function writeStatus() {
    $("tactus-status").textContent = JSON.stringify(status);
  }

  function decode(text, Type) {
    if (text === null || text === undefined) return null;
    const bin = atob(text);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; ++i) bytes[i] = bin.charCodeAt(i);
    return new Type(bytes.buffer);
  }

  function loadScript(src) {
    return new Promise((resolve, reject) => {
      const el = document.createElement("script");
      el.src = src;
      el.onload = resolve;
      el.onerror = () => reject(new Error("cannot load " + src));
      document.head.appendChild(el);
    });
  }

  // VTK's default rainbow (hue 2/3 -> 0 at full saturation), as the PNG pictures use.
  function rainbow(t) {
    const h = (2 / 3) * (1 - Math.min(1, Math.max(0, t))) * 6;
    const i = Math.floor(h) % 6;
    const f = h - Math.floor(h);
    const q = 1 - f;
    return [
      [1, f, 0],
      [q, 1, 0],
      [0, 1, f],
      [0, q, 1],
      [f, 0, 1],
      [1, 0, q],
    ][i];
  }
  const GREY = [0.78, 0.78, 0.78];

  const fmt = (x) => (Math.abs(x) >= 100 ? x.toFixed(0) : Math.abs(x) >= 1 ? x.toPrecision(3) : x.toPrecision(3));
  const mm = (p) => "(" + p.map((c) => (c * 1e3).toFixed(2)).join(", ") + ") mm";

  // --- the scene ----------------------------------------------------------------------------
  const view = {};
  function buildScene() {
    const T = window.THREE;
    const host = $("view");
    view.renderer = new T.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    view.renderer.outputColorSpace = "srgb-linear";
    view.renderer.setPixelRatio(1);
    view.renderer.setClearColor(0xffffff, 1);
    host.appendChild(view.renderer.domElement);
    view.scene = new T.Scene();
    view.camera = new T.PerspectiveCamera(30, 1, 1e-4, 100);
    view.scene.add(view.camera);
    view.scene.add(new T.AmbientLight(0xffffff, 1.6));
    const light = new T.DirectionalLight(0xffffff, 1.6);
    light.position.set(0.3, 0.5, 1);
    view.camera.add(light);

    // The faces sorted by body, one draw group (and material) per body, so a body can be hidden.
    const faces = decode(model.faces, Uint32Array);
    const faceTet = decode(model.face_tet, Uint32Array);
    const faceBody = decode(model.face_body, Uint32Array);
    const F = faces.length / 3;
    const order = Array.from({ length: F }, (_, i) => i).sort((a, b) => faceBody[a] - faceBody[b] || a - b);
    view.faces = new Uint32Array(3 * F);
    view.faceTet = new Uint32Array(F);
    view.faceBody = new Uint32Array(F);
    order.forEach((f, i) => {
      view.faces.set(faces.subarray(3 * f, 3 * f + 3), 3 * i);
      view.faceTet[i] = faceTet[f];
      view.faceBody[i] = faceBody[f];
    });
    view.reference = decode(model.reference, Float32Array);
    view.nodeId = decode(model.node_id, Uint32Array);
    view.geometry = new T.BufferGeometry();
    view.positions = new Float32Array(9 * F);
    view.colors = new Float32Array(9 * F);
    view.geometry.setAttribute("position", new T.BufferAttribute(view.positions, 3));
    view.geometry.setAttribute("color", new T.BufferAttribute(view.colors, 3));
    view.materials = model.bodies.map(() => new T.MeshLambertMaterial({ vertexColors: true, side: T.DoubleSide }));
    for (let i = 0; i < F; ) {
      let j = i;
      while (j < F && view.faceBody[j] === view.faceBody[i]) ++j;
      view.geometry.addGroup(3 * i, 3 * (j - i), Math.min(view.faceBody[i], view.materials.length - 1));
      i = j;
    }
    view.mesh = new T.Mesh(view.geometry, view.materials);
    view.scene.add(view.mesh);
    bodyToggles();

    // Frame the reference configuration.
    const box = new T.Box3();
    for (let i = 0; i < view.reference.length; i += 3)
      box.expandByPoint(new T.Vector3(view.reference[i], view.reference[i + 1], view.reference[i + 2]));
    const sphere = box.getBoundingSphere(new T.Sphere());
    view.radius = Math.max(sphere.radius, 1e-6);
    view.marker = new T.Mesh(new T.SphereGeometry(0.012 * view.radius, 16, 12), new T.MeshBasicMaterial({ color: 0x000000 }));
    view.scene.add(view.marker);
    view.camera.near = view.radius / 100;
    view.camera.far = view.radius * 100;
    view.camera.position.copy(sphere.center).add(viewDirection().multiplyScalar(3.9 * view.radius));
    view.camera.up.set(0, 0, 1);
    view.controls = new T.OrbitControls(view.camera, view.renderer.domElement);
    view.controls.target.copy(sphere.center);
    view.controls.update();
    view.controls.addEventListener("change", render); // (update() itself fires "change": never call it from render)
    window.addEventListener("resize", resize);
    resize();
    setupPicking();
  }

  // A checkbox per body. With contact, the bodies that carry no pressure (the masters: a block, a
  // handle) start hidden, so the pressed skin is in view; tick them back to see them.
  function bodyToggles() {
    const host = $("bodies");
    const pressed = pressedBodies();
    model.bodies.forEach((name, b) => {
      const label = document.createElement("label");
      const box = document.createElement("input");
      box.type = "checkbox";
      box.checked = pressed.size === 0 || pressed.has(b);
      view.materials[b].visible = box.checked;
      box.addEventListener("change", () => {
        view.materials[b].visible = box.checked;
        render();
      });
      label.append(box, " " + name + " ");
      host.appendChild(label);
    });
  }

  function pressedBodies() {
    const bodies = new Set();
    const p = model.fields.pressure.peak;
    if (!(p.value > 0) || !states[p.state] || !stateArrays(p.state).pressure) return bodies;
    const pressure = stateArrays(p.state).pressure;
    for (let f = 0; f < view.faceBody.length; ++f)
      for (let c = 0; c < 3; ++c) if (pressure[view.faces[3 * f + c]] > 0) bodies.add(view.faceBody[f]);
    return bodies;
  }

  // The camera's side: with contact, along the pressure-weighted outward normal of the pressed
  // faces at the peak's output (the side the contact partner sees, as pressure.png); otherwise an
  // oblique view.
  function viewDirection() {
    const T = window.THREE;
    const d = new T.Vector3(1, -1.6, 1.1);
    const p = model.fields.pressure.peak;
    if (p.value > 0 && states[p.state] && stateArrays(p.state).pressure) {
      const a = stateArrays(p.state);
      const n = new T.Vector3();
      const x = [0, 1, 2].map(() => new T.Vector3());
      for (let f = 0; f < view.faceBody.length; ++f) {
        let q = 0;
        for (let c = 0; c < 3; ++c) {
          const v = view.faces[3 * f + c];
          q += a.pressure[v] / 3;
          x[c].set(...[0, 1, 2].map((i) => view.reference[3 * v + i] + a.displacement[3 * v + i]));
        }
        if (q > 0) n.add(x[1].clone().sub(x[0]).cross(x[2].clone().sub(x[0])).multiplyScalar(q));
      }
      if (n.lengthSq() > 0) d.copy(n).normalize().add(new T.Vector3(0.15, -0.15, 0.15));
    }
    return d.normalize();
  }

  function resize() {
    const host = $("view");
    const w = host.clientWidth;
    const h = host.clientHeight;
    view.renderer.setSize(w, h);
    view.camera.aspect = w / Math.max(h, 1);
    view.camera.updateProjectionMatrix();
    const r = host.getBoundingClientRect();
    status.canvas = [r.left, r.top, w, h];
    render();
  }

  function render() {
    if (!view.renderer) return;
    view.renderer.render(view.scene, view.camera);
    drawTriad();
  }

  // The axes triad and the side the model is seen from, drawn from the camera's rotation.
  function drawTriad() {
    const c = $("triad");
    const g = c.getContext("2d");
    g.clearRect(0, 0, c.width, c.height);
    const e = view.camera.matrixWorldInverse.elements;
    const axes = [
      ["x", "#d22", 0],
      ["y", "#2a2", 1],
      ["z", "#22d", 2],
    ];
    for (const [name, colour, k] of axes) {
      const sx = e[k * 4 + 0];
      const sy = e[k * 4 + 1];
      g.strokeStyle = colour;
      g.fillStyle = colour;
      g.lineWidth = 2;
      g.beginPath();
      g.moveTo(50, 60);
      g.lineTo(50 + 32 * sx, 60 - 32 * sy);
      g.stroke();
      g.font = "12px sans-serif";
      g.fillText(name, 50 + 40 * sx - 3, 60 - 40 * sy + 4);
    }
    const d = view.camera.position.clone().sub(view.controls.target);
    const a = [Math.abs(d.x), Math.abs(d.y), Math.abs(d.z)];
    const k = a.indexOf(Math.max(...a));
    g.fillStyle = "#333";
    g.font = "11px sans-serif";
    g.fillText("seen from " + ([d.x, d.y, d.z][k] >= 0 ? "+" : "-") + "xyz"[k], 4, 106);
  }

  // --- fields -------------------------------------------------------------------------------
  let current = 0;
  let field = "pressure";
  const decoded = [];
  function stateArrays(k) {
    if (!decoded[k]) {
      const s = states[k];
      decoded[k] = {
        displacement: decode(s.displacement, Float32Array),
        pressure: decode(s.pressure, Float32Array),
        von_mises_nodal: decode(s.von_mises_nodal, Float32Array),
        von_mises_tet: decode(s.von_mises_tet, Float32Array),
      };
    }
    return decoded[k];
  }
  const fieldInfo = (f) => model.fields[f.startsWith("von_mises") ? "von_mises" : f];

  // Colours the surface by the field at state k; returns the state's largest value, where.
  function colour(k) {
    const a = stateArrays(k);
    const info = fieldInfo(field);
    const cap = info.cap > 0 ? info.cap : 1;
    const F = view.faces.length / 3;
    const best = { value: -1, vertex: -1, face: -1 };
    let pressed = 0;
    const counted = new Uint8Array(model.vertices);
    for (let f = 0; f < F; ++f) {
      for (let c = 0; c < 3; ++c) {
        const v = view.faces[3 * f + c];
        const o = 9 * f + 3 * c;
        for (let i = 0; i < 3; ++i) view.positions[o + i] = view.reference[3 * v + i] + a.displacement[3 * v + i];
        let rgb;
        let value;
        if (field === "pressure") {
          value = a.pressure ? a.pressure[v] : 0;
          rgb = value > 0 ? rainbow(value / cap) : GREY;
          if (value > 0 && !counted[v]) (counted[v] = 1), ++pressed;
        } else if (field === "von_mises_tet") {
          value = a.von_mises_tet[f];
          rgb = rainbow(value / cap);
        } else if (field === "von_mises_nodal") {
          value = a.von_mises_nodal[v];
          rgb = rainbow(value / cap);
        } else {
          const d = a.displacement;
          value = Math.hypot(d[3 * v], d[3 * v + 1], d[3 * v + 2]);
          rgb = rainbow(value / cap);
        }
        view.colors.set(rgb, o);
        if (value > best.value) Object.assign(best, { value, vertex: v, face: f });
      }
    }
    view.geometry.attributes.position.needsUpdate = true;
    view.geometry.attributes.color.needsUpdate = true;
    view.geometry.computeVertexNormals();
    view.geometry.computeBoundingSphere();
    status.pressed_vertices = field === "pressure" ? pressed : null;
    return best;
  }

  function show(k) {
    current = k;
    const best = colour(k);
    const info = fieldInfo(field);
    const a = stateArrays(k);
    const t = model.states[k].time;
    $("time").textContent = "t = " + (t * 1e3).toFixed(3) + " ms  (output " + (k + 1) + " of " + model.states.length + ")";
    $("slider").value = String(k);
    const shown = best.value > 0;
    view.marker.visible = shown;
    if (shown) {
      const v = best.vertex;
      view.marker.position.set(
        view.reference[3 * v] + a.displacement[3 * v],
        view.reference[3 * v + 1] + a.displacement[3 * v + 1],
        view.reference[3 * v + 2] + a.displacement[3 * v + 2]
      );
    }
    drawBar(info, best);
    for (const p of plots) drawPlot(p, t);
    status.state = k;
    status.time = t;
    status.field = field;
    status.state_max = shown
      ? { value: best.value, node_id: view.nodeId[best.vertex], tet_id: field === "von_mises_tet" ? view.faceTet[best.face] : null }
      : null;
    const u = new URL(window.location.href);
    u.searchParams.set("state", String(k));
    u.searchParams.set("field", field);
    if (window.location.protocol !== "file:" || window.history.replaceState) {
      try {
        window.history.replaceState(null, "", u.toString());
      } catch (e) {
        /* some file:// pages refuse history changes; the parameters are a convenience */
      }
    }
    render();
    writeStatus();
  }

  function drawBar(info, best) {
    const c = $("bar");
    const g = c.getContext("2d");
    g.clearRect(0, 0, c.width, c.height);
    const w = c.width - 40;
    for (let x = 0; x < w; ++x) {
      const [r, gg, b] = rainbow(x / (w - 1));
      g.fillStyle = "rgb(" + Math.round(255 * r) + "," + Math.round(255 * gg) + "," + Math.round(255 * b) + ")";
      g.fillRect(20 + x, 8, 1, 36);
    }
    g.fillStyle = "#222";
    g.font = "22px sans-serif";
    for (let i = 0; i <= 4; ++i) {
      const x = 20 + (i / 4) * (w - 1);
      g.fillRect(x, 44, 2, 8);
      const label = fmt((i / 4) * info.cap * info.scale);
      g.fillText(label, Math.min(c.width - g.measureText(label).width, Math.max(0, x - g.measureText(label).width / 2)), 76);
    }
    const p = info.peak;
    let text = info.label + " in " + info.unit + ": 0 – " + fmt(info.cap * info.scale) + " (" + info.cap_rule + "; red: at or above).";
    if (p && p.value > 0)
      text +=
        " True peak " + fmt(p.value * info.scale) + " " + info.unit + " at t = " + (p.time * 1e3).toFixed(3) + " ms, " +
        (field === "von_mises_tet" || field === "von_mises_nodal" ? "tet " : "node ") + p.id + ", " + mm(p.position) + ".";
    if (best.value > 0) text += " This output: largest " + fmt(best.value * info.scale) + " " + info.unit + " (black dot).";
    else if (field === "pressure") text += " No contact at this output.";
    $("scale").textContent = text;
  }

  // --- picking --------------------------------------------------------------------------------
  function setupPicking() {
    const T = window.THREE;
    const ray = new T.Raycaster();
    let down = null;
    const el = view.renderer.domElement;
    el.addEventListener("pointerdown", (e) => (down = [e.clientX, e.clientY]));
    el.addEventListener("pointerup", (e) => {
      if (!down || Math.hypot(e.clientX - down[0], e.clientY - down[1]) > 4) return;
      const r = el.getBoundingClientRect();
      ray.setFromCamera(new T.Vector2(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1), view.camera);
      const hit = ray.intersectObject(view.mesh).find((h) => view.materials[view.faceBody[h.faceIndex]].visible);
      if (hit) pick(hit.faceIndex, hit.point);
    });
  }

  function pick(f, point) {
    const a = stateArrays(current);
    let best = -1;
    let bestD = Infinity;
    for (let c = 0; c < 3; ++c) {
      const o = 9 * f + 3 * c;
      const d = Math.hypot(view.positions[o] - point.x, view.positions[o + 1] - point.y, view.positions[o + 2] - point.z);
      if (d < bestD) (bestD = d), (best = view.faces[3 * f + c]);
    }
    const v = best;
    const x = [0, 1, 2].map((i) => view.reference[3 * v + i] + a.displacement[3 * v + i]);
    const u = [0, 1, 2].map((i) => a.displacement[3 * v + i]);
    const body = model.bodies[view.faceBody[f]] || "body " + view.faceBody[f];
    const lines = [
      "node " + view.nodeId[v] + " on " + body + " at " + mm(x),
      "pressure " + fmt((a.pressure ? a.pressure[v] : 0) * 1e-6) + " MPa",
      "von Mises " + fmt(a.von_mises_nodal[v] * 1e-6) + " MPa (nodal average)",
      "tet " + view.faceTet[f] + ": von Mises " + fmt(a.von_mises_tet[f] * 1e-6) + " MPa",
      "|u| " + fmt(Math.hypot(...u) * 1e3) + " mm",
    ];
    $("pick").textContent = lines.join("\n");
    status.picked = { node_id: view.nodeId[v], tet_id: view.faceTet[f] };
    writeStatus();
  }

  // --- plots ----------------------------------------------------------------------------------
  const plots = [];
  function setupPlots() {
    const h = model.history || {};
    const out = model.at_outputs || [];
    const ot = out.map((o) => o.time);
    plots.push({
      id: "plot_force",
      title: "contact force (N)",
      series: [
        { label: "per step", t: h.time, y: h.contact_force, colour: "#aaa", scale: 1 },
        { label: "windowed, at outputs", t: ot, y: out.map((o) => o.windowed_normal_force), colour: "#14c", scale: 1, dots: true },
      ],
    });
    plots.push({
      id: "plot_area",
      title: "contact area (mm²)",
      series: [
        { label: "per step", t: h.time, y: h.contact_area, colour: "#aaa", scale: 1e6 },
        { label: "windowed, at outputs", t: ot, y: out.map((o) => o.windowed_area), colour: "#14c", scale: 1e6, dots: true },
      ],
    });
    plots.push({
      id: "plot_pressure",
      title: "peak contact pressure (MPa)",
      series: [
        { label: "one step (impulse / dt)", t: h.time, y: h.peak_step_pressure, colour: "#aaa", scale: 1e-6 },
        { label: "windowed", t: h.time, y: h.peak_pressure, colour: "#14c", scale: 1e-6 },
      ],
    });
  }

  function drawPlot(p, now) {
    const c = $(p.id);
    const g = c.getContext("2d");
    g.clearRect(0, 0, c.width, c.height);
    const series = p.series.filter((s) => s.t && s.y && s.t.length && s.y.length === s.t.length);
    const L = 90;
    const R = c.width - 12;
    const Tp = 40;
    const B = c.height - 36;
    let tmax = model.states.length ? model.states[model.states.length - 1].time : 0;
    let ymax = 0;
    for (const s of series) {
      tmax = Math.max(tmax, s.t[s.t.length - 1]);
      for (const y of s.y) if (isFinite(y)) ymax = Math.max(ymax, y * s.scale);
    }
    if (!(tmax > 0)) tmax = 1;
    if (!(ymax > 0)) ymax = 1;
    const X = (t) => L + (t / tmax) * (R - L);
    const Y = (y) => B - (y / ymax) * (B - Tp);
    g.strokeStyle = "#888";
    g.lineWidth = 1;
    g.strokeRect(L, Tp, R - L, B - Tp);
    g.fillStyle = "#222";
    g.font = "22px sans-serif";
    g.fillText(p.title, L, 28);
    g.fillText(fmt(ymax), 4, Tp + 18);
    g.fillText("0", 60, B);
    g.fillText((tmax * 1e3).toFixed(2) + " ms", R - 90, B + 28);
    let legend = L + g.measureText(p.title).width + 16;
    g.font = "18px sans-serif";
    for (const s of series) {
      g.strokeStyle = s.colour;
      g.fillStyle = s.colour;
      g.lineWidth = 2;
      g.beginPath();
      s.t.forEach((t, i) => (i ? g.lineTo(X(t), Y(s.y[i] * s.scale)) : g.moveTo(X(t), Y(s.y[i] * s.scale))));
      g.stroke();
      if (s.dots) for (let i = 0; i < s.t.length; ++i) g.fillRect(X(s.t[i]) - 4, Y(s.y[i] * s.scale) - 4, 8, 8);
      g.fillText(s.label, legend, 28);
      legend += g.measureText(s.label).width + 14;
    }
    g.strokeStyle = "#d00";
    g.lineWidth = 2;
    g.beginPath();
    g.moveTo(X(now), Tp);
    g.lineTo(X(now), B);
    g.stroke();
  }

  // --- the grasp: the handle's load per region and digit (run.json's joints.grasp) -------------
  function showGrasp(g) {
    if (!g) return;
    $("grasp").hidden = false;
    $("grip").textContent =
      "grip " + g.final_grip_N.toFixed(1) + " N (target " + g.target_N.toFixed(1) + " N) on " + g.handle +
      "; peak pressure averaged over " + (g.sensor_area_m2 * 1e6).toFixed(0) + " mm²" + (g.quasi_static ? "." : "; the hold was dynamic (KE/IE above 5 %).");
    const table = $("regions");
    const head = table.insertRow();
    for (const h of ["region", "force N", "share", "area mm²", "peak MPa"]) head.appendChild(document.createElement("th")).textContent = h;
    const widest = Math.max(1e-12, ...g.regions.map((r) => r.share));
    for (const r of g.regions) {
      const row = table.insertRow();
      row.insertCell().textContent = r.name;
      row.insertCell().textContent = r.force_N.toFixed(1);
      const share = row.insertCell();
      const bar = document.createElement("span");
      bar.className = "share";
      bar.style.width = Math.round((48 * r.share) / widest) + "px";
      share.append(bar, " " + (100 * r.share).toFixed(0) + " %");
      row.insertCell().textContent = (r.area_m2 * 1e6).toFixed(0);
      row.insertCell().textContent = (r.averaged_peak_pressure_Pa * 1e-6).toFixed(3);
    }
    if (g.grip_map) {
      const img = $("grip_map");
      img.src = g.grip_map;
      img.hidden = false;
      img.title = "pressure against the angle round the handle and the length along it, capped as the pictures are";
    }
    status.grasp_regions = g.regions.length;
  }

  // --- start ----------------------------------------------------------------------------------
  async function main() {
    try {
      await loadScript("data/model.js");
    } catch (e) {
      $("run").textContent = "No data: data/model.js is missing beside this page (run tactus-post again).";
      report(e.message);
      return;
    }
    status.missing = model.missing.slice();
    const n = model.states.length;
    for (let k = 0; k < n; ++k) {
      $("run").textContent = "loading output " + (k + 1) + " of " + n + "…";
      const file = "data/state_" + String(k).padStart(4, "0") + ".js";
      try {
        await loadScript(file);
      } catch (e) {
        status.missing.push(file + " is missing");
      }
    }
    const loaded = model.states.map((_, k) => k).filter((k) => states[k]);
    const missingText = status.missing.length ? "Not shown: " + status.missing.join("; ") + "." : "";
    const decimated =
      model.faces_shown < model.surface_faces
        ? " The surface that never touches is coarsened (" + model.faces_shown + " of " + model.surface_faces + " triangles shown) to keep the page small."
        : "";
    $("missing").textContent = missingText + decimated + (model.status !== "completed" ? " The run's status: " + model.status + "." : "");
    $("run").textContent =
      model.bodies.join(", ") + ": " + n + " output states, " + model.vertices + " surface nodes, " + model.faces_shown + " triangles.";
    status.outputs = loaded.length;
    status.peaks = {};
    for (const f of Object.keys(model.fields)) status.peaks[f] = model.fields[f].peak;
    if (!loaded.length) {
      $("run").textContent += " No output state could be shown.";
      writeStatus();
      return;
    }
    buildScene();
    setupPlots();
    showGrasp(model.grasp);
    const params = new URLSearchParams(window.location.search);
    const hasContact = model.fields.pressure.peak.value > 0;
    field = params.get("field") || (hasContact ? "pressure" : "von_mises_nodal");
    if (!["pressure", "von_mises_nodal", "von_mises_tet", "displacement"].includes(field)) field = "von_mises_nodal";
    document.querySelectorAll("input[name=field]").forEach((r) => {
      r.checked = r.value === field;
      r.addEventListener("change", () => {
        field = r.value;
        show(current);
      });
    });
    let start = loaded[loaded.length - 1];
    if (params.has("state")) start = Math.min(n - 1, Math.max(0, parseInt(params.get("state"), 10) || 0));
    else if (params.has("t")) {
      const t = parseFloat(params.get("t"));
      start = loaded.reduce((b, k) => (Math.abs(model.states[k].time - t) < Math.abs(model.states[b].time - t) ? k : b), loaded[0]);
    }
    if (!states[start]) start = loaded[0];
    const slider = $("slider");
    slider.max = String(n - 1);
    slider.disabled = false;
    slider.addEventListener("input", () => {
      const k = parseInt(slider.value, 10);
      if (states[k]) show(k);
    });
    let timer = null;
    $("play").disabled = false;
    $("play").addEventListener("click", () => {
      if (timer) return void (clearInterval(timer), (timer = null), ($("play").textContent = "play"));
      $("play").textContent = "pause";
      timer = setInterval(() => {
        const i = loaded.indexOf(current);
        show(loaded[(i + 1) % loaded.length]);
      }, 400);
    });
    show(start);
    status.load_ms = Math.round(performance.now()); // from navigation start: every file read, the first picture drawn
    status.ready = true;
    writeStatus();
  }
  main();
})();
