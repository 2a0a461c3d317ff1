/* ehatp policy explorer: the policy tree with pan/zoom and folding, a node's worlds, and a
 * branch as a timeline. Plain JS with no dependencies: the page must work offline from one
 * file, and a tidy layout plus viewBox pan/zoom is too little code to justify a library.
 *
 * This is the part both pages share (render.py puts it first in the page's one script). The
 * page's own script then calls ehatpExplorer with a function that builds its *model* of the
 * policy from the shared pieces:
 *   explorer-eager.js   a version 2 graph embedded whole: every tree item made at once, a
 *                       node drawn at its first path and referenced at the others;
 *   explorer-lifted.js  a lifted policy (format version 3): items realised through the
 *                       renamings when their parent is unfolded.
 * The model answers what the two pages do differently (docs/rendering.md): how items are
 * made, how a node is named and linked, the URL fragment, the counts and the branch list. */
function ehatpExplorer(pageModel) {
  "use strict";

  const $ = (id) => document.getElementById(id);
  const policy = JSON.parse($("policy-data").textContent);
  const config = JSON.parse($("explorer-config").textContent);
  const nodes = policy.nodes; // a graph: nodes[i].moves[j] = {agent, action, cost, kind, to, ...}
  const ROBOT = policy.agents.robot;
  const HUMAN = policy.agents.human;
  const COMM = new Set(["inform", "ask"]);
  const IDLE = new Set(["wait", "pass"]);
  const STATIC = config.staticFacts || []; // given with the problem (render --problem)

  // box size and grid step of the tree drawing (SVG user units); the drawing opens at a scale
  // of at least MIN_SCALE screen pixels per unit, so the smallest text (11 units) reads >= 11 px
  // and at most SCREENS pane widths wide (the rest starts folded)
  const W = 160, H = 40, DX = 176, DY = 74, MIN_SCALE = 1, SCREENS = 3;

  // The tree is drawn as *items*, one per move along a path plus the root, which the model
  // makes: {node, view (the node as drawn), move (the move into it, null at the root),
  // parent, depth, width (how many children it has or will have: 0 for a leaf and for a
  // reference), kids (item indices; null until the model makes them), sibling, ref (a
  // reference: a dashed box leading to its node's first copy)}, plus the model's own fields.
  const items = [];
  const collapsed = new Set(); // item indices
  const width = (it) => items[it].width;
  let model = null;

  function kidsOf(it) {
    // the item's children, made by the model the first time they are asked for
    const item = items[it];
    if (!item.kids) {
      item.kids = model.makeKids(it);
      tellApart(item.kids);
    }
    return item.kids;
  }

  // sibling moves with the same label (agent and action) cannot be told apart by it: each gets
  // its number among them and what its next node differs by (the literals told, the human's
  // agendas, the robot's, the facts true there and not at every sibling's)
  function differs(group) {
    const told = group.map((x) => (items[x].move.told || []).join(", "));
    if (new Set(told).size > 1) return told.map((t) => (t ? `says ${t}` : "says nothing"));
    const next = group.map((x) => items[x].view);
    const agendas = (n) => (n.hypotheses && n.hypotheses.length > 1 ? n.hypotheses : [n.human_agenda])
      .map((a) => a.join(", ") || "nothing").join(" | ");
    const human = next.map(agendas);
    if (new Set(human).size > 1) return human.map((a) => `human: ${a}`);
    const robot = next.map((n) => n.robot_agenda.join(", ") || "nothing");
    if (new Set(robot).size > 1) return robot.map((a) => `robot: ${a}`);
    const common = next.map((n) => new Set(n.state)).reduce((a, b) => new Set([...a].filter((x) => b.has(x))));
    const every = new Set(next.flatMap((n) => n.state));
    return next.map((n) => {
      const mine = new Set(n.state);
      const plus = n.state.filter((a) => !common.has(a));
      const minus = [...every].filter((a) => !mine.has(a)).sort().map((a) => `not ${a}`);
      const facts = [...plus, ...minus];
      return facts.length ? facts.slice(0, 3).join(", ") + (facts.length > 3 ? ", …" : "")
        : `→ node ${model.nodeId(n)}`;
    });
  }
  function tellApart(kids) {
    // the siblings of one item: numbered, and told apart, where their labels are the same
    const groups = new Map();
    for (const x of kids) {
      const m = items[x].move;
      const key = `${m.agent}\u0000${m.action}`;
      if (!groups.has(key)) groups.set(key, []);
      groups.get(key).push(x);
    }
    for (const group of groups.values()) {
      if (group.length < 2) continue;
      const what = differs(group);
      group.forEach((x, i) => { items[x].sibling = { k: i + 1, n: group.length, what: what[i] }; });
    }
  }

  const svg = $("tree");
  const NS = svg.namespaceURI; // taken from the parsed page, so no namespace URL in the source
  const gEdges = $("edges");
  const gNodes = $("nodes");

  let selected = null; // item index
  let pos = new Map(); // item index -> {x, y}
  let visibleCount = 0;
  let expandNote = ""; // set when "expand all" stops at the model's budget
  let vb = { x: 0, y: 0, w: 1000, h: 600 };

  function el(tag, attrs, parent, text) {
    const e = document.createElementNS(NS, tag);
    for (const k in attrs) e.setAttribute(k, attrs[k]);
    if (text !== undefined) e.textContent = text;
    if (parent) parent.appendChild(e);
    return e;
  }

  function h(tag, attrs, text) {
    const e = document.createElement(tag);
    for (const k in attrs || {}) e.setAttribute(k, attrs[k]);
    if (text !== undefined) e.textContent = text;
    return e;
  }

  const plural = (n, word) => `${n} ${word}${n === 1 ? "" : "s"}`;
  const count = (x) => x.toLocaleString("en-US");
  const siblingTag = (it) => {
    const s = items[it].sibling;
    return s ? ` (${s.k}/${s.n})` : "";
  };
  const label = (it) => {
    const m = items[it].move;
    return m ? `${m.agent}: ${m.action}${siblingTag(it)}` : "start";
  };
  const role = (agent) => (agent === ROBOT ? "robot" : agent === HUMAN ? "human" : "");
  const kindOf = (it) => (items[it].move ? items[it].move.kind : "start");
  const nodeOf = (it) => items[it].view;
  const shownLeaf = (it) => collapsed.has(it) || !width(it);
  const kText = (n) => `k=${n.k}/${policy.K}`; // unseen robot turns of the bound K
  // where a reference leads: its node's first copy
  const drawnAt = (it) => (items[it].ref ? model.first(items[it].node) : it);

  function kindClasses(it) {
    const c = ["node"];
    const m = items[it].move, n = nodeOf(it);
    if (!m) c.push("start");
    else c.push(role(m.agent));
    if (m && COMM.has(m.kind)) c.push("comm");
    if (m && IDLE.has(m.kind)) c.push("idle");
    if (items[it].ref) c.push("ref");
    if (n.goal) c.push("goal");
    if (!n.copresent) c.push("apart");
    if (n.worlds > 1) c.push("multi");
    return c;
  }

  // ------------------------------------------------------------------ folding and layout

  function initialFolding() {
    // fold below the depth cap, where the breadth-first budget runs out, and where the tree
    // would get wider than a few screens at the readable scale (a column per shown leaf);
    // what is not reached stays as the model made it (eager: unfolded, lifted: folded)
    const maxDepth = config.maxDepth, budget = config.maxNodes;
    const maxColumns = Math.max(4, Math.floor(SCREENS * (svg.clientWidth || 1000) / MIN_SCALE / DX));
    let shown = 1, columns = 1;
    const queue = [0];
    for (let q = 0; q < queue.length; q++) {
      const it = queue[q];
      const wide = width(it);
      if (!wide) continue;
      const deep = maxDepth !== null && maxDepth !== undefined && items[it].depth >= maxDepth;
      const full = budget !== null && budget !== undefined && shown + wide > budget;
      if (deep || full || columns + wide - 1 > maxColumns) {
        collapsed.add(it);
        continue;
      }
      collapsed.delete(it);
      const kids = kidsOf(it);
      shown += kids.length;
      columns += kids.length - 1;
      queue.push(...kids);
    }
  }

  function layout() {
    // leaves take consecutive columns, a parent sits over its first and last child
    pos = new Map();
    const visible = [];
    for (const stack = [0]; stack.length;) {
      const it = stack.pop();
      visible.push(it);
      if (shownLeaf(it)) continue;
      const kids = items[it].kids;
      for (let i = kids.length - 1; i >= 0; i--) stack.push(kids[i]);
    }
    let column = 0;
    for (const it of visible) {
      if (shownLeaf(it)) pos.set(it, { x: column++ * DX, y: items[it].depth * DY });
    }
    for (let i = visible.length - 1; i >= 0; i--) {
      const it = visible[i];
      if (shownLeaf(it)) continue;
      const kids = items[it].kids;
      const x = (pos.get(kids[0]).x + pos.get(kids[kids.length - 1]).x) / 2;
      pos.set(it, { x, y: items[it].depth * DY });
    }
    return visible;
  }

  function ancestors(it) {
    const out = [];
    for (let a = items[it].parent; a >= 0; a = items[a].parent) out.push(a);
    return out;
  }

  // ------------------------------------------------------------------ drawing

  function truncate(s, n) {
    return s.length > n ? s.slice(0, n - 1) + "…" : s;
  }

  function drawNode(it, p) {
    const item = items[it], n = nodeOf(it), m = item.move;
    const attrs = {
      class: kindClasses(it).join(" "),
      "data-item": it,
      "data-kind": kindOf(it),
      "data-worlds": n.worlds,
      tabindex: "0",
      role: "button",
      transform: `translate(${p.x - W / 2},${p.y - H / 2})`,
      ...model.boxHooks(it), // the ids tests and scripts find the box by, its aria-label
    };
    const g = el("g", attrs, gNodes);
    const same = item.sibling;
    const apart = same ? `\n${same.n} sibling moves read the same; this one: ${same.what}` : "";
    el("title", {}, g, item.ref
      ? `${label(it)}\n→ node ${n.id}, shared by several paths: click to go to its first copy${apart}`
      : `${model.tag(it)} ${label(it)}\ncost ${m ? m.cost : 0}, cost to go ${n.value}${apart}`);
    if (m && COMM.has(m.kind)) el("rect", { class: "halo", x: -6, y: -6, width: W + 12, height: H + 12, rx: 9 }, g);
    if (n.goal && !item.ref) el("rect", { class: "goal-ring", x: -4, y: -4, width: W + 8, height: H + 8, rx: 8 }, g);
    const human = m && m.agent === HUMAN;
    el("rect", { class: "box", x: 0, y: 0, width: W, height: H, rx: human ? H / 2 : 5 }, g);
    if (!n.copresent) el("rect", { class: "apart-bar", x: human ? 10 : 0, y: 0, width: 5, height: H }, g);
    const tag = siblingTag(it);
    el("text", { x: W / 2, y: 17, "text-anchor": "middle" }, g,
      m ? truncate(`${m.agent}: ${m.action}`, 24 - tag.length) + tag : "start");
    let sub;
    if (same) {
      g.setAttribute("data-sibling", `${same.k}/${same.n}`);
      g.setAttribute("data-differs", same.what);
      sub = [truncate(same.what, 28)];
    } else if (item.ref) {
      sub = [`→ see node ${n.id}`];
    } else {
      sub = [plural(n.worlds, "world"), kText(n)];
      if (!n.copresent) sub.push("apart");
      if (n.goal) sub.push("goal");
    }
    el("text", { class: "sub", x: W / 2, y: 33, "text-anchor": "middle" }, g, sub.join(" · "));
    if (n.worlds > 1 && !item.ref) {
      const b = el("g", { class: "badge", transform: `translate(${W - 2},2)` }, g);
      el("circle", { r: 10 }, b);
      el("text", { y: 4, "text-anchor": "middle" }, b, String(n.worlds));
    }
    if (width(it)) {
      const folded = collapsed.has(it);
      const t = el("g", {
        class: "toggle", ...model.toggleHooks(it), "data-toggle-item": it, role: "button",
        "aria-label": folded ? "expand" : "collapse",
        transform: `translate(${p.x},${p.y + H / 2 + 8})`,
      }, gNodes);
      // an invisible hit area: the circle alone is a few pixels wide when zoomed out
      el("rect", { class: "hit", x: -9, y: -8, width: folded ? 80 : 18, height: 16 }, t);
      el("circle", { r: 7 }, t);
      el("text", { y: 4, "text-anchor": "middle" }, t, folded ? "+" : "−");
      if (folded) {
        el("text", { class: "folded-count", x: 11, y: 4 }, t, `${model.below(it)} more`);
      }
    }
  }

  function markSelected() {
    // classes only, so selecting in a big tree does not redraw it
    for (const e of svg.querySelectorAll(".selected, .on-branch")) {
      e.classList.remove("selected", "on-branch");
    }
    if (selected === null) return;
    const g = gNodes.querySelector(`[data-item="${selected}"]`);
    if (g) g.classList.add("selected");
    for (const it of [selected, ...ancestors(selected)]) {
      const e = gEdges.querySelector(`[data-edge-to="${it}"]`);
      if (e) e.classList.add("on-branch");
    }
  }

  function draw() {
    const visible = layout();
    visibleCount = visible.length;
    gEdges.textContent = "";
    gNodes.textContent = "";
    for (const it of visible) {
      if (shownLeaf(it)) continue;
      const p = pos.get(it);
      for (const c of items[it].kids) {
        const q = pos.get(c);
        const y0 = p.y + H / 2, y1 = q.y - H / 2, ym = (y0 + y1) / 2;
        const cls = ["edge"];
        if (items[c].move.agent === HUMAN) cls.push("to-human");
        if (items[c].ref) cls.push("to-ref");
        el("path", {
          class: cls.join(" "), "data-edge-to": c,
          d: `M${p.x},${y0} C${p.x},${ym} ${q.x},${ym} ${q.x},${y1}`,
        }, gEdges);
      }
    }
    for (const it of visible) drawNode(it, pos.get(it));
    markSelected();
    $("node-count").textContent = model.shownText(visible) + expandNote;
  }

  // ------------------------------------------------------------------ pan and zoom

  function applyView() {
    svg.setAttribute("viewBox", `${vb.x} ${vb.y} ${vb.w} ${vb.h}`);
  }

  function fit() {
    let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
    for (const p of pos.values()) {
      x0 = Math.min(x0, p.x); x1 = Math.max(x1, p.x);
      y0 = Math.min(y0, p.y); y1 = Math.max(y1, p.y);
    }
    const m = 30;
    vb = { x: x0 - W / 2 - m, y: y0 - H / 2 - m, w: x1 - x0 + W + 2 * m, h: y1 - y0 + H + 2 * m + 20 };
    applyView();
  }

  function openView() {
    // the whole tree when it reads at MIN_SCALE or more; else its top, around the root, at
    // MIN_SCALE: a big policy opens readable, to be panned, not as an unreadable strip
    fit();
    const rw = svg.clientWidth || 1000, rh = svg.clientHeight || 600;
    if (Math.min(rw / vb.w, rh / vb.h) >= MIN_SCALE) return;
    const root = pos.get(0);
    const w = rw / MIN_SCALE, hh = rh / MIN_SCALE;
    // the root and, when it fits beside it, its first child (where the first branch goes)
    const kid = width(0) && !collapsed.has(0) ? pos.get(items[0].kids[0]) : root;
    const reach = w / 2 - W / 2 - 20;
    const cx = Math.max((root.x + kid.x) / 2, root.x - reach);
    vb = { x: cx - w / 2, y: root.y - H / 2 - 30, w, h: hh };
    applyView();
  }

  function toUser(clientX, clientY) {
    const ctm = svg.getScreenCTM();
    if (!ctm) return { x: vb.x + vb.w / 2, y: vb.y + vb.h / 2 };
    const pt = svg.createSVGPoint();
    pt.x = clientX;
    pt.y = clientY;
    return pt.matrixTransform(ctm.inverse());
  }

  function zoom(factor, at) {
    const w = Math.min(Math.max(vb.w * factor, 80), 200000);
    const f = w / vb.w;
    const c = at || { x: vb.x + vb.w / 2, y: vb.y + vb.h / 2 };
    vb = { x: c.x - (c.x - vb.x) * f, y: c.y - (c.y - vb.y) * f, w: vb.w * f, h: vb.h * f };
    applyView();
  }

  function centerOn(id) {
    const p = pos.get(id);
    if (!p) return;
    const inside = p.x > vb.x && p.x < vb.x + vb.w && p.y > vb.y && p.y < vb.y + vb.h;
    if (inside) return;
    vb.x = p.x - vb.w / 2;
    vb.y = p.y - vb.h / 2;
    applyView();
  }

  svg.addEventListener("wheel", (e) => {
    e.preventDefault();
    zoom(Math.exp(e.deltaY * 0.0015), toUser(e.clientX, e.clientY));
  }, { passive: false });

  let drag = null;
  let dragged = false;
  svg.addEventListener("pointerdown", (e) => {
    if (e.button !== 0 || e.target.closest(".node, .toggle")) return;
    const ctm = svg.getScreenCTM();
    drag = { cx: e.clientX, cy: e.clientY, x: vb.x, y: vb.y, scale: ctm ? ctm.a : 1 };
    dragged = false;
    svg.classList.add("dragging");
  });
  window.addEventListener("pointermove", (e) => {
    if (!drag) return;
    const dx = e.clientX - drag.cx, dy = e.clientY - drag.cy;
    if (Math.abs(dx) + Math.abs(dy) > 3) dragged = true;
    vb.x = drag.x - dx / drag.scale;
    vb.y = drag.y - dy / drag.scale;
    applyView();
  });
  window.addEventListener("pointerup", () => {
    drag = null;
    svg.classList.remove("dragging");
  });

  // ------------------------------------------------------------------ details

  function worldTable(n) {
    const table = $("world-table");
    table.textContent = "";
    const truth = new Set(n.state);
    const atoms = new Set();
    for (const d of n.world_diffs) for (const a of [...d.true, ...d.false]) atoms.add(a);
    const cols = [...atoms].sort();
    const head = h("tr");
    head.appendChild(h("th", { class: "corner", scope: "col" }, "world"));
    for (const a of cols) head.appendChild(h("th", { scope: "col", "data-atom": a, title: a }, a));
    table.appendChild(h("thead")).appendChild(head);
    const body = table.appendChild(h("tbody"));
    const row = (key, name, value, cls) => {
      const tr = h("tr", { "data-world": key, class: cls });
      tr.appendChild(h("th", { scope: "row" }, name));
      for (const a of cols) {
        const v = value(a);
        const td = h("td", { "data-atom": a, "data-value": String(v) }, v ? "T" : "F");
        if (v !== truth.has(a)) td.className = "differs";
        tr.appendChild(td);
      }
      body.appendChild(tr);
    };
    row("truth", "truth (designated)", (a) => truth.has(a), "truth");
    n.world_diffs.forEach((d, i) => {
      const same = d.true.length === 0 && d.false.length === 0;
      const t = new Set(d.true), f = new Set(d.false);
      row(String(i + 1), `world ${i + 1}${same ? " (= truth)" : ""}`,
        (a) => (t.has(a) ? true : f.has(a) ? false : truth.has(a)), same ? "same" : "");
    });
    $("worlds-note").textContent = cols.length
      ? `The human entertains ${plural(n.worlds, "world")}; they differ from the truth on ` +
        `${plural(cols.length, "atom")} (T/F; red = unlike the truth).`
      : `The human entertains ${plural(n.worlds, "world")}, all equal to the truth.`;
  }

  function gotoButton(it) {
    // a button to a tree item, named by the model (data-goto: the model's key for it)
    const m = items[it].move;
    return h("button", { type: "button", class: "goto" + (m && COMM.has(m.kind) ? " comm" : ""),
      "data-goto": model.key(it) }, `${model.tag(it)} ${label(it)}`);
  }

  function showDetails(it) {
    const n = nodeOf(it), m = items[it].move;
    $("details-empty").hidden = true;
    $("details-body").hidden = false;
    $("node-title").textContent = `${model.title(it)}${n.goal ? " — goal reached" : ""}`;
    const action = $("fact-action");
    action.textContent = m ? m.action : "start";
    action.className = m && COMM.has(m.kind) ? "comm-text" : "";
    if (m && COMM.has(m.kind)) action.textContent += ` (communication: ${m.kind})`;
    $("fact-agent").textContent = m ? `${m.agent} (${role(m.agent)})` : "nobody (initial state)";
    $("fact-cost").textContent = String(m ? m.cost : 0);
    $("fact-value").textContent = String(n.value);
    const co = $("fact-copresent");
    co.textContent = n.copresent ? "together" : "apart (the human does not see the robot's actions)";
    co.className = n.copresent ? "" : "apart-text";
    $("fact-k").textContent = `${n.k} of K = ${policy.K} robot turns unseen by the human`;
    $("fact-worlds").textContent = String(n.worlds);
    $("fact-to-move").textContent = n.to_move || "nobody (goal reached)";
    const same = items[it].sibling;
    $("fact-differs").textContent = same
      ? `move ${same.k} of ${same.n} that read "${m.agent}: ${m.action}"; this one: ${same.what}` : "";
    $("fact-differs-term").hidden = $("fact-differs").hidden = !same;
    const nav = $("node-nav");
    nav.textContent = "";
    const from = model.from(it); // {text, items}: the links up, or null
    if (from) {
      nav.append(from.text);
      for (const u of from.items) nav.append(gotoButton(u));
      nav.append(h("br"));
    }
    if (width(it)) {
      nav.append("next: ");
      for (const c of kidsOf(it)) nav.append(gotoButton(c));
    }
    model.withWorlds(n); // a lazy model renames the worlds only now
    worldTable(n);
    const doubted = new Set(n.divergence);
    const ul = $("designated-world");
    ul.textContent = "";
    for (const a of n.state) {
      ul.appendChild(h("li", doubted.has(a) ? { class: "doubted", title: "some world disagrees" } : {}, a));
    }
    for (const a of STATIC) { // true in every state and every world: [init] facts nothing changes
      const li = h("li", { class: "static", "data-static": "true", title: "static: true throughout, from [init]" }, a);
      li.appendChild(h("span", { class: "tag" }, "static"));
      ul.appendChild(li);
    }
    const ag = $("agendas");
    ag.textContent = "";
    ag.append(h("dt", {}, `${ROBOT} (robot)`), h("dd", {}, n.robot_agenda.join(", ") || "—"));
    ag.append(h("dt", {}, `${HUMAN} (human)`), h("dd", {}, n.human_agenda.join(", ") || "—"));
  }

  // ------------------------------------------------------------------ timeline

  function branchThrough(it) {
    // the items from the root to ``it``, then on along first choices to a leaf (through a
    // reference, on from the node's first copy)
    const path = [...ancestors(it).reverse(), it];
    for (let cur = it; ;) {
      const from = drawnAt(cur);
      if (!width(from)) break;
      cur = kidsOf(from)[0];
      path.push(cur);
    }
    return path;
  }

  function showTimeline(it) {
    const path = branchThrough(it);
    const upto = path.indexOf(it);
    const last = path[path.length - 1];
    const leaf = nodeOf(last);
    const box = $("timeline");
    box.textContent = "";
    box.append(h("div", { class: "lane-head" }, `${ROBOT} (robot)`),
      h("div", { class: "lane-head" }, `${HUMAN} (human)`));
    const step = (i) => {
      const m = items[path[i]].move, n = nodeOf(path[i]);
      const cls = ["tl-step", role(m.agent)];
      if (COMM.has(m.kind)) cls.push("comm");
      if (IDLE.has(m.kind)) cls.push("idle");
      if (i === upto) cls.push("current");
      if (i > upto) cls.push("after");
      const d = h("div", { class: cls.join(" "), "data-step-node": n.id, "data-step-item": path[i],
        ...model.stepHooks(path[i]), "data-agent": m.agent });
      d.append(h("span", { class: "n" }, model.tag(path[i])), m.action);
      return d;
    };
    // same rule as policy_format.timeline(): a step taken while apart goes to its agent's lane
    let lanes = null;
    let cost = 0;
    for (let i = 1; i < path.length; i++) {
      const m = items[path[i]].move, n = nodeOf(path[i]), prev = nodeOf(path[i - 1]);
      cost += Number(m.cost) || 0;
      if (prev.copresent) {
        box.appendChild(step(i));
      } else {
        if (!lanes) {
          const par = h("div", { class: "tl-parallel" });
          par.appendChild(h("div", { class: "tl-caption" }, "apart: acting in parallel, unseen by each other"));
          lanes = {};
          lanes[ROBOT] = par.appendChild(h("div", { class: "tl-lane", "data-agent": ROBOT }));
          lanes[HUMAN] = par.appendChild(h("div", { class: "tl-lane", "data-agent": HUMAN }));
          box.appendChild(par);
        }
        lanes[m.agent].appendChild(step(i));
      }
      if (n.copresent) lanes = null;
    }
    if (path.length === 1) box.appendChild(h("div", { class: "tl-end" }, "the initial state is the goal"));
    else if (leaf.goal) box.appendChild(h("div", { class: "tl-end" }, `goal reached (branch cost ${cost})`));
    $("branch-select").value = model.branchValue(last); // none when the list does not hold it
    $("timeline-note").textContent = upto < path.length - 1
      ? `Branch through ${model.named(it)}, continued along first choices to leaf ` +
        `${model.nodeId(leaf)} (faded).`
      : `Branch ending at leaf ${model.nodeId(leaf)}.`;
  }

  // ------------------------------------------------------------------ selection

  function select(it, recenter, quiet) {
    if (it === undefined || it === null || !items[it]) return;
    it = drawnAt(it); // a reference leads to the first copy
    let unfolded = false;
    for (const a of ancestors(it)) unfolded = collapsed.delete(a) || unfolded;
    selected = it;
    if (unfolded) draw();
    else markSelected();
    if (unfolded || recenter) centerOn(it);
    showDetails(it);
    showTimeline(it);
    if (quiet) return;
    try {
      history.replaceState(null, "", `#${model.fragment(it)}`);
    } catch (err) {
      // some browsers refuse history changes on file pages; the selection still works
    }
  }

  function toggle(it) {
    // keep the toggled node where it was on screen; the layout around it changes
    const before = pos.get(it);
    if (collapsed.has(it)) {
      kidsOf(it); // made now if they were not (a lazy model makes them each folded)
      collapsed.delete(it);
    } else {
      collapsed.add(it);
    }
    draw();
    const after = pos.get(it);
    vb.x += after.x - before.x;
    vb.y += after.y - before.y;
    applyView();
  }

  svg.addEventListener("click", (e) => {
    if (dragged) {
      dragged = false;
      return;
    }
    const t = e.target.closest(".toggle");
    if (t) return toggle(Number(t.getAttribute("data-toggle-item")));
    const g = e.target.closest(".node");
    if (g) select(Number(g.getAttribute("data-item")), Boolean(items[Number(g.getAttribute("data-item"))].ref));
  });
  svg.addEventListener("keydown", (e) => {
    const g = e.target.closest && e.target.closest(".node");
    if (!g) return;
    const it = Number(g.getAttribute("data-item"));
    if (e.key === "Enter" || e.key === " ") {
      e.preventDefault();
      select(it, Boolean(items[it].ref));
    } else if ((e.key === "+" || e.key === "-") && width(it)) {
      toggle(it);
    }
  });
  document.addEventListener("click", (e) => {
    const b = e.target.closest && e.target.closest("[data-goto], [data-step-item]");
    if (!b) return;
    if (b.hasAttribute("data-step-item")) select(Number(b.getAttribute("data-step-item")), true);
    else select(model.find(b.getAttribute("data-goto")), true);
  });

  $("zoom-in").addEventListener("click", () => zoom(1 / 1.25));
  $("zoom-out").addEventListener("click", () => zoom(1.25));
  $("fit").addEventListener("click", fit);
  $("expand-all").addEventListener("click", () => {
    // breadth-first while the drawing stays under the model's budget (eager: none; the tree
    // unfolding of a lifted policy can have more items than a page can draw)
    let shown = 1;
    expandNote = "";
    const queue = [0];
    for (let q = 0; q < queue.length; q++) {
      const it = queue[q];
      if (!width(it)) continue;
      if (shown + width(it) > model.expandAll) {
        collapsed.add(it);
        expandNote = ` (expand all stops at ${count(model.expandAll)}: unfold the rest by hand)`;
        continue;
      }
      collapsed.delete(it);
      const kids = kidsOf(it);
      shown += kids.length;
      queue.push(...kids);
    }
    draw();
    fit();
  });
  $("collapse-all").addEventListener("click", () => {
    expandNote = "";
    for (let it = 0; it < items.length; it++) if (width(it) && items[it].depth >= 1) collapsed.add(it);
    draw();
    fit();
  });
  $("show-timeline").addEventListener("click", () => $("timeline-pane").scrollIntoView());
  $("branch-select").addEventListener("change", (e) => select(model.find(e.target.value), true));

  // ------------------------------------------------------------------ the page's model

  // What a model gives (each a function of a tree item ``it`` unless said):
  //   build()         make the items the page opens with (the root at least): asked once,
  //                   before anything else
  //   makeKids(it)    make the item's children (items pushed on ``items``), return their
  //                   indices; asked once per item whose ``kids`` is null
  //   first(id)       the item where node ``id`` is drawn first (a reference leads there)
  //   find(key)       the item a ``data-goto`` key or a branch option names, or null
  //   key(it)         the ``data-goto`` key of an item
  //   tag(it)         the item's short name before its label (buttons, timeline steps)
  //   named(it)       the item's node in a sentence; nodeId(view): a node's id as written
  //   title(it)       the details' heading (before "— goal reached")
  //   from(it)        the details' links up: {text, items}, or null
  //   withWorlds(view)  make sure the view has its divergence and world_diffs
  //   boxHooks(it), toggleHooks(it), stepHooks(it)  attributes of a box, toggle, step
  //   below(it)       what a folded box's count says is below it
  //   shownText(visible)  the toolbar's count of what is drawn
  //   branchValue(it) the branch option of a leaf item ("" for none)
  //   fromHash(hash)  the item a URL fragment selects, or null; fragment(it): the reverse
  //   facts           the header's words for the nodes (before "and N moves")
  //   expandAll       the most boxes "expand all" draws (Infinity: no budget)
  //   branches(most)  the branch drop-down's first ``most`` options: [value, text] pairs
  model = pageModel({
    policy, nodes, items, collapsed, $, plural, count, label, kidsOf, tellApart,
  });
  model.build();

  // ------------------------------------------------------------------ start

  const moveCount = nodes.reduce((a, n) => a + n.moves.length, 0);
  $("policy-title").textContent = `${policy.problem} — ${policy.domain}`;
  // a preference profile (C11) is what a "preferences" policy optimised: neither cost is marked
  const kind = policy.objective && policy.objective.kind;
  const objective = kind === "expected" || kind === "preferences" ? kind : "worst-case";
  const mark = (k) => (k === objective ? " (optimised)" : "");
  const costs = $("policy-costs");
  if (policy.worst_case !== null && policy.worst_case !== undefined &&
      policy.expected !== null && policy.expected !== undefined) {
    costs.append(h("span", { id: "policy-worst-case" }, `worst-case cost ${policy.worst_case}${mark("worst-case")}`),
      " · ", h("span", { id: "policy-expected" }, `expected cost ${policy.expected}${mark("expected")}`));
  } else {
    costs.append(h("span", { id: "policy-cost" }, `${objective} cost ${policy.cost} (optimised)`));
  }
  // joint steps (docs/concurrent.md): who moves first; a preference profile and the root's vector
  const steps = policy.steps;
  if (steps && steps.mode === "concurrent") {
    $("policy-joint").hidden = false;
    const first = steps.first === "robot" ? ROBOT : HUMAN;
    const other = first === ROBOT ? HUMAN : ROBOT;
    $("policy-steps").textContent = `joint steps: ${first} moves first, ${other} replies`;
    const o = policy.objective || {};
    if (o.kind === "preferences" && Array.isArray(o.metrics) && Array.isArray(o.value)) {
      const root = o.metrics.map((m, i) => `${m} = ${o.value[i]}`).join(", ");
      $("policy-profile").textContent = ` · profile ${o.profile} (${o.metrics.join(", ")}), ` +
        `${o.estimate || "worst-case"} estimate; root: ${root}`;
    }
  }
  $("policy-facts").textContent = [
    `${policy.leaves} branch${policy.leaves === 1 ? "" : "es"}`,
    plural(policy.communications, "communication"), `K = ${policy.K}`,
    `${model.facts} and ${plural(moveCount, "move")}`, `robot ${ROBOT}, human ${HUMAN}`,
    policy.optimal === false ? "not proved optimal" : "optimal",
  ].join(" · ");
  // every communication move of the graph, once, at the first path to the node it is played
  // at (on a lifted page its images elsewhere say the same with other objects)
  const list = $("comm-list");
  let comms = 0;
  nodes.forEach((n, i) => {
    n.moves.forEach((m, j) => {
      if (!COMM.has(m.kind)) return;
      list.appendChild(gotoButton(kidsOf(model.first(i))[j]));
      comms++;
    });
  });
  if (!comms) list.textContent = "none";
  // the branch drop-down: the model's first MAX_OPTIONS branches
  const select_ = $("branch-select");
  const MAX_OPTIONS = 2000;
  for (const [value, text] of model.branches(MAX_OPTIONS)) {
    select_.appendChild(h("option", { value }, text));
  }

  initialFolding();
  draw();
  openView();
  const start = model.fromHash(location.hash);
  if (start !== null && start !== undefined) select(start, true);
  else select(0, false, true); // the root's details and its first branch, the URL untouched
  document.body.setAttribute("data-ready", "true");
}
