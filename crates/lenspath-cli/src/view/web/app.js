// lenspath view: the page. It shows the frames the server streams over a
// WebSocket and sends every change as a JSON object of the settings that
// change; the server checks them as it checks the CLI's flags, and an error
// comes back as a message shown on the page.

const $ = (id) => document.getElementById(id);

/** What the MTF depends on, as last shown: it is fetched again only when the optics change, not on a move. */
let shownOptics = "";

const canvas = $("frame");
const context = canvas.getContext("2d");

/** The last state the server sent: settings, choices, the camera's figures. */
let state = null;
/** Frames received, and the number of the last one drawn, in arrival order. */
let framesReceived = 0;
let framesDrawn = 0;

// ---- Talking to the server ----

function showError(message) {
  const box = $("error");
  box.textContent = message;
  box.hidden = !message;
}

async function post(path, body, contentType = "application/json") {
  const response = await fetch(path, {
    method: "POST",
    headers: { "Content-Type": contentType },
    body: contentType === "application/json" ? JSON.stringify(body) : body,
  });
  const answer = await response.json().catch(() => ({ error: `${response.status} ${response.statusText}` }));
  if (!response.ok) {
    showError(answer.error ?? `${response.status} ${response.statusText}`);
    return null;
  }
  showError("");
  return answer;
}

/** Changes settings; one request at a time, the latest change winning. */
let pending = null;
let inFlight = false;
async function change(fields) {
  pending = { ...(pending ?? {}), ...fields };
  if (inFlight) return;
  inFlight = true;
  while (pending) {
    const next = pending;
    pending = null;
    const answer = await post("/api/settings", next);
    // A newer change waiting means the controls already show newer values than this answer.
    if (answer && !pending) showState(answer);
  }
  inFlight = false;
}

function connect() {
  const socket = new WebSocket(`ws://${location.host}/ws`);
  socket.binaryType = "blob";
  socket.onopen = () => ($("connection").textContent = "connected");
  socket.onclose = () => {
    $("connection").textContent = "disconnected: retrying…";
    setTimeout(connect, 1000);
  };
  socket.onmessage = async (event) => {
    if (event.data instanceof Blob) {
      // A frame follows its "frame" message; the canvas says which it shows.
      const shown = { ...lastFrame };
      const sequence = ++framesReceived;
      const bitmap = await createImageBitmap(event.data);
      // Decoding is asynchronous: a frame decoded after a newer one was drawn
      // is not drawn over it (two quick steps could otherwise leave the older).
      if (sequence < framesDrawn) return;
      framesDrawn = sequence;
      // A half-size preview is scaled up to the image's size.
      context.drawImage(bitmap, 0, 0, canvas.width, canvas.height);
      canvas.dataset.generation = shown.generation;
      canvas.dataset.spp = shown.spp;
      return;
    }
    const message = JSON.parse(event.data);
    const handler = handlers[message.type];
    if (handler) handler(message);
  };
}

const handlers = {
  state: showState,
  frame: showFrameStats,
  error: (m) => showError(m.message),
  "autofocus-start": startCurve,
  "autofocus-evaluation": addCurvePoint,
  "autofocus-done": finishCurve,
  "autofocus-failed": (m) => {
    showError(`autofocus: ${m.message}`);
    $("af-result").textContent = "failed";
  },
};

// ---- Showing the state ----

const F_STOP_STEPS_PER_STOP = 3;
const F_STOP_MAX = 32;

/** The f-number of slider step k: thirds of a stop from wide open. */
function fNumberAt(k) {
  return state.wide_open_f_number * Math.pow(2, k / (2 * F_STOP_STEPS_PER_STOP));
}

