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
  document.body.dataset.ready = "true";
}

function session() {
  for (const id of ["truth-pane", "worlds-pane", "log-pane"]) document.getElementById(id).hidden = false;
  const scheme = location.protocol === "https:" ? "wss://" : "ws://";
  const ws = new WebSocket(scheme + location.host + "/ws/" + encodeURIComponent(sid)
    + "/experimenter?key=" + encodeURIComponent(key));
  ws.addEventListener("message", ev => {
    const msg = JSON.parse(ev.data);
    if (msg.type === "experimenter") draw(msg.view);
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

if (sid) session(); else sessions();
