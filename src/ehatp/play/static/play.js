// The participant's page of `ehatp play`: it draws the view the server sends over the
// WebSocket (the human's perspective only) and sends the participant's moves. Every piece of
// data is inserted as text (textContent), never as markup.
"use strict";

const KINDS = new Set(["table", "box", "hand", "place", "pan", "dish", "cube", "agent",
  "ingredient", "state", "you", "robot", "hidden", "speech", "answer", "question", "end",
  "action", "ask", "pass", "answer"]);

function el(tag, cls, text) {
  const e = document.createElement(tag);
  if (cls) for (const c of cls.split(" ")) if (c) e.classList.add(c);
  if (text !== undefined && text !== null) e.textContent = String(text);
  return e;
}

function kind(k) { return KINDS.has(k) ? "k-" + k : "k-other"; }

function clear(node) { while (node.firstChild) node.removeChild(node.firstChild); }

function facts(container, groups, status) {
  clear(container);
  for (const g of groups) {
    const row = el("div", "group");
    row.appendChild(el("span", "predicate", g.predicate));
    const list = el("ul", "facts");
    for (const f of g.facts) {
      const li = el("li", "fact " + status + (f.seen ? " seen" : ""), f.text);
      li.dataset.fact = f.text;
      li.dataset.status = f.seen ? "seen" : status;
      if (f.seen) li.appendChild(el("span", "seen-mark", "seen"));
      list.appendChild(li);
    }
    row.appendChild(list);
    container.appendChild(row);
  }
}

function unsure(container, items) {
  clear(container);
  const list = el("ul", "facts");
  for (const u of items) {
    const li = el("li", "fact unsure");
    li.dataset.fact = u.name;
    li.dataset.status = "unsure";
    li.appendChild(el("span", "unsure-mark", "?"));
    li.appendChild(el("span", "unsure-text", u.options.length === 2 && u.options[1] === "not " + u.options[0]
      ? u.name : u.options.join(" or ")));
    list.appendChild(li);
  }
  container.appendChild(list);
}

function scene(view) {
  const pane = document.getElementById("scene-pane");
  const box = document.getElementById("scene");
  clear(box);
  if (!view.scene) { pane.hidden = true; return; }
  pane.hidden = false;
  for (const a of view.scene.areas) {
    const area = el("div", "area " + kind(a.kind));
    area.appendChild(el("div", "area-title", a.title));
    const items = el("div", "items");
    for (const i of a.items) {
      const token = el("span", "item " + kind(i.kind) + (i.unsure ? " unsure" : ""), i.text);
      token.dataset.item = i.text;
      items.appendChild(token);
    }
    area.appendChild(items);
    box.appendChild(area);
  }
}

let socket = null;

function send(label) {
  if (socket && socket.readyState === WebSocket.OPEN) {
    stopTimer();
    for (const b of document.querySelectorAll("#moves button")) b.disabled = true;
    socket.send(JSON.stringify({move: label}));
  }
}

const STATUS = {
  "your-turn": "Your turn: choose a move.",
  "robot-turn": "The robot is acting…",
  "goal": "Done: the task is complete. Thank you!",
  "over": "The session is over. Thank you!",
};

// Joint steps: the decision's timer. When it runs out the page tells the server, which plays
// "pass" for the decision it started at (a late message for an older decision is ignored).
let timer = null;

function stopTimer() {
  if (timer !== null) { clearInterval(timer); timer = null; }
}

let timerStep = null;

function startTimer(view) {
  const box = document.getElementById("timer");
  const timed = Boolean(view.timer) && view.status === "your-turn";
  if (timed && timer !== null && timerStep === view.step) return;  // the same decision
  stopTimer();
  box.hidden = !timed;
  if (!timed) return;
  timerStep = view.step;
  const end = Date.now() + view.timer * 1000;
  const step = view.step;
  const tick = () => {
    const left = Math.max(0, Math.ceil((end - Date.now()) / 1000));
    box.textContent = "Time to decide: " + left + " s (then you wait this step)";
    box.dataset.left = String(left);
    if (Date.now() >= end) {
      stopTimer();
      if (socket && socket.readyState === WebSocket.OPEN) {
        for (const b of document.querySelectorAll("#moves button")) b.disabled = true;
        socket.send(JSON.stringify({timeout: step}));
      }
    }
  };
  tick();
  timer = setInterval(tick, 200);
}

function draw(view) {
  document.getElementById("who").textContent = "You are " + view.you;
  document.getElementById("task").textContent = "Your task: " + view.task.join(", ");
  document.getElementById("status").textContent = STATUS[view.status] || "";
  document.getElementById("presence").textContent = view.robot_here
    ? view.robot + " is here with you." : view.robot + " is out of sight.";
  document.body.dataset.status = view.status;
  document.body.dataset.step = String(view.step);
  document.body.dataset.robotHere = String(view.robot_here);
  scene(view);
  facts(document.getElementById("believed"), view.believed, "believed");
  unsure(document.getElementById("unsure"), view.unsure);
  document.getElementById("unsure-title").hidden = view.unsure.length === 0;
  facts(document.getElementById("fixed"), view.fixed, "fixed");
  document.getElementById("fixed-title").hidden = view.fixed.length === 0;
  const tasks = view.robot_tasks.map(t => t.join(", ") || "nothing more");
  document.getElementById("robot-tasks").textContent = tasks.length === 1
    ? "You think " + view.robot + " still has to do: " + tasks[0]
    : "You are not sure what " + view.robot + " still has to do: " + tasks.join(" or ");
  const moves = document.getElementById("moves");
  clear(moves);
  for (const m of view.moves) {
    const b = el("button", "move " + kind(m.kind), m.text);
    b.type = "button";
    b.dataset.move = m.label;
    b.addEventListener("click", () => send(m.label));
    moves.appendChild(b);
  }
  if (view.moves.length === 0) moves.appendChild(el("p", "none", STATUS[view.status] || ""));
  const signal = document.getElementById("signal");
  signal.hidden = !view.signal;
  signal.textContent = view.signal ? view.robot + " signals: " + view.signal.text : "";
  signal.dataset.signal = view.signal ? view.signal.key : "";
  startTimer(view);
  const feed = document.getElementById("feed");
  clear(feed);
  for (const f of view.feed) {
    const li = el("li", "entry " + kind(f.kind), f.text);
    li.dataset.kind = f.kind;
    feed.appendChild(li);
  }
  feed.scrollTop = feed.scrollHeight;
  document.body.dataset.ready = "true";
}

function connect(attempt) {
  const sid = location.pathname.split("/").pop();
  const scheme = location.protocol === "https:" ? "wss://" : "ws://";
  socket = new WebSocket(scheme + location.host + "/ws/" + encodeURIComponent(sid));
  socket.addEventListener("message", ev => {
    const msg = JSON.parse(ev.data);
    if (msg.type === "view") draw(msg.view);
  });
  socket.addEventListener("open", () => { attempt = 0; });
  socket.addEventListener("close", () => {
    document.body.dataset.ready = "false";
    if (document.body.dataset.status === "goal" || document.body.dataset.status === "over") return;
    document.getElementById("status").textContent = "Connection lost; reconnecting…";
    setTimeout(() => connect(attempt + 1), Math.min(5000, 250 * 2 ** attempt));
  });
}

connect(0);