function showState(s) {
  state = s;
  const settings = s.settings;
  $("scene").textContent = `${s.scene}, ${s.resolution[0]}×${s.resolution[1]}`;
  // Setting a canvas's size clears it, even to the size it has: only when it changes,
  // or a state message would blank the image until the next frame (none, once refined).
  if (canvas.width !== s.resolution[0] || canvas.height !== s.resolution[1]) {
    [canvas.width, canvas.height] = s.resolution;
  }
  fillSelect($("lens"), s.lenses, settings.lens);
  fillSelect($("af-metric"), s.metrics, $("af-metric").value || s.metric_default);
  fillSelect($("af-strategy"), s.strategies, $("af-strategy").value || s.strategy_default);
  $("lens-facts").textContent =
    `${s.focal_length_mm.toFixed(1)} mm, f/${s.wide_open_f_number.toFixed(2)} wide open, ` +
    `sensor ${s.sensor_mm[0].toFixed(1)}×${s.sensor_mm[1].toFixed(1)} mm` +
    (s.lens_disperses
      ? `; longitudinal colour ${(1000 * s.longitudinal_color_mm).toFixed(0)} µm (F − C)`
      : "; no glass data: no colour");
  $("dispersion").checked = settings.dispersion;
  $("dispersion").disabled = !s.lens_disperses;
  $("diffraction").checked = settings.diffraction;

  const fstop = $("fstop");
  const steps = Math.max(0, Math.floor(2 * F_STOP_STEPS_PER_STOP * Math.log2(F_STOP_MAX / s.wide_open_f_number)));
  fstop.max = steps;
  const n = settings.f_number ?? s.wide_open_f_number;
  setValue(fstop, Math.round(2 * F_STOP_STEPS_PER_STOP * Math.log2(n / s.wide_open_f_number)));
  $("fstop-value").textContent = `f/${n.toFixed(1)}`;

  const [kind, count] = settings.aperture.split(":");
  setValue($("aperture-kind"), kind);
  if (count) setValue($("aperture-count"), count);
  $("aperture-count").disabled = kind === "circle";

  const sensor = $("sensor-depth");
  sensor.min = s.focus_range_mm[0];
  sensor.max = s.focus_range_mm[1];
  setValue(sensor, s.sensor_depth_mm);
  $("sensor-depth-value").textContent = `${s.sensor_depth_mm.toFixed(3)} mm`;
  setValue($("focus-distance"), s.focus_distance_m == null ? "" : s.focus_distance_m.toFixed(3));
  $("max-spp").max = s.max_spp_limit;
  setValue($("max-spp"), settings.max_spp);
  fillSelect($("integrator"), s.integrators, settings.integrator);
  showSensor(s);
  $("layout").src = `/api/layout.svg?generation=${s.generation}`;
  shownOptics = JSON.stringify([
    settings.lens, settings.f_number, settings.dispersion, s.sensor_depth_mm, s.focal_length_mm, s.sensor_mm,
  ]);
  showMtf();
  $("layout-caption").textContent = `sensor ${s.sensor_depth_mm.toFixed(3)} mm behind the stop`;
}

/** The MTF plot, computed on the server (about a second) only while its panel is open. */
function showMtf() {
  if ($("mtf-details").open) {
    const src = `/api/mtf.svg?optics=${encodeURIComponent(shownOptics)}`;
    if ($("mtf").getAttribute("src") !== src) {
      $("mtf").src = src;
    }
  }
}

$("mtf-details").addEventListener("toggle", showMtf);

const SENSOR_CONTROLS = ["sensor-model", "sensor-auto", "sensor-iso", "sensor-exposure", "sensor-wb"];

/** The sensor's settings: the scene's or the page's, the library's defaults where they say nothing. */
function showSensor(s) {
  const on = s.settings.sensor != null;
  $("sensor-on").checked = on;
  const shown = { ...s.sensor_defaults, ...(s.settings.sensor ?? {}) };
  fillSelect($("sensor-model"), s.sensor_models, shown.model);
  setValue($("sensor-iso"), shown.iso);
  setValue($("sensor-exposure"), shown.exposure_time_s);
  setValue($("sensor-wb"), shown.white_balance);
  $("sensor-auto").checked = shown.auto_exposure;
  for (const id of SENSOR_CONTROLS) $(id).disabled = !on;
  // Metered, the exposure time and ISO are the camera's to choose.
  for (const id of ["sensor-iso", "sensor-exposure"]) $(id).disabled ||= shown.auto_exposure;
}

/** Sends the sensor controls: the table the settings file will carry, or none. */
function sendSensor() {
  if (!$("sensor-on").checked) {
    change({ sensor: null });
    return;
  }
  change({
    sensor: {
      ...(state.settings.sensor ?? {}),
      model: $("sensor-model").value,
      auto_exposure: $("sensor-auto").checked,
      iso: Number($("sensor-iso").value),
      exposure_time_s: Number($("sensor-exposure").value),
      white_balance: $("sensor-wb").value,
    },
  });
}

