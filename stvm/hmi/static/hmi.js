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
function say(text, isError, kind) {
  message.textContent = text;
  message.dataset.state = kind || (isError ? "error" : "ok");
  message.hidden = !text;
}

// ---- liveness: every live value and command is greyed out while the page is not live
const clientId = Math.random().toString(36).slice(2, 12);
const banner = document.getElementById("hmi-banner");
let isLive = false;
let offlineReason = "";
const clockText = () => new Date().toTimeString().slice(0, 8);
function setLive(on, reason, since) {
  if (on === isLive && (on || reason === offlineReason)) return;
  isLive = on;
  document.body.dataset.live = on ? "on" : "off";
  live.dataset.state = on ? "on" : "off";
  for (const el of document.querySelectorAll("[data-var], [data-action]")) {
    if (el.hasAttribute("data-always") || el.dataset.action === "close" ||
        (el.dataset.action || "").startsWith("page:")) continue;
    el.disabled = !on;
  }
  if (on) {
    banner.hidden = true;
    if (message.dataset.state === "offline") say("", false);
  } else {
    offlineReason = reason;
    banner.textContent = `NOT LIVE since ${since || clockText()}: ${reason}. Values shown are old; commands are disabled.`;
    banner.hidden = false;
  }
}

// ---- writes
function stringLiteral(text) {            // ST string literal: $ and ' are escaped with $
  return "'" + text.replace(/\$/g, "$$$$").replace(/'/g, "$$'") + "'";
}

async function post(url, body) {
  if (!isLive && !url.startsWith("/api/alarms")) {
    const text = `Not sent: the page is not live (${offlineReason}).`;
    say(text, true, "offline");
    throw new Error(text);
  }
  let response;
  try {
    response = await fetch(url, {method: "POST", headers: {"Content-Type": "application/json", "X-Hmi-Client": clientId},
                                 body: JSON.stringify(body), credentials: "same-origin"});
  } catch (e) {
    const text = `Not delivered: the HMI server cannot be reached (${clockText()}). Nothing was written.`;
    say(text, true, "offline");
    throw new Error(text);
  }
  let reply = {};
  try { reply = await response.json(); } catch (e) { /* not JSON: use the status text */ }
  if (!response.ok) {
    say(reply.error || `${response.status} ${response.statusText}`, true);
    throw new Error(reply.error || response.statusText);
  }
  if (reply.queued) say("Sent, but the VM has not scanned yet: it applies at the next scan.", false, "notice");
  else say("", false);
  return reply;
}
const write = (values) => post("/api/vars", values);

// ---- operator input: a number as typed (point or comma), a text within its length
const DECIMAL = /^[+-]?(\d+([.,]\d*)?|[.,]\d+)([eE][+-]?\d+)?$/;
class Refusal extends Error {}
function literalOf(el) {
  const label = el.dataset.label || el.dataset.var;
  if (el.dataset.kind === "text") {
    const bytes = new TextEncoder().encode(el.value).length;
    const max = parseInt(el.dataset.maxbytes, 10);
    if (bytes > max) throw new Refusal(`${label}: text too long (${bytes} characters; at most ${max})`);
    return stringLiteral(el.value);
  }
  if (el.dataset.kind === "numeric") {
    const typed = el.value.trim();
    if (!typed) throw new Refusal(`${label}: nothing entered`);
    if (!DECIMAL.test(typed)) {
      throw new Refusal(`${label}: '${typed}' is not a number (digits with one decimal point or comma, e.g. 350.5)`);
    }
    const text = typed.replace(",", ".");
    const number = Number(text);
    if (!Number.isFinite(number)) throw new Refusal(`${label}: '${typed}' is not a number`);
    if (el.dataset.int === "1" && !Number.isInteger(number)) throw new Refusal(`${label}: ${typed} is not a whole number`);
    const unit = el.parentElement.querySelector(".unit").textContent;
    const u = unit ? ` ${unit}` : "";
    if (el.dataset.min !== undefined && number < Number(el.dataset.min)) {
      throw new Refusal(`${label}: ${typed} is below the minimum ${el.dataset.min}${u}`);
    }
    if (el.dataset.max !== undefined && number > Number(el.dataset.max)) {
      throw new Refusal(`${label}: ${typed} is above the maximum ${el.dataset.max}${u}`);
    }
    return el.dataset.int === "1" ? String(number) : text;
  }
  return el.value.trim();                 // drop-downs hold the literal
}

// ---- showing values in operator form
function formatted(el, value) {
  if (value === null || value === undefined) return "";
  if (typeof value === "number" && el.dataset.decimals !== undefined) {
    return value.toFixed(parseInt(el.dataset.decimals, 10));
  }
  return String(value);
}

function show(path, value) {
  current[path] = value;
  for (const el of byPath.get(path) || []) {
    if (el.classList.contains("lamp")) {
      el.dataset.state = value ? "on" : "off";
    } else if (el.tagName === "BUTTON") {
      el.dataset.state = value ? "on" : "off";
      if (el.classList.contains("toggle")) el.dataset.action = `set:${path}=${value ? "FALSE" : "TRUE"}`;
    } else if (el.tagName === "SELECT") {
      const wanted = typeof value === "boolean" ? (value ? "TRUE" : "FALSE") : String(value);
      let option = [...el.options].find((o) => o.value === wanted);
      for (const stale of el.querySelectorAll("option[data-unknown]")) if (stale !== option) stale.remove();
      if (!option) {                       // a value that is none of the choices: shown, marked
        option = new Option(`${wanted} (not a choice)`, wanted);
        option.dataset.unknown = "1";
        option.disabled = true;
        el.add(option);
      }
      el.value = wanted;
      el.dataset.unknown = option.dataset.unknown ? "1" : "";
    } else if (!(el === document.activeElement && el.dataset.dirty)) {
      el.value = formatted(el, value);    // never overwrite what is being typed
      if (el.readOnly) el.title = el.value;
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
      if (e instanceof Refusal) say(e.message, true);
      delete el.dataset.dirty;
      show(path, current[path]);          // refused: back to what the VM holds
      el.dataset.refused = "1";
      setTimeout(() => { delete el.dataset.refused; }, 1500);
      return;
    }
    delete el.dataset.dirty;
    show(path, current[path]);            // the VM's value in operator form (its update may follow)
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
  } else if (kind === "ack") {
    await post(`/api/alarms/${encodeURIComponent(rest)}/ack`, {});
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
  const tab = event.target.closest("[data-tab-index]");
  if (tab) { selectTab(tab.dataset.tabIndex); return; }
  const el = event.target.closest("[data-action]");
  if (!el || el.disabled || el.dataset.action.startsWith("momentary:")) return;
  act(el.dataset.action, el).catch((e) => {   // post() already says why; anything else is said here
    if (message.hidden) say(`Not done: ${e.message}`, true);
  });
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
    done.then(() => write({[path]: "FALSE"}), () => { /* the press failed: post() said why */ })
        .catch(() => say(`${el.textContent}: the release was not delivered; ${path} may still be TRUE`, true));
  };
  el.addEventListener("pointerdown", () => { if (!pressed && !el.disabled) pressed = write({[path]: "TRUE"}); });
  el.addEventListener("pointerup", release);
  el.addEventListener("pointerleave", release);
  el.addEventListener("pointercancel", release);
  el.addEventListener("click", (event) => {           // keyboard: Enter / Space
    if (event.detail === 0 && !pressed && !el.disabled) { pressed = write({[path]: "TRUE"}); release(); }
  });
}

// ---- tabs: on a small panel one parameter group at a time, the commands always in view
const panel = document.querySelector("main.panel");
function selectTab(index) {
  if (!panel) return;
  panel.dataset.tab = String(index);
  for (const area of panel.querySelectorAll("[data-area-index]")) {
    area.classList.toggle("current", area.dataset.areaIndex === String(index));
  }
  for (const tab of panel.querySelectorAll("[data-tab-index]")) {
    tab.classList.toggle("current", tab.dataset.tabIndex === String(index));
  }
}
selectTab(0);

// ---- alarms: a banner on every page, the list on /alarms
const alarmBanner = document.getElementById("hmi-alarm-banner");
const alarmCount = document.getElementById("hmi-alarm-count");
const alarmTable = document.querySelector("#hmi-alarm-list tbody");
function showAlarms(alarms) {
  const open = alarms.current.filter((a) => !a.acknowledged);
  alarmCount.dataset.count = String(alarms.current.length);
  alarmCount.textContent = `Alarms ${alarms.current.length}`;
  const newest = open[0] || alarms.current.find((a) => a.active);
  if (newest && !alarmTable) {
    alarmBanner.replaceChildren();
    const text = document.createElement("a");
    text.href = "/alarms";
    text.textContent = `${newest.active ? "ALARM" : "Returned"} ${newest.time} ${newest.source}` +
      `${newest.code_text ? " " + newest.code_text : ""}: ${newest.text || "error"}` +
      (open.length > 1 ? ` (+${open.length - 1} more unacknowledged)` : "");
    alarmBanner.appendChild(text);
    alarmBanner.dataset.state = newest.active ? "active" : "returned";
    alarmBanner.hidden = false;
  } else {
    alarmBanner.hidden = true;
  }
  if (!alarmTable) return;
  alarmTable.replaceChildren();
  for (const a of alarms.current) {
    const row = document.createElement("tr");
    row.dataset.alarm = String(a.id);
    row.dataset.active = a.active ? "1" : "0";
    row.dataset.acknowledged = a.acknowledged ? "1" : "0";
    for (const text of [a.time, a.source, a.code_text, a.text,
                        `${a.active ? "active" : "returned"}${a.acknowledged ? ", acknowledged" : ""}`]) {
      const cell = document.createElement("td");
      cell.textContent = text;
      row.appendChild(cell);
    }
    const cell = document.createElement("td");
    if (!a.acknowledged) {
      const button = document.createElement("button");
      button.type = "button";
      button.className = "set";
      button.dataset.action = `ack:${a.id}`;
      button.textContent = "Acknowledge";
      cell.appendChild(button);
    }
    row.appendChild(cell);
    alarmTable.appendChild(row);
  }
  document.getElementById("hmi-no-alarms").hidden = alarms.current.length > 0;
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
setTimeout(() => views.forEach(drawGrid), 0);

function toView(view, axes, p) {           // mm -> viewBox coordinates: y up, equal scale, centred
  const [a, b] = axes;
  const [a0, a1] = view.ranges[a], [b0, b1] = view.ranges[b];
  const scale = Math.min(300 / (a1 - a0), 200 / (b1 - b0));
  return [160 + (p[a] - (a0 + a1) / 2) * scale, 130 - (p[b] - (b0 + b1) / 2) * scale];
}

// axes with a scale: a grid line and its value every 50/100/200 mm, drawn once per projection
function drawGrid(view) {
  for (const svg of view.figure.querySelectorAll("svg")) {
    const axes = svg.dataset.axes.split(",").map(Number);
    const group = svg.querySelector(".grid");
    const parts = [];
    axes.forEach((axis, k) => {
      const [lo, hi] = view.ranges[axis];
      const step = (hi - lo) > 1200 ? 200 : (hi - lo) > 500 ? 100 : 50;
      for (let mm = Math.ceil(lo / step) * step; mm <= hi; mm += step) {
        const p = [0, 0, 0];
        p[axes[0]] = k === 0 ? mm : view.ranges[axes[0]][0];
        p[axes[1]] = k === 1 ? mm : view.ranges[axes[1]][0];
        const [x, y] = toView(view, axes, p);
        parts.push(k === 0 ? `<line x1="${x.toFixed(1)}" y1="20" x2="${x.toFixed(1)}" y2="232"></line><text x="${(x + 2).toFixed(1)}" y="236">${mm}</text>`
                           : `<line x1="8" y1="${y.toFixed(1)}" x2="312" y2="${y.toFixed(1)}"></line><text x="2" y="${(y - 2).toFixed(1)}">${mm}</text>`);
      }
    });
    group.innerHTML = parts.join("");
  }
}

function drawTargets(view) {
  for (const svg of view.figure.querySelectorAll("svg")) {
    const axes = svg.dataset.axes.split(",").map(Number);
    const group = svg.querySelector(".targets");
    group.replaceChildren();
    view.targets.forEach((target, i) => {
      const p = ["X", "Y", "Z"].map((axis) => parseFloat(current[`${target}.${axis}`]));
      if (p.some(Number.isNaN)) return;
      // a target outside the drawn range is pinned to the frame's edge and marked as such
      const outside = axes.some((a) => p[a] < view.ranges[a][0] || p[a] > view.ranges[a][1]);
      let [x, y] = toView(view, axes, p);
      x = Math.min(314, Math.max(6, x));
      y = Math.min(234, Math.max(20, y));
      const mark = document.createElementNS(SVG, "g");
      mark.setAttribute("class", outside ? "target outside" : "target");
      mark.dataset.target = String(i);
      mark.dataset.mm = p.join(",");
      if (outside) mark.dataset.outside = "1";
      // labels alternate above/below so neighbouring targets do not overlap
      const dy = i % 2 ? 14 : -6;
      mark.innerHTML = `<rect x="${x - 4}" y="${y - 4}" width="8" height="8"></rect>` +
                       `<text x="${x + 6}" y="${y + dy}">${i + 1}${outside ? " out of view" : ""}</text>`;
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
let lastMessage = 0;
const tell = (message) => { if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify(message)); };
const live = document.getElementById("hmi-live");
const clock = document.getElementById("hmi-clock");
function connect() {
  const scheme = window.location.protocol === "https:" ? "wss" : "ws";
  const page = document.querySelector("#hmi-alarm-list") ? "@alarms" : pageName;
  socket = new WebSocket(`${scheme}://${window.location.host}/ws?page=${encodeURIComponent(page)}&client=${clientId}`);
  socket.onopen = () => {
    lastMessage = Date.now();
    const open = document.querySelector("dialog[open]");
    if (open) tell({popup: open.dataset.popup});
  };
  socket.onclose = () => {
    setLive(false, "the connection to the HMI server is lost (reconnecting)");
    setTimeout(connect, 1000);
  };
  socket.onmessage = (event) => {
    lastMessage = Date.now();
    const update = JSON.parse(event.data);
    for (const [path, value] of Object.entries(update.values)) show(path, value);
    if (update.vm) {
      if (update.vm.state === "running") setLive(true);
      else setLive(false, update.vm.reason || `the VM is ${update.vm.state}`, update.vm.since);
    }
    if (update.alarms) showAlarms(update.alarms);
    for (const notice of update.notices || []) say(notice, false, "notice");
    if (update.scan >= 0) clock.textContent = `scan ${update.scan} · t = ${update.t.toFixed(3)} s`;
    else if (update.vm && update.vm.scan !== undefined) clock.textContent = `scan ${update.vm.scan}`;
    for (const view of views) {
      drawTargets(view);
      if (update.robot) drawRobot(view, update.robot, update.t);
    }
  };
}
// the server sends the VM's state every 0.5 s: silence means the server or the network stopped
setInterval(() => {
  if (isLive && Date.now() - lastMessage > 2500) {
    setLive(false, "no data from the HMI server for 2.5 s");
  }
}, 500);
setLive(false, "connecting to the HMI server");
connect();
