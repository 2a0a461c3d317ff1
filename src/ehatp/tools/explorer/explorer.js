/* ehatp policy explorer: the policy tree with pan/zoom and folding, a node's worlds, and a
 * branch as a timeline. Plain JS with no dependencies: the page must work offline from one
 * file, and a tidy layout plus viewBox pan/zoom is too little code to justify a library. */
(function () {
  "use strict";

  const $ = (id) => document.getElementById(id);
  const policy = JSON.parse($("policy-data").textContent);
  const config = JSON.parse($("explorer-config").textContent);
  const nodes = policy.nodes;
  const byId = new Map(nodes.map((n) => [n.id, n]));
  const ROBOT = policy.agents.robot;
  const HUMAN = policy.agents.human;
  const COMM = new Set(["inform", "ask"]);
  const IDLE = new Set(["wait", "pass"]);

  // box size and grid step of the tree drawing (SVG user units)
  const W = 150, H = 38, DX = 166, DY = 70;

  // parents, depths and subtree sizes, without recursion (policies can be deep)
  const parentOf = new Map();
  const depthOf = new Map([[0, 0]]);
  const sizeOf = new Map();
  const preorder = [];
  for (const stack = [0]; stack.length;) {
    const id = stack.pop();
    preorder.push(id);
    const kids = byId.get(id).children;
    for (let i = kids.length - 1; i >= 0; i--) {
      parentOf.set(kids[i], id);
      depthOf.set(kids[i], depthOf.get(id) + 1);
      stack.push(kids[i]);
    }
  }
  for (let i = preorder.length - 1; i >= 0; i--) {
    const id = preorder[i];
    let s = 1;
    for (const c of byId.get(id).children) s += sizeOf.get(c);
    sizeOf.set(id, s);
  }

  const svg = $("tree");
  const NS = svg.namespaceURI; // taken from the parsed page, so no namespace URL in the source
  const gEdges = $("edges");
  const gNodes = $("nodes");

  const collapsed = new Set();
  let selected = null;
  let pos = new Map();
  let visibleCount = 0;
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
  const label = (n) => (n.agent ? `${n.agent}: ${n.action}` : n.action);
  const role = (agent) => (agent === ROBOT ? "robot" : agent === HUMAN ? "human" : "");
  const shownLeaf = (id) => collapsed.has(id) || byId.get(id).children.length === 0;

  function kindClasses(n) {
    const c = ["node"];
    if (n.kind === "start") c.push("start");
    else c.push(role(n.agent));
    if (COMM.has(n.kind)) c.push("comm");
    if (IDLE.has(n.kind)) c.push("idle");
    if (n.goal) c.push("goal");
    if (!n.copresent) c.push("apart");
    if (n.worlds > 1) c.push("multi");
    return c;
  }

  // ------------------------------------------------------------------ folding and layout

  function initialFolding() {
    // fold below the depth cap and where the breadth-first budget runs out
    const maxDepth = config.maxDepth, budget = config.maxNodes;
    let shown = 1;
    const queue = [0];
    for (let q = 0; q < queue.length; q++) {
      const id = queue[q];
      const kids = byId.get(id).children;
      if (!kids.length) continue;
      const deep = maxDepth !== null && maxDepth !== undefined && depthOf.get(id) >= maxDepth;
      const full = budget !== null && budget !== undefined && shown + kids.length > budget;
      if (deep || full) {
        collapsed.add(id);
        continue;
      }
      shown += kids.length;
      queue.push(...kids);
    }
  }

  function layout() {
    // leaves take consecutive columns, a parent sits over its first and last child
    pos = new Map();
    const visible = [];
    for (const stack = [0]; stack.length;) {
      const id = stack.pop();
      visible.push(id);
      if (collapsed.has(id)) continue;
      const kids = byId.get(id).children;
      for (let i = kids.length - 1; i >= 0; i--) stack.push(kids[i]);
    }
    let column = 0;
    for (const id of visible) {
      if (shownLeaf(id)) pos.set(id, { x: column++ * DX, y: depthOf.get(id) * DY });
    }
    for (let i = visible.length - 1; i >= 0; i--) {
      const id = visible[i];
      if (shownLeaf(id)) continue;
      const kids = byId.get(id).children;
      const x = (pos.get(kids[0]).x + pos.get(kids[kids.length - 1]).x) / 2;
      pos.set(id, { x, y: depthOf.get(id) * DY });
    }
    return visible;
  }

  function ancestors(id) {
    const out = [];
    for (let a = parentOf.get(id); a !== undefined; a = parentOf.get(a)) out.push(a);
    return out;
  }

  // ------------------------------------------------------------------ drawing

  function truncate(s, n) {
    return s.length > n ? s.slice(0, n - 1) + "…" : s;
  }

  function drawNode(n, p) {
    const g = el("g", {
      class: kindClasses(n).join(" "),
      "data-node-id": n.id,
      "data-kind": n.kind,
      "data-worlds": n.worlds,
      tabindex: "0",
      role: "button",
      "aria-label": `node ${n.id}: ${label(n)}, ${plural(n.worlds, "world")}`,
      transform: `translate(${p.x - W / 2},${p.y - H / 2})`,
    }, gNodes);
    el("title", {}, g, `#${n.id} ${label(n)}\ncost ${n.cost}, cost to go ${n.value}`);
    if (COMM.has(n.kind)) el("rect", { class: "halo", x: -6, y: -6, width: W + 12, height: H + 12, rx: 9 }, g);
    if (n.goal) el("rect", { class: "goal-ring", x: -4, y: -4, width: W + 8, height: H + 8, rx: 8 }, g);
    const human = n.agent === HUMAN && n.kind !== "start";
    el("rect", { class: "box", x: 0, y: 0, width: W, height: H, rx: human ? H / 2 : 5 }, g);
    if (!n.copresent) el("rect", { class: "apart-bar", x: human ? 10 : 0, y: 0, width: 5, height: H }, g);
    el("text", { x: W / 2, y: 16, "text-anchor": "middle" }, g, truncate(label(n), 24));
    const sub = [plural(n.worlds, "world"), `K=${n.k}`];
    if (!n.copresent) sub.push("apart");
    if (n.goal) sub.push("goal");
    el("text", { class: "sub", x: W / 2, y: 30, "text-anchor": "middle" }, g, sub.join(" · "));
    if (n.worlds > 1) {
      const b = el("g", { class: "badge", transform: `translate(${W - 2},2)` }, g);
      el("circle", { r: 9 }, b);
      el("text", { y: 3.5, "text-anchor": "middle" }, b, String(n.worlds));
    }
    if (n.children.length) {
      const folded = collapsed.has(n.id);
      const t = el("g", {
        class: "toggle", "data-toggle-id": n.id, role: "button",
        "aria-label": folded ? "expand" : "collapse",
        transform: `translate(${p.x},${p.y + H / 2 + 7})`,
      }, gNodes);
      // an invisible hit area: the circle alone is a few pixels wide when zoomed out
      el("rect", { class: "hit", x: -9, y: -8, width: folded ? 70 : 18, height: 16 }, t);
      el("circle", { r: 6.5 }, t);
      el("text", { y: 4, "text-anchor": "middle" }, t, folded ? "+" : "−");
      if (folded) {
        el("text", { class: "folded-count", x: 10, y: 4 }, t, `${sizeOf.get(n.id) - 1} more`);
      }
    }
  }

  function markSelected() {
    // classes only, so selecting in a big tree does not redraw it
    for (const e of svg.querySelectorAll(".selected, .on-branch")) {
      e.classList.remove("selected", "on-branch");
    }
    if (selected === null) return;
    const g = gNodes.querySelector(`[data-node-id="${selected}"]`);
    if (g) g.classList.add("selected");
    for (const id of [selected, ...ancestors(selected)]) {
      const e = gEdges.querySelector(`[data-edge-to="${id}"]`);
      if (e) e.classList.add("on-branch");
    }
  }

  function draw() {
    const visible = layout();
    visibleCount = visible.length;
    gEdges.textContent = "";
    gNodes.textContent = "";
    for (const id of visible) {
      if (collapsed.has(id)) continue;
      const p = pos.get(id);
      for (const c of byId.get(id).children) {
        const q = pos.get(c);
        const y0 = p.y + H / 2, y1 = q.y - H / 2, ym = (y0 + y1) / 2;
        const cls = ["edge"];
        if (byId.get(c).agent === HUMAN) cls.push("to-human");
        el("path", {
          class: cls.join(" "), "data-edge-to": c,
          d: `M${p.x},${y0} C${p.x},${ym} ${q.x},${ym} ${q.x},${y1}`,
        }, gEdges);
      }
    }
    for (const id of visible) drawNode(byId.get(id), pos.get(id));
    markSelected();
    $("node-count").textContent = `${visibleCount} of ${plural(nodes.length, "node")} shown`;
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

  function gotoButton(id, text) {
    const n = byId.get(id);
    const b = h("button", { type: "button", class: "goto" + (COMM.has(n.kind) ? " comm" : ""), "data-goto": id },
      text || `#${id} ${label(n)}`);
    return b;
  }

  function showDetails(n) {
    $("details-empty").hidden = true;
    $("details-body").hidden = false;
    $("node-title").textContent = `Node ${n.id}${n.goal ? " — goal reached" : ""}`;
    const action = $("fact-action");
    action.textContent = n.action;
    action.className = COMM.has(n.kind) ? "comm-text" : "";
    if (COMM.has(n.kind)) action.textContent += ` (communication: ${n.kind})`;
    $("fact-agent").textContent = n.agent ? `${n.agent} (${role(n.agent)})` : "nobody (initial state)";
    $("fact-cost").textContent = String(n.cost);
    $("fact-value").textContent = String(n.value);
    const co = $("fact-copresent");
    co.textContent = n.copresent ? "together" : "apart (the human does not see the robot's actions)";
    co.className = n.copresent ? "" : "apart-text";
    $("fact-k").textContent = `${n.k} (bound K = ${policy.K})`;
    $("fact-worlds").textContent = String(n.worlds);
    $("fact-to-move").textContent = n.to_move || "nobody (goal reached)";
    const nav = $("node-nav");
    nav.textContent = "";
    const up = parentOf.get(n.id);
    if (up !== undefined) nav.append("up: ", gotoButton(up), h("br"));
    if (n.children.length) {
      nav.append("next: ");
      for (const c of n.children) nav.append(gotoButton(c));
    }
    worldTable(n);
    const doubted = new Set(n.divergence);
    const ul = $("designated-world");
    ul.textContent = "";
    for (const a of n.state) {
      ul.appendChild(h("li", doubted.has(a) ? { class: "doubted", title: "some world disagrees" } : {}, a));
    }
    const ag = $("agendas");
    ag.textContent = "";
    ag.append(h("dt", {}, `${ROBOT} (robot)`), h("dd", {}, n.robot_agenda.join(", ") || "—"));
    ag.append(h("dt", {}, `${HUMAN} (human)`), h("dd", {}, n.human_agenda.join(", ") || "—"));
  }

  // ------------------------------------------------------------------ timeline

  function branchThrough(id) {
    const path = [...ancestors(id).reverse(), id];
    for (let n = byId.get(id); n.children.length;) {
      n = byId.get(n.children[0]);
      path.push(n.id);
    }
    return path;
  }

  function showTimeline(id) {
    const path = branchThrough(id).map((i) => byId.get(i));
    const upto = path.findIndex((n) => n.id === id);
    const leaf = path[path.length - 1];
    const box = $("timeline");
    box.textContent = "";
    box.append(h("div", { class: "lane-head" }, `${ROBOT} (robot)`),
      h("div", { class: "lane-head" }, `${HUMAN} (human)`));
    const step = (n, i) => {
      const cls = ["tl-step", role(n.agent)];
      if (COMM.has(n.kind)) cls.push("comm");
      if (IDLE.has(n.kind)) cls.push("idle");
      if (n.id === id) cls.push("current");
      if (i > upto) cls.push("after");
      const d = h("div", { class: cls.join(" "), "data-step-node": n.id, "data-agent": n.agent });
      d.append(h("span", { class: "n" }, `#${n.id}`), n.action);
      return d;
    };
    // same rule as policy.timeline(): a step taken while apart goes to its agent's lane
    let lanes = null;
    let cost = 0;
    for (let i = 1; i < path.length; i++) {
      const n = path[i], prev = path[i - 1];
      cost += Number(n.cost) || 0;
      if (prev.copresent) {
        box.appendChild(step(n, i));
      } else {
        if (!lanes) {
          const par = h("div", { class: "tl-parallel" });
          par.appendChild(h("div", { class: "tl-caption" }, "apart: acting in parallel, unseen by each other"));
          lanes = {};
          lanes[ROBOT] = par.appendChild(h("div", { class: "tl-lane", "data-agent": ROBOT }));
          lanes[HUMAN] = par.appendChild(h("div", { class: "tl-lane", "data-agent": HUMAN }));
          box.appendChild(par);
        }
        lanes[n.agent].appendChild(step(n, i));
      }
      if (n.copresent) lanes = null;
    }
    if (leaf.goal) box.appendChild(h("div", { class: "tl-end" }, `goal reached (branch cost ${cost})`));
    $("branch-select").value = String(leaf.id);
    $("timeline-note").textContent = upto < path.length - 1
      ? `Branch through node ${id}, continued along first choices to leaf ${leaf.id} (faded).`
      : `Branch ending at leaf ${leaf.id}.`;
  }

  // ------------------------------------------------------------------ selection

  function select(id, recenter) {
    if (!byId.has(id)) return;
    let unfolded = false;
    for (const a of ancestors(id)) unfolded = collapsed.delete(a) || unfolded;
    selected = id;
    if (unfolded) draw();
    else markSelected();
    if (unfolded || recenter) centerOn(id);
    const n = byId.get(id);
    showDetails(n);
    showTimeline(id);
    try {
      history.replaceState(null, "", `#node=${id}`);
    } catch (err) {
      // some browsers refuse history changes on file pages; the selection still works
    }
  }

  function toggle(id) {
    // keep the toggled node where it was on screen; the layout around it changes
    const before = pos.get(id);
    if (collapsed.has(id)) collapsed.delete(id);
    else collapsed.add(id);
    draw();
    const after = pos.get(id);
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
    if (t) return toggle(Number(t.getAttribute("data-toggle-id")));
    const g = e.target.closest(".node");
    if (g) select(Number(g.getAttribute("data-node-id")), false);
  });
  svg.addEventListener("keydown", (e) => {
    const g = e.target.closest && e.target.closest(".node");
    if (!g) return;
    const id = Number(g.getAttribute("data-node-id"));
    if (e.key === "Enter" || e.key === " ") {
      e.preventDefault();
      select(id, false);
    } else if ((e.key === "+" || e.key === "-") && byId.get(id).children.length) {
      toggle(id);
    }
  });
  document.addEventListener("click", (e) => {
    const b = e.target.closest && e.target.closest("[data-goto], [data-step-node]");
    if (!b) return;
    const id = b.getAttribute("data-goto") ?? b.getAttribute("data-step-node");
    select(Number(id), true);
  });

  $("zoom-in").addEventListener("click", () => zoom(1 / 1.25));
  $("zoom-out").addEventListener("click", () => zoom(1.25));
  $("fit").addEventListener("click", fit);
  $("expand-all").addEventListener("click", () => {
    collapsed.clear();
    draw();
    fit();
  });
  $("collapse-all").addEventListener("click", () => {
    for (const n of nodes) if (n.children.length && depthOf.get(n.id) >= 1) collapsed.add(n.id);
    draw();
    fit();
  });
  $("show-timeline").addEventListener("click", () => $("timeline-pane").scrollIntoView());
  $("branch-select").addEventListener("change", (e) => select(Number(e.target.value), true));

  // ------------------------------------------------------------------ start

  $("policy-title").textContent = `${policy.problem} — ${policy.domain}`;
  $("policy-facts").textContent = [
    `worst-case cost ${policy.cost}`, `${policy.leaves} branch${policy.leaves === 1 ? "" : "es"}`,
    plural(policy.communications, "communication"), `K = ${policy.K}`,
    plural(nodes.length, "node"), `robot ${ROBOT}, human ${HUMAN}`,
    policy.optimal === false ? "not proved optimal" : "optimal",
  ].join(" · ");
  const comms = preorder.filter((i) => COMM.has(byId.get(i).kind));
  const list = $("comm-list");
  if (comms.length) for (const i of comms) list.appendChild(gotoButton(i));
  else list.textContent = "none";
  const select_ = $("branch-select");
  for (const i of preorder) {
    const n = byId.get(i);
    if (n.children.length) continue;
    select_.appendChild(h("option", { value: i }, `leaf #${i}: ${label(n)}`));
  }

  initialFolding();
  draw();
  fit();
  const m = /node=(\d+)/.exec(location.hash);
  if (m) select(Number(m[1]), true);
  document.body.setAttribute("data-ready", "true");
})();