/** Shows a value in a control, unless the control has the focus: what is being typed or dragged wins. */
function setValue(control, value) {
  if (document.activeElement !== control) control.value = value;
}

function fillSelect(select, names, chosen) {
  if ([...select.options].map((o) => o.value).join("\n") !== names.join("\n")) {
    select.replaceChildren(...names.map((n) => new Option(n, n)));
  }
  select.value = chosen;
}

/** The last "frame" message: which generation and samples the next frame is. */
let lastFrame = { generation: -1, spp: 0 };

function showFrameStats(m) {
  lastFrame = { generation: m.generation, spp: m.spp };
  if (state && m.generation !== state.generation) return;
  if (m.preview) {
    $("spp").textContent = "preview";
    $("latency").textContent = `first preview ${m.latency_ms.toFixed(0)} ms`;
    return;
  }
  $("spp").textContent = `${m.spp} / ${m.max_spp} spp`;
  $("sensor-exposure-taken").textContent = m.exposure
    ? `taken at ${m.exposure.time_s < 0.5 ? `1/${Math.round(1 / m.exposure.time_s)}` : m.exposure.time_s.toFixed(2)} s, ISO ${Math.round(m.exposure.iso)}`
    : "";
  $("speed").textContent = `${(m.rays_per_second / 1e6).toFixed(2)} M rays/s`;
}

// ---- The focus curve of an autofocus ----

let curve = null;

function startCurve(m) {
  curve = { range: m.range_mm, points: [] };
  $("af-result").textContent = `searching (${m.strategy}, ${m.metric})…`;
  delete $("af-result").dataset.sensorMm;
  drawCurve();
}

function addCurvePoint(m) {
  if (!curve) return;
  curve.points.push(m);
  drawCurve();
}

function finishCurve(m) {
  if (curve) curve.chosen = m.sensor_depth_mm;
  drawCurve();
  const distance = m.focus_distance_m == null ? "beyond infinity" : `${m.focus_distance_m.toFixed(3)} m`;
  const result = $("af-result");
  result.textContent =
    `sensor ${m.sensor_depth_mm.toFixed(4)} mm, in focus at ${distance}; ` +
    `${m.evaluations} evaluations, ${m.seconds.toFixed(2)} s`;
  result.dataset.sensorMm = m.sensor_depth_mm;
}

function drawCurve() {
  const svg = $("af-curve");
  const ns = "http://www.w3.org/2000/svg";
  svg.replaceChildren();
  if (!curve) return;
  // The axis spans what was searched (with a margin), within the focus range.
  const zs = curve.points.map((p) => p.sensor_depth_mm).concat(curve.chosen ?? []);
  const [lo, hi] = zs.length ? [Math.min(...zs), Math.max(...zs)] : curve.range;
  const margin = 0.1 * Math.max(hi - lo, 0.02 * (curve.range[1] - curve.range[0]));
  const z0 = Math.max(curve.range[0], lo - margin);
  const z1 = Math.min(curve.range[1], hi + margin);
  const top = Math.max(...curve.points.map((p) => p.score), 1e-30);
  const x = (z) => 5 + (290 * (z - z0)) / (z1 - z0);
  const y = (score) => 105 - (95 * score) / top;
  for (const [z, anchor] of [
    [z0, "start"],
    [z1, "end"],
  ]) {
    const label = document.createElementNS(ns, "text");
    label.setAttribute("x", x(z));
    label.setAttribute("y", 118);
    label.setAttribute("text-anchor", anchor);
    label.setAttribute("font-size", 9);
    label.textContent = `${z.toFixed(2)} mm`;
    svg.append(label);
  }
  for (const p of curve.points) {
    const dot = document.createElementNS(ns, "circle");
    dot.setAttribute("cx", x(p.sensor_depth_mm));
    dot.setAttribute("cy", y(p.score));
    dot.setAttribute("r", 2.5);
    dot.setAttribute("class", p.refocused ? "point refocused" : "point");
    svg.append(dot);
  }
  if (curve.chosen != null) {
    const line = document.createElementNS(ns, "line");
    line.setAttribute("x1", x(curve.chosen));
    line.setAttribute("x2", x(curve.chosen));
    line.setAttribute("y1", 5);
    line.setAttribute("y2", 107);
    line.setAttribute("class", "chosen");
    svg.append(line);
  }
}

