/* ehatp policy explorer for a lifted policy (format version 3): the same page as explorer.js,
 * whose tree is realised lazily from the canonical nodes and their renamings, so the page is
 * as small as the lifted file and opens as fast whatever the size of the expansion.
 * (explorer.js draws a version 2 graph and is left as it is: those pages stay byte-identical.)
 * Plain JS with no dependencies: the page must work offline from one file. */
(function () {
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

  // A lifted policy (format version 3, docs/policy-format.md): ``nodes`` are canonical nodes,
  // each move carries the renaming that maps its child onto node ``to``. The page realises the
  // tree lazily, as Renamings (src/ehatp/formats/lifted.py) does in Python: an *item* is a
  // canonical node seen through ``tau``, the renaming from it to the real objects (at the root
  // the inverse of ``symmetry.root``; along a move, ``tau . inverse(renamings[m.renaming])``),
  // and an item's children are made only when it is unfolded. Facts keep their canonical
  // positions (no atom order), as expanded() writes them. The drawing is the tree unfolding:
  // a real node reached by two paths is drawn under each, unlinked.
  const SYM = policy.symmetry;
  const OBJECTS = SYM.objects;
  const TABLE = SYM.renamings;
  // an object name in a label or a fact: lifted.TOKEN (the planner's tokenisation); JS and
  // Python agree on \s for every character an object name or a separator can hold (ASCII
  // spaces; a policy file holds no control character)
  const TOKEN = /[^\s(),=\[\]<>!|{}+;:]+/g;
  const CACHE = 4096; // views kept (a walk revisits the same few)
  const inverse = (p) => {
    const inv = new Array(p.length);
    p.forEach((j, i) => { inv[j] = i; });
    return inv;
  };
  const compose = (a, b) => b.map((j) => a[j]); // a after b (b first)
  const ROOT_TAU = inverse(TABLE[SYM.root]);
  const inverses = new Map(); // renaming index -> its inverse
  function childTau(tau, r) {
    if (!r) return tau;
    if (!inverses.has(r)) inverses.set(r, inverse(TABLE[r]));
    return compose(tau, inverses.get(r));
  }
  const namesOf = new Map(); // tau key -> Map(object -> image), null for no change
  function names(tau, key) {
    if (!namesOf.has(key)) {
      const ren = new Map();
      tau.forEach((j, i) => { if (i !== j) ren.set(OBJECTS[i], OBJECTS[j]); });
      if (namesOf.size >= CACHE) namesOf.clear();
      namesOf.set(key, ren.size ? ren : null);
    }
    return namesOf.get(key);
  }
  const renamed = (ren, s) => (ren ? s.replace(TOKEN, (t) => (ren.has(t) ? ren.get(t) : t)) : s);
  const views = new Map(); // "node|tau" -> the node on the real objects
  function realise(id, tau) {
    // Renamings.node: the canonical node ``id`` as ``tau`` maps it; its moves renamed, each
    // ``to`` still the canonical id; the worlds (the bulk of a file) on demand (worldsOf)
    const key = tau.join(",");
    const vkey = `${id}|${key}`;
    if (views.has(vkey)) return views.get(vkey);
    const n = nodes[id], ren = names(tau, key);
    const t = (s) => renamed(ren, s);
    const hyps = (n.hypotheses || []).map((x) => x.map(t));
    const view = {
      id, tau, ren, copresent: n.copresent, k: n.k, worlds: n.worlds, value: n.value,
      goal: n.goal, to_move: n.to_move, state: n.state.map(t),
      robot_agenda: n.robot_agenda.map(t),
      human_agenda: hyps.length > 1 ? hyps[0] : n.human_agenda.map(t),
      moves: n.moves.map((m) => Object.assign({}, m, {
        action: t(m.action), told: (m.told || []).map(t),
      })),
    };
    if (n.hypotheses) view.hypotheses = hyps;
    if (views.size >= CACHE) views.clear();
    views.set(vkey, view);
    return view;
  }
  function worldsOf(view) {
    // the divergence and the worlds' differences, renamed (only for the details panel)
    if (!view.world_diffs) {
      const n = nodes[view.id], t = (s) => renamed(view.ren, s);
      view.divergence = n.divergence.map(t);
      view.world_diffs = n.world_diffs.map((d) => ({ true: d.true.map(t), false: d.false.map(t) }));
    }
    return view;
  }

  // tree items, made on demand: {node, tau, view, move, parent, kids (null until made), depth,
  // path ("" at the root, else the move indices from the root joined by "."), sibling}
  const items = [];
  const collapsed = new Set(); // item indices; an item with moves starts folded
  function newItem(id, tau, move, parent, path) {
    const it = items.length;
    items.push({
      node: id, tau, view: realise(id, tau), move, parent, kids: null, sibling: null,
      depth: parent >= 0 ? items[parent].depth + 1 : 0, path,
    });
    if (nodes[id].moves.length) collapsed.add(it);
    return it;
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
        : `→ node c${n.id}`;
    });
  }
  function kidsOf(it) {
    const item = items[it];
    if (item.kids) return item.kids;
    item.kids = [];
    const groups = new Map();
    item.view.moves.forEach((m, j) => {
      const kid = newItem(m.to, childTau(item.tau, m.renaming || 0), m, it,
        item.path === "" ? String(j) : `${item.path}.${j}`);
      item.kids.push(kid);
      const key = `${m.agent}\u0000${m.action}`;
      if (!groups.has(key)) groups.set(key, []);
      groups.get(key).push(kid);
    });
    for (const group of groups.values()) {
      if (group.length < 2) continue;
      const what = differs(group);
      group.forEach((x, i) => { items[x].sibling = { k: i + 1, n: group.length, what: what[i] }; });
    }
    return item.kids;
  }
  const hasMoves = (it) => nodes[items[it].node].moves.length > 0;
  function itemAt(path) {
    // the item a path of move indices leads to, made on the way; null when there is none
    let it = 0;
    for (const part of path === "" ? [] : path.split(".")) {
      const j = Number(part);
      if (!/^\d+$/.test(part) || j >= nodes[items[it].node].moves.length) return null;
      it = kidsOf(it)[j];
    }
    return it;
  }
  // the number of items of the tree unfolding below each canonical node (a renaming keeps the
  // shape), children first: exact however many branches, as Policy.tree_size() counts them
  const treeSize = new Array(nodes.length).fill(null);
  function sizeBelow(id) {
    for (const stack = [id]; stack.length;) {
      const n = stack[stack.length - 1];
      if (treeSize[n] !== null) { stack.pop(); continue; }
      const todo = nodes[n].moves.filter((m) => treeSize[m.to] === null);
      if (todo.length) { stack.push(...todo.map((m) => m.to)); continue; }
      treeSize[n] = nodes[n].moves.reduce((a, m) => a + treeSize[m.to], 1n);
      stack.pop();
    }
    return treeSize[id] - 1n;
  }
  const count = (x) => x.toLocaleString("en-US");
  // the first path (depth-first, moves in order) to each canonical node: where the lists of
  // communications and of leaves show it
  const firstPath = new Array(nodes.length).fill(null);
  for (const stack = [[0, ""]]; stack.length;) {
    const [n, path] = stack.pop();
    if (firstPath[n] !== null) continue;
    firstPath[n] = path;
    const moves = nodes[n].moves;
    for (let j = moves.length - 1; j >= 0; j--) {
      stack.push([moves[j].to, path === "" ? String(j) : `${path}.${j}`]);
    }
  }
  newItem(0, ROOT_TAU, null, -1, "");

  const svg = $("tree");
  const NS = svg.namespaceURI; // taken from the parsed page, so no namespace URL in the source
  const gEdges = $("edges");
  const gNodes = $("nodes");

  let selected = null; // item index
  let pos = new Map(); // item index -> {x, y}
  let visibleCount = 0;
  let expandNote = ""; // set when "expand all" stops at its budget
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
  const siblingTag = (it) => {
    const s = items[it].sibling;
    return s ? ` (${s.k}/${s.n})` : "";
  };
  const label = (it) => {
    const m = items[it].move;
    return m ? `${m.agent}: ${m.action}${siblingTag(it)}` : "start";
  };
  const cid = (it) => `c${items[it].node}`; // a canonical node's name: c12 is node 12
  const role = (agent) => (agent === ROBOT ? "robot" : agent === HUMAN ? "human" : "");
  const kindOf = (it) => (items[it].move ? items[it].move.kind : "start");
  const nodeOf = (it) => items[it].view;
  const shownLeaf = (it) => collapsed.has(it) || !hasMoves(it);
  const kText = (n) => `k=${n.k}/${policy.K}`; // unseen robot turns of the bound K

  function kindClasses(it) {
    const c = ["node"];
    const m = items[it].move, n = nodeOf(it);
    if (!m) c.push("start");
    else c.push(role(m.agent));
    if (m && COMM.has(m.kind)) c.push("comm");
    if (m && IDLE.has(m.kind)) c.push("idle");
    if (n.goal) c.push("goal");
    if (!n.copresent) c.push("apart");
    if (n.worlds > 1) c.push("multi");
    return c;
  }

  // ------------------------------------------------------------------ folding and layout

  function initialFolding() {
    // fold below the depth cap, where the breadth-first budget runs out, and where the tree
    // would get wider than a few screens at the readable scale (a column per shown leaf)
    const maxDepth = config.maxDepth, budget = config.maxNodes;
    const maxColumns = Math.max(4, Math.floor(SCREENS * (svg.clientWidth || 1000) / MIN_SCALE / DX));
    let shown = 1, columns = 1;
    const queue = [0];
    for (let q = 0; q < queue.length; q++) {
      const it = queue[q];
      const width = nodes[items[it].node].moves.length;
      if (!width) continue;
      const deep = maxDepth !== null && maxDepth !== undefined && items[it].depth >= maxDepth;
      const full = budget !== null && budget !== undefined && shown + width > budget;
      if (deep || full || columns + width - 1 > maxColumns) continue; // stays folded
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
      if (collapsed.has(it) || !hasMoves(it)) continue;
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
    };
    attrs["data-canonical-id"] = n.id;
    attrs["data-path"] = item.path;
    attrs["aria-label"] = `canonical node ${n.id}: ${label(it)}, ${plural(n.worlds, "world")}`;
    const g = el("g", attrs, gNodes);
    const same = item.sibling;
    const apart = same ? `\n${same.n} sibling moves read the same; this one: ${same.what}` : "";
    el("title", {}, g, `${cid(it)} ${label(it)}\ncost ${m ? m.cost : 0}, cost to go ${n.value}${apart}`);
    if (m && COMM.has(m.kind)) el("rect", { class: "halo", x: -6, y: -6, width: W + 12, height: H + 12, rx: 9 }, g);
    if (n.goal) el("rect", { class: "goal-ring", x: -4, y: -4, width: W + 8, height: H + 8, rx: 8 }, g);
    const human = m && m.agent === HUMAN;
    el("rect", { class: "box", x: 0, y: 0, width: W, height: H, rx: human ? H / 2 : 5 }, g);
    if (!n.copresent) el("rect", { class: "apart-bar", x: human ? 10 : 0, y: 0, width: 5, height: H }, g);
    const tag = siblingTag(it);
    el("text", { x: W / 2, y: 17, "text-anchor": "middle" }, g,
      m ? truncate(`${m.agent}: ${m.action}`, 24 - tag.length) + tag : "start");
    const sibling = item.sibling;
    let sub;
    if (sibling) {
      g.setAttribute("data-sibling", `${sibling.k}/${sibling.n}`);
      g.setAttribute("data-differs", sibling.what);
      sub = [truncate(sibling.what, 28)];
    } else {
      sub = [plural(n.worlds, "world"), kText(n)];
      if (!n.copresent) sub.push("apart");
      if (n.goal) sub.push("goal");
    }
    el("text", { class: "sub", x: W / 2, y: 33, "text-anchor": "middle" }, g, sub.join(" · "));
    if (n.worlds > 1) {
      const b = el("g", { class: "badge", transform: `translate(${W - 2},2)` }, g);
      el("circle", { r: 10 }, b);
      el("text", { y: 4, "text-anchor": "middle" }, b, String(n.worlds));
    }
    if (hasMoves(it)) {
      const folded = collapsed.has(it);
      const t = el("g", {
        class: "toggle", "data-toggle-path": item.path, "data-toggle-item": it, role: "button",
        "aria-label": folded ? "expand" : "collapse",
        transform: `translate(${p.x},${p.y + H / 2 + 8})`,
      }, gNodes);
      // an invisible hit area: the circle alone is a few pixels wide when zoomed out
      el("rect", { class: "hit", x: -9, y: -8, width: folded ? 80 : 18, height: 16 }, t);
      el("circle", { r: 7 }, t);
      el("text", { y: 4, "text-anchor": "middle" }, t, folded ? "+" : "−");
      if (folded) {
        el("text", { class: "folded-count", x: 11, y: 4 }, t, `${count(sizeBelow(n.id))} more`);
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
      if (collapsed.has(it) || !hasMoves(it)) continue;
      const p = pos.get(it);
      for (const c of items[it].kids) {
        const q = pos.get(c);
        const y0 = p.y + H / 2, y1 = q.y - H / 2, ym = (y0 + y1) / 2;
        const cls = ["edge"];
        if (items[c].move.agent === HUMAN) cls.push("to-human");
        el("path", {
          class: cls.join(" "), "data-edge-to": c,
          d: `M${p.x},${y0} C${p.x},${ym} ${q.x},${ym} ${q.x},${y1}`,
        }, gEdges);
      }
    }
    for (const it of visible) drawNode(it, pos.get(it));
    markSelected();
    // the tree unfolding's items (a real node reached by two paths is an item under each)
    $("node-count").textContent = `${count(visible.length)} of ${count(sizeBelow(0) + 1n)} ` +
      `tree items shown${expandNote}`;
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
    const kid = hasMoves(0) && !collapsed.has(0) ? pos.get(items[0].kids[0]) : root;
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
    // a button to a tree item (data-goto: its path of moves from the root)
    const m = items[it].move;
    return h("button", { type: "button", class: "goto" + (m && COMM.has(m.kind) ? " comm" : ""),
      "data-goto": items[it].path }, `${cid(it)} ${label(it)}`);
  }

  function showDetails(it) {
    const n = nodeOf(it), m = items[it].move;
    $("details-empty").hidden = true;
    $("details-body").hidden = false;
    $("node-title").textContent = `Canonical node ${n.id}` +
      `${n.ren ? ", objects renamed" : ""}${n.goal ? " — goal reached" : ""}`;
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
    // the parent on this path only: other paths may reach the same real node (not searched)
    if (items[it].parent >= 0) {
      nav.append("from (on this path): ", gotoButton(items[it].parent), h("br"));
    }
    if (hasMoves(it)) {
      nav.append("next: ");
      for (const c of kidsOf(it)) nav.append(gotoButton(c));
    }
    worldsOf(n);
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
    // the items from the root to ``it``, then on along first choices to a leaf
    const path = [...ancestors(it).reverse(), it];
    for (let cur = it; ;) {
      if (!hasMoves(cur)) break;
      cur = kidsOf(cur)[0];
      path.push(cur);
    }
    return path;
  }

  function showTimeline(it) {
    const path = branchThrough(it);
    const upto = path.indexOf(it);
    const leaf = nodeOf(path[path.length - 1]);
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
        "data-step-path": items[path[i]].path, "data-agent": m.agent });
      d.append(h("span", { class: "n" }, cid(path[i])), m.action);
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
    // the drop-down lists the first MAX_OPTIONS branches; a later one shows no option
    const end = items[path[path.length - 1]].path;
    $("branch-select").value = leafOptions.has(end) ? end : "";
    $("timeline-note").textContent = upto < path.length - 1
      ? `Branch through ${cid(it)}, continued along first choices to leaf c${leaf.id} (faded).`
      : `Branch ending at leaf c${leaf.id}.`;
  }

  // ------------------------------------------------------------------ selection

  function select(it, recenter, quiet) {
    if (it === undefined || it === null || !items[it]) return;
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
      history.replaceState(null, "", `#path=${items[it].path}`);
    } catch (err) {
      // some browsers refuse history changes on file pages; the selection still works
    }
  }

  function toggle(it) {
    // keep the toggled node where it was on screen; the layout around it changes
    const before = pos.get(it);
    if (collapsed.has(it)) {
      kidsOf(it); // made now, each folded
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
    if (g) select(Number(g.getAttribute("data-item")), false);
  });
  svg.addEventListener("keydown", (e) => {
    const g = e.target.closest && e.target.closest(".node");
    if (!g) return;
    const it = Number(g.getAttribute("data-item"));
    if (e.key === "Enter" || e.key === " ") {
      e.preventDefault();
      select(it, false);
    } else if ((e.key === "+" || e.key === "-") && hasMoves(it)) {
      toggle(it);
    }
  });
  document.addEventListener("click", (e) => {
    const b = e.target.closest && e.target.closest("[data-goto], [data-step-item]");
    if (!b) return;
    if (b.hasAttribute("data-step-item")) select(Number(b.getAttribute("data-step-item")), true);
    else select(itemAt(b.getAttribute("data-goto")), true);
  });

  $("zoom-in").addEventListener("click", () => zoom(1 / 1.25));
  $("zoom-out").addEventListener("click", () => zoom(1.25));
  $("fit").addEventListener("click", fit);
  // the tree unfolding of a lifted policy can have more items than a page can draw: "expand
  // all" unfolds breadth-first while the drawing stays under EXPAND_ALL items
  const EXPAND_ALL = 3000;
  $("expand-all").addEventListener("click", () => {
    let shown = 1;
    expandNote = "";
    const queue = [0];
    for (let q = 0; q < queue.length; q++) {
      const it = queue[q];
      if (!hasMoves(it)) continue;
      if (shown + nodes[items[it].node].moves.length > EXPAND_ALL) {
        collapsed.add(it);
        expandNote = ` (expand all stops at ${count(EXPAND_ALL)}: unfold the rest by hand)`;
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
    for (let it = 0; it < items.length; it++) if (hasMoves(it) && items[it].depth >= 1) collapsed.add(it);
    draw();
    fit();
  });
  $("show-timeline").addEventListener("click", () => $("timeline-pane").scrollIntoView());
  $("branch-select").addEventListener("change", (e) => select(itemAt(e.target.value), true));

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
    `lifted: ${plural(nodes.length, "canonical node")} and ${plural(moveCount, "move")}`,
    `robot ${ROBOT}, human ${HUMAN}`,
    policy.optimal === false ? "not proved optimal" : "optimal",
  ].join(" · ");
  // every communication move of the canonical graph, once, as seen at the first path to the
  // node it is played at (its images elsewhere say the same with other objects)
  const list = $("comm-list");
  let comms = 0;
  nodes.forEach((n, i) => {
    n.moves.forEach((m, j) => {
      if (!COMM.has(m.kind)) return;
      list.appendChild(gotoButton(kidsOf(itemAt(firstPath[i]))[j]));
      comms++;
    });
  });
  if (!comms) list.textContent = "none";
  // the first branches of the tree unfolding, depth-first (the order of Policy.iter_branches
  // and of `ehatp show`'s timelines): a leaf's move renamed through its parent's renaming, made
  // into items only where sibling moves read the same (for their numbers)
  const select_ = $("branch-select");
  const MAX_OPTIONS = 2000;
  const leafOptions = new Set();
  for (const stack = [[0, ROOT_TAU, "", -1, -1, null]]; stack.length && leafOptions.size < MAX_OPTIONS;) {
    const [n, tau, path, up, j, upTau] = stack.pop();
    const moves = nodes[n].moves;
    for (let k = moves.length - 1; k >= 0; k--) {
      stack.push([moves[k].to, childTau(tau, moves[k].renaming || 0),
        path === "" ? String(k) : `${path}.${k}`, n, k, tau]);
    }
    if (moves.length) continue;
    let text = "start";
    if (up >= 0) {
      const m = nodes[up].moves[j];
      const twins = nodes[up].moves.filter((x) => x.agent === m.agent && x.action === m.action);
      text = twins.length > 1 ? label(itemAt(path))
        : `${m.agent}: ${renamed(names(upTau, upTau.join(",")), m.action)}`;
    }
    leafOptions.add(path);
    select_.appendChild(h("option", { value: path }, `branch ${leafOptions.size}: ${text} (leaf c${n})`));
  }

  // a lifted page says how to read it (the template's hint and legend speak of references)
  $("hint").textContent = "Lifted policy: each box is a canonical node (cN) seen through the " +
    "renaming of the objects along its path, made when its parent is unfolded; a node reached " +
    "by several paths is drawn under each. Click a node for its worlds; click ± to fold or " +
    "unfold; drag to pan, wheel to zoom.";
  const ref = document.querySelector("#legend .sw-ref");
  if (ref) {
    ref.nextSibling.remove();
    ref.remove();
  }

  initialFolding();
  draw();
  openView();
  const m = /^#path=([\d.]*)$/.exec(location.hash);
  const start = m ? itemAt(m[1]) : null;
  if (start !== null) select(start, true);
  else select(0, false, true); // the root's details and its first branch, the URL untouched
  document.body.setAttribute("data-ready", "true");
})();
