// The experimenter's pages of `ehatp play`: the list of sessions, or one session as the
// experimenter sees it (the truth, the policy node, the human's worlds, the robot's
// hypotheses, the log). Data is inserted as text only (textContent).
"use strict";

function el(tag, cls, text) {
  const e = document.createElement(tag);
  if (cls) e.className = cls;
  if (text !== undefined && text !== null) e.textContent = String(text);
  return e;
}

function clear(node) { while (node.firstChild) node.removeChild(node.firstChild); }

const key = new URLSearchParams(location.search).get("key") || "";
const parts = location.pathname.split("/").filter(Boolean);
const sid = parts.length > 1 ? parts[1] : null;

function list(id, items, cls) {
  const ul = document.getElementById(id);
  clear(ul);
  for (const i of items) ul.appendChild(el("li", cls || "", i));
}

function dl(id, pairs) {
  const d = document.getElementById(id);
  clear(d);
  for (const [k, v] of pairs) { d.appendChild(el("dt", "", k)); d.appendChild(el("dd", "", v)); }
}

function draw(v) {
  document.getElementById("title").textContent = "Experimenter: " + v.problem + ", session " + v.session;
  document.getElementById("summary").textContent = "status " + v.status
    + (v.outcome ? " (" + v.outcome + ")" : "") + "; policy node " + v.node + "; "
    + v.policy.replans + " replan(s); to move: " + (v.to_move || "nobody");
  document.body.dataset.node = String(v.node);
  document.body.dataset.replans = String(v.policy.replans);
  document.body.dataset.status = v.status;
  list("truth", v.truth);
  dl("robot", [
    ["agenda", v.robot_agenda.join(", ") || "done"],
    ["next move", v.robot_next || "-"],
    ["hypotheses about the human", v.hypotheses.map(h => h.join(", ") || "done").join("  /  ")],
    ["co-present", v.copresent ? "yes" : "no"],
    ["K counter", v.k + " of " + v.K],
    ["policy", "cost " + v.policy.cost + ", " + v.policy.nodes + " nodes"],
  ]);
  const body = document.querySelector("#worlds tbody");
  clear(body);
  v.beliefs.worlds.forEach((w, i) => {
    const tr = el("tr");
    tr.appendChild(el("td", "", String(i + 1) + (w.true.length + w.false.length === 0 ? " (the truth)" : "")));
    tr.appendChild(el("td", "", w.true.join(", ")));
    tr.appendChild(el("td", "", w.false.join(", ")));
    tr.appendChild(el("td", "", w.robot_agenda.join(", ") || "done"));
    body.appendChild(tr);
  });
  list("moves", v.moves.map(m => m.label + (m.covered ? "" : "  (not covered: the robot replans)")
    + (m.fails ? "  (fails: a false belief)" : "")));
  list("participant-feed", v.participant.feed.map(f => f.text));
  list("history", v.history.map(h => h.agent + " " + h.move + "  -> node " + h.node
    + (h.opening ? "  (opening)" : "") + (h.replanned ? "  (REPLANNED)" : "")),
    "");
  document.getElementById("log").textContent = v.log.map(r => JSON.stringify(r)).join("\n");
  drawProfiles(v.profiles);
  document.body.dataset.ready = "true";
}

// A preferences problem: the profile followed, and the control that switches it (sent on the
// experimenter's socket as {"profile": NAME}; the server answers {"type": "switch", ...}).
function drawProfiles(p) {
  const pane = document.getElementById("profile-pane");
  pane.hidden = !p;
  if (!p) return;
  document.getElementById("profile-current").textContent = p.current;
  document.getElementById("profile-queued").textContent = p.queued
    ? " (switching to " + p.queued + " when this step ends)" : "";
  document.body.dataset.profile = p.current;
  const select = document.getElementById("profile-choice");
  if (select.options.length !== p.names.length) {
    clear(select);
    for (const n of p.names) { const o = el("option", "", n); o.value = n; select.appendChild(o); }
  }
  document.getElementById("profile-switch").disabled = !p.can_switch;
}

let socket = null;

function switchProfile() {
  const name = document.getElementById("profile-choice").value;
  if (socket && name) socket.send(JSON.stringify({ profile: name }));
}

function session() {
  for (const id of ["truth-pane", "worlds-pane", "log-pane"]) document.getElementById(id).hidden = false;
  const scheme = location.protocol === "https:" ? "wss://" : "ws://";
  const ws = new WebSocket(scheme + location.host + "/ws/" + encodeURIComponent(sid)
    + "/experimenter?key=" + encodeURIComponent(key));
  socket = ws;
  ws.addEventListener("message", ev => {
    const msg = JSON.parse(ev.data);
    if (msg.type === "experimenter") draw(msg.view);
    else if (msg.type === "switch") {
      document.getElementById("profile-result").textContent = msg.result === "refused"
        ? "Refused: " + msg.reason
        : msg.result === "queued" ? "Queued: the switch is made when this step ends."
        : "Switched: the robot now follows " + msg.profile + ".";
      document.body.dataset.switch = msg.result;
    } else if (msg.type === "error") {
      document.getElementById("profile-result").textContent = msg.message;
    }
  });
  ws.addEventListener("close", () => { setTimeout(session, 1000); });
}

async function sessions() {
  document.getElementById("sessions-pane").hidden = false;
  const r = await fetch("/api/sessions?key=" + encodeURIComponent(key));
  const data = await r.json();
  const body = document.querySelector("#sessions tbody");
  clear(body);
  for (const s of data.sessions) {
    const tr = el("tr");
    const td = el("td");
    const a = el("a", "", s.session);
    a.href = "/experimenter/" + encodeURIComponent(s.session) + "?key=" + encodeURIComponent(key);
    td.appendChild(a);
    tr.appendChild(td);
    tr.appendChild(el("td", "", s.status + (s.outcome ? " (" + s.outcome + ")" : "")));
    tr.appendChild(el("td", "", s.steps));
    tr.appendChild(el("td", "", s.replans));
    tr.appendChild(el("td", "", s.open));
    body.appendChild(tr);
  }
  document.body.dataset.ready = "true";
  setTimeout(sessions, 2000);
}

document.getElementById("profile-switch").addEventListener("click", switchProfile);
if (sid) session(); else sessions();