// ---- The image: autofocus on a click or a rectangle; orbit, pan, zoom ----

/** The pointer's place in fractions of the image. */
function fraction(event) {
  const box = canvas.getBoundingClientRect();
  return [
    Math.min(Math.max((event.clientX - box.left) / box.width, 0), 1),
    Math.min(Math.max((event.clientY - box.top) / box.height, 0), 1),
  ];
}

/** The patch a click focuses on: a tenth of the image's width around it. */
const CLICK_PATCH = [0.1, 0.12];
/** A drag shorter than this (fraction of the width) is a click. */
const CLICK_SLOP = 0.01;

let drag = null;

canvas.addEventListener("contextmenu", (e) => e.preventDefault());
canvas.addEventListener("pointerdown", (event) => {
  canvas.setPointerCapture(event.pointerId);
  const move = event.button === 1 || (event.button === 2 && event.shiftKey) ? "pan" : event.button === 2 ? "orbit" : "patch";
  drag = { move, start: fraction(event), last: [event.clientX, event.clientY] };
});
canvas.addEventListener("pointermove", (event) => {
  if (!drag) return;
  if (drag.move === "patch") {
    showPatch(drag.start, fraction(event));
    return;
  }
  const dx = event.clientX - drag.last[0];
  const dy = event.clientY - drag.last[1];
  drag.last = [event.clientX, event.clientY];
  if (drag.move === "orbit") orbit(dx, dy);
  else pan(dx, dy);
});
canvas.addEventListener("pointerup", (event) => {
  if (drag?.move === "patch") {
    const end = fraction(event);
    const [x0, y0] = drag.start;
    let patch;
    if (Math.abs(end[0] - x0) < CLICK_SLOP && Math.abs(end[1] - y0) < CLICK_SLOP) {
      const [w, h] = CLICK_PATCH;
      patch = [clamp(x0 - w / 2, 0, 1 - w), clamp(y0 - h / 2, 0, 1 - h), w, h];
    } else {
      patch = [Math.min(x0, end[0]), Math.min(y0, end[1]), Math.abs(end[0] - x0), Math.abs(end[1] - y0)];
    }
    showPatch([patch[0], patch[1]], [patch[0] + patch[2], patch[1] + patch[3]]);
    autofocus(patch);
  }
  drag = null;
});
canvas.addEventListener(
  "wheel",
  (event) => {
    event.preventDefault();
    zoom(Math.exp(event.deltaY * 0.001));
  },
  { passive: false },
);

function clamp(v, lo, hi) {
  return Math.min(Math.max(v, lo), hi);
}

function showPatch([x0, y0], [x1, y1]) {
  const box = $("patch-box");
  const w = canvas.clientWidth;
  const h = canvas.clientHeight;
  Object.assign(box.style, {
    left: `${Math.min(x0, x1) * w}px`,
    top: `${Math.min(y0, y1) * h}px`,
    width: `${Math.abs(x1 - x0) * w}px`,
    height: `${Math.abs(y1 - y0) * h}px`,
  });
  box.hidden = false;
}

function autofocus(patch) {
  post("/api/autofocus", { patch, metric: $("af-metric").value, strategy: $("af-strategy").value });
}

// Vector helpers on [x, y, z] arrays.
const sub = (a, b) => a.map((v, i) => v - b[i]);
const add = (a, b) => a.map((v, i) => v + b[i]);
const scale = (a, s) => a.map((v) => v * s);
const dot = (a, b) => a.reduce((s, v, i) => s + v * b[i], 0);
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const norm = (a) => scale(a, 1 / Math.hypot(...a));

/** `v` turned by `angle` radians about the unit `axis` (Rodrigues). */
function rotate(v, axis, angle) {
  const c = Math.cos(angle);
  const s = Math.sin(angle);
  return add(add(scale(v, c), scale(cross(axis, v), s)), scale(axis, dot(axis, v) * (1 - c)));
}

const ORBIT_RADIANS_PER_PIXEL = 0.005;

