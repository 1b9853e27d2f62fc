// stvm HMI page script: live values over a WebSocket, writes over HTTP (docs/hmi.md).
// The server renders the widgets; this file only fills them in and sends what the operator does.
"use strict";

const pageName = document.body.dataset.page;
const current = {};                       // path -> value as the server shows it
const byPath = new Map();                 // path -> elements showing it
for (const el of document.querySelectorAll("[data-var]")) {
  const list = byPath.get(el.dataset.var) || [];
  list.push(el);
  byPath.set(el.dataset.var, list);
}

// ---- messages (a refused write says why, on the page)
const message = document.getElementById("hmi-message");
function say(text, isError) {
  message.textContent = text;
  message.dataset.state = isError ? "error" : "ok";
  message.hidden = !text;
}

// ---- writes
function stringLiteral(text) {            // ST string literal: $ and ' are escaped with $
  return "'" + text.replace(/\$/g, "$$$$").replace(/'/g, "$$'") + "'";
}

async function post(url, body) {
  const response = await fetch(url, {method: "POST", headers: {"Content-Type": "application/json"},
                                     body: JSON.stringify(body), credentials: "same-origin"});
  let reply = {};
  try { reply = await response.json(); } catch (e) { /* not JSON: use the status text */ }
  if (!response.ok) {
    say(reply.error || `${response.status} ${response.statusText}`, true);
    throw new Error(reply.error || response.statusText);
  }
  say("", false);
  return reply;
}
const write = (values) => post("/api/vars", values);

function literalOf(el) {
  if (el.dataset.kind === "text") return stringLiteral(el.value);
  return el.value.trim();                 // numbers as typed; drop-downs hold the literal
}

// ---- showing values
function show(path, value) {
  current[path] = value;
  for (const el of byPath.get(path) || []) {
    if (el.classList.contains("lamp")) {
      el.dataset.state = value ? "on" : "off";
    } else if (el.tagName === "BUTTON") {
      el.dataset.state = value ? "on" : "off";
      if (el.classList.contains("toggle")) el.dataset.action = `set:${path}=${value ? "FALSE" : "TRUE"}`;
    } else if (el.tagName === "SELECT") {
      el.value = typeof value === "boolean" ? (value ? "TRUE" : "FALSE") : String(value);
    } else if (!(el === document.activeElement && el.dataset.dirty)) {
      el.value = value === null ? "" : String(value);    // never overwrite what is being typed
    }
  }
}

for (const el of document.querySelectorAll("input[data-var]:not([readonly]), select[data-var]")) {
  el.addEventListener("input", () => { el.dataset.dirty = "1"; });
  el.addEventListener("change", async () => {
    const path = el.dataset.var;
    try {
      await write({[path]: literalOf(el)});
    } catch (e) {
      delete el.dataset.dirty;
      show(path, current[path]);          // refused: back to what the VM holds
      return;
    }
    delete el.dataset.dirty;
  });
}

// ---- buttons: data-action says what they do
async function act(action, el) {
  const [kind, rest] = [action.slice(0, action.indexOf(":")), action.slice(action.indexOf(":") + 1)];
  if (action === "close") { el.closest("dialog").close(); return; }
  if (kind === "set") {
    const eq = rest.indexOf("=");
    await write({[rest.slice(0, eq)]: rest.slice(eq + 1)});
  } else if (kind === "preset") {
    await post(`/api/presets/${encodeURIComponent(rest)}`, {});
  } else if (kind === "page") {
    window.location.href = `/page/${encodeURIComponent(rest)}`;
  } else if (kind === "popup") {
    const dialog = document.getElementById(`popup-${rest}`);
    dialog.showModal();
    tell({popup: rest});                  // the server now sends this pop-up's fields too
    dialog.addEventListener("close", () => tell({popup: null}), {once: true});
  }
}

document.addEventListener("click", (event) => {
  const el = event.target.closest("[data-action]");
  if (!el || el.dataset.action.startsWith("momentary:")) return;
  act(el.dataset.action, el).catch(() => { /* the message line shows why */ });
});

// momentary: TRUE while pressed; the release is sent once the press was applied, so the
// program sees TRUE in at least one scan however short the click
for (const el of document.querySelectorAll("[data-action^='momentary:']")) {
  const path = el.dataset.action.slice("momentary:".length);
  let pressed = null;
  const release = () => {
    if (!pressed) return;
    const done = pressed;
    pressed = null;
    done.catch(() => {}).finally(() => write({[path]: "FALSE"}).catch(() => {}));
  };
  el.addEventListener("pointerdown", () => { if (!pressed) pressed = write({[path]: "TRUE"}); });
  el.addEventListener("pointerup", release);
  el.addEventListener("pointerleave", release);
  el.addEventListener("pointercancel", release);
  el.addEventListener("click", (event) => {           // keyboard: Enter / Space
    if (event.detail === 0 && !pressed) { pressed = write({[path]: "TRUE"}); release(); }
  });
}

// ---- robot view: top (X-Y) and side (X-Z) projections of the TCP path and the targets
const views = [...document.querySelectorAll("[data-robot-view]")].map((figure) => ({
  figure,
  history: parseFloat(figure.dataset.historyS),
  ranges: JSON.parse(figure.dataset.ranges),
  targets: JSON.parse(figure.dataset.targets),
  points: [],
}));
const SVG = "http://www.w3.org/2000/svg";

function toView(view, axes, p) {           // mm -> viewBox coordinates: y up, equal scale, centred
  const [a, b] = axes;
  const [a0, a1] = view.ranges[a], [b0, b1] = view.ranges[b];
  const scale = Math.min(300 / (a1 - a0), 200 / (b1 - b0));
  return [160 + (p[a] - (a0 + a1) / 2) * scale, 130 - (p[b] - (b0 + b1) / 2) * scale];
}

function drawTargets(view) {
  for (const svg of view.figure.querySelectorAll("svg")) {
    const axes = svg.dataset.axes.split(",").map(Number);
    const group = svg.querySelector(".targets");
    group.replaceChildren();
    view.targets.forEach((target, i) => {
      const p = ["X", "Y", "Z"].map((axis) => parseFloat(current[`${target}.${axis}`]));
      if (p.some(Number.isNaN)) return;
      const [x, y] = toView(view, axes, p);
      const mark = document.createElementNS(SVG, "g");
      mark.setAttribute("class", "target");
      mark.dataset.target = String(i);
      mark.dataset.mm = p.join(",");
      mark.innerHTML = `<rect x="${x - 4}" y="${y - 4}" width="8" height="8"></rect>` +
                       `<text x="${x + 6}" y="${y - 6}">${i + 1}</text>`;
      group.appendChild(mark);
    });
  }
}

function drawRobot(view, robot, t) {
  if (robot.reset) view.points = [];
  view.points.push(...robot.points);
  view.points = view.points.filter((p) => p[0] >= t - view.history);
  const tcp = robot.pose.slice(0, 3);
  for (const svg of view.figure.querySelectorAll("svg")) {
    const axes = svg.dataset.axes.split(",").map(Number);
    svg.querySelector(".path").setAttribute("points",
      view.points.map((p) => toView(view, axes, p.slice(1)).map((v) => v.toFixed(1)).join(",")).join(" "));
    const [x, y] = toView(view, axes, tcp);
    const dot = svg.querySelector(".tcp");
    dot.setAttribute("cx", x.toFixed(1));
    dot.setAttribute("cy", y.toFixed(1));
  }
  const state = robot.paused ? "paused" : robot.moving ? "moving" : "still";
  Object.assign(view.figure.dataset, {tcp: tcp.map((v) => v.toFixed(1)).join(","),
                                      points: String(view.points.length), robotState: state});
  view.figure.querySelector(".tcp-text").value =
    `X ${tcp[0].toFixed(1)}  Y ${tcp[1].toFixed(1)}  Z ${tcp[2].toFixed(1)} mm · ${state} · ${robot.state}`;
}

// ---- the live connection
let socket = null;
const tell = (message) => { if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify(message)); };
const live = document.getElementById("hmi-live");
const clock = document.getElementById("hmi-clock");
function connect() {
  const scheme = window.location.protocol === "https:" ? "wss" : "ws";
  socket = new WebSocket(`${scheme}://${window.location.host}/ws?page=${encodeURIComponent(pageName)}`);
  socket.onopen = () => {
    live.dataset.state = "on";
    const open = document.querySelector("dialog[open]");
    if (open) tell({popup: open.dataset.popup});
  };
  socket.onclose = () => { live.dataset.state = "off"; setTimeout(connect, 1000); };
  socket.onmessage = (event) => {
    const update = JSON.parse(event.data);
    for (const [path, value] of Object.entries(update.values)) show(path, value);
    clock.textContent = `scan ${update.scan} · t = ${update.t.toFixed(3)} s`;
    for (const view of views) {
      drawTargets(view);
      if (update.robot) drawRobot(view, update.robot, update.t);
    }
  };
}
connect();