/** Turns the eye about the target: left-right about up, up-down about the camera's right. */
function orbit(dx, dy) {
  const { eye, target, up } = state.settings;
  const upAxis = norm(up);
  let offset = rotate(sub(eye, target), upAxis, -dx * ORBIT_RADIANS_PER_PIXEL);
  const right = norm(cross(scale(offset, -1), upAxis));
  const turned = rotate(offset, right, -dy * ORBIT_RADIANS_PER_PIXEL);
  // Stop short of looking straight along up, where the view would flip.
  if (Math.abs(dot(norm(turned), upAxis)) < 0.99) offset = turned;
  moveCamera(add(target, offset), target);
}

/** Moves the eye and the target together, by the image's width per its width in pixels. */
function pan(dx, dy) {
  const { eye, target, up } = state.settings;
  const forward = sub(target, eye);
  const right = norm(cross(forward, up));
  const trueUp = norm(cross(right, forward));
  const perPixel = Math.hypot(...forward) / canvas.clientWidth;
  const shift = add(scale(right, -dx * perPixel), scale(trueUp, dy * perPixel));
  moveCamera(add(eye, shift), add(target, shift));
}

/** Moves the eye toward the target (factor < 1) or away. */
function zoom(factor) {
  const { eye, target } = state.settings;
  moveCamera(add(target, scale(sub(eye, target), factor)), target);
}

function moveCamera(eye, target) {
  state.settings.eye = eye;
  state.settings.target = target;
  change({ eye, target });
}

// ---- The controls ----

$("lens").addEventListener("change", (e) => change({ lens: e.target.value }));
$("lens-path-form").addEventListener("submit", (e) => {
  e.preventDefault();
  change({ lens: $("lens-path").value.trim() });
});
const drop = $("lens-drop");
drop.addEventListener("dragover", (e) => {
  e.preventDefault();
  drop.classList.add("over");
});
drop.addEventListener("dragleave", () => drop.classList.remove("over"));
drop.addEventListener("drop", async (e) => {
  e.preventDefault();
  drop.classList.remove("over");
  const file = e.dataTransfer.files[0];
  if (!file) return;
  const answer = await post(`/api/lens?name=${encodeURIComponent(file.name)}`, await file.text(), "text/plain");
  if (answer) {
    showState(answer);
    change({ lens: file.name });
  }
});

$("fstop").addEventListener("input", (e) => {
  const k = Number(e.target.value);
  const n = fNumberAt(k);
  $("fstop-value").textContent = `f/${n.toFixed(1)}`;
  change({ f_number: k === 0 ? null : n });
});

function sendAperture() {
  const kind = $("aperture-kind").value;
  $("aperture-count").disabled = kind === "circle";
  change({ aperture: kind === "circle" ? "circle" : `${kind}:${$("aperture-count").value}` });
}
$("aperture-kind").addEventListener("change", sendAperture);
$("dispersion").addEventListener("change", (e) => change({ dispersion: e.target.checked }));
$("diffraction").addEventListener("change", (e) => change({ diffraction: e.target.checked }));
$("aperture-count").addEventListener("change", sendAperture);

$("sensor-depth").addEventListener("input", (e) => {
  const depth = Number(e.target.value);
  $("sensor-depth-value").textContent = `${depth.toFixed(3)} mm`;
  change({ focus: { by: "sensor", depth_mm: depth } });
});
$("focus-distance").addEventListener("change", (e) => {
  change({ focus: { by: "distance", distance_m: Number(e.target.value) } });
});
$("max-spp").addEventListener("change", (e) => change({ max_spp: Number(e.target.value) }));
$("integrator").addEventListener("change", (e) => change({ integrator: e.target.value }));
for (const id of ["sensor-on", ...SENSOR_CONTROLS]) $(id).addEventListener("change", sendSensor);

let initial = null;
$("reset-view").addEventListener("click", () => {
  if (initial) change({ eye: initial.eye, target: initial.target, up: initial.up });
});

document.addEventListener("keydown", (e) => {
  if (!state || e.target instanceof HTMLInputElement) return;
  const [lo, hi] = state.focus_range_mm;
  const stepMm = (hi - lo) / 200;
  const moves = { "[": -stepMm, "]": stepMm };
  if (e.key in moves) {
    const depth = clamp(state.sensor_depth_mm + moves[e.key], lo, hi);
    state.sensor_depth_mm = depth;
    change({ focus: { by: "sensor", depth_mm: depth } });
  }
});

const first = await fetch("/api/state").then((r) => r.json());
initial = { ...first.settings };
showState(first);
connect();
