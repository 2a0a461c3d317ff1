/* ehatp policy explorer, the lazy page: the model of a lifted policy (format version 3) too
 * large to expand, for the shared explorer (explorer.js, which comes first in the page). Its
 * tree is realised from the canonical nodes and their renamings, a branch when it is unfolded,
 * so the page is as small as the lifted file and opens as fast whatever the size of the
 * expansion. */
ehatpExplorer(function liftedModel(core) {
  "use strict";

  const { $, nodes, items, collapsed, plural, count, label, kidsOf } = core;

  // A lifted policy (format version 3, docs/policy-format.md): ``nodes`` are canonical nodes,
  // each move carries the renaming that maps its child onto node ``to``. The page realises the
  // tree lazily, as Renamings (src/ehatp/formats/lifted.py) does in Python: an *item* is a
  // canonical node seen through ``tau``, the renaming from it to the real objects (at the root
  // the inverse of ``symmetry.root``; along a move, ``tau . inverse(renamings[m.renaming])``),
  // and an item's children are made only when it is unfolded. Facts keep their canonical
  // positions (no atom order), as expanded() writes them. The drawing is the tree unfolding:
  // a real node reached by two paths is drawn under each, unlinked.
  const SYM = core.policy.symmetry;
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
    // ``to`` still the canonical id; the worlds (the bulk of a file) on demand (withWorlds)
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

  // tree items, made on demand, with the shared fields and {tau, path ("" at the root, else
  // the move indices from the root joined by ".")}; an item with moves starts folded
  function newItem(id, tau, move, parent, path) {
    const it = items.length;
    items.push({
      node: id, tau, view: realise(id, tau), move, parent, kids: null, sibling: null,
      depth: parent >= 0 ? items[parent].depth + 1 : 0, path, width: nodes[id].moves.length,
    });
    if (nodes[id].moves.length) collapsed.add(it);
    return it;
  }
  function makeKids(it) {
    const item = items[it];
    return item.view.moves.map((m, j) => newItem(m.to, childTau(item.tau, m.renaming || 0), m,
      it, item.path === "" ? String(j) : `${item.path}.${j}`));
  }
  function itemAt(path) {
    // the item a path of move indices leads to, made on the way; null when there is none
    let it = 0;
    for (const part of path === "" ? [] : path.split(".")) {
      const j = Number(part);
      if (!/^\d+$/.test(part) || j >= items[it].width) return null;
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
  const cid = (it) => `c${items[it].node}`; // a canonical node's name: c12 is node 12
  const leafOptions = new Set(); // the paths the branch drop-down lists

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

  return {
    build: () => newItem(0, ROOT_TAU, null, -1, ""),
    makeKids,
    first: (id) => itemAt(firstPath[id]),
    find: itemAt, // a path
    key: (it) => items[it].path,
    tag: cid,
    named: cid,
    nodeId: (n) => `c${n.id}`,
    title: (it) => `Canonical node ${items[it].node}${items[it].view.ren ? ", objects renamed" : ""}`,
    // the parent on this path only: other paths may reach the same real node (not searched)
    from: (it) => (items[it].parent >= 0
      ? { text: "from (on this path): ", items: [items[it].parent] } : null),
    withWorlds(view) {
      // the divergence and the worlds' differences, renamed (only for the details panel)
      if (!view.world_diffs) {
        const n = nodes[view.id], t = (s) => renamed(view.ren, s);
        view.divergence = n.divergence.map(t);
        view.world_diffs = n.world_diffs.map((d) => ({ true: d.true.map(t), false: d.false.map(t) }));
      }
      return view;
    },
    boxHooks: (it) => ({
      "data-canonical-id": items[it].node, "data-path": items[it].path,
      "aria-label": `canonical node ${items[it].node}: ${label(it)}, ${plural(items[it].view.worlds, "world")}`,
    }),
    toggleHooks: (it) => ({ "data-toggle-path": items[it].path }),
    stepHooks: (it) => ({ "data-step-path": items[it].path }),
    below: (it) => count(sizeBelow(items[it].node)),
    // the tree unfolding's items (a real node reached by two paths is an item under each)
    shownText: (visible) => `${count(visible.length)} of ${count(sizeBelow(0) + 1n)} tree items shown`,
    // the drop-down lists the first branches; a later one shows no option
    branchValue: (it) => (leafOptions.has(items[it].path) ? items[it].path : ""),
    fromHash(hash) {
      const m = /^#path=([\d.]*)$/.exec(hash);
      return m ? itemAt(m[1]) : null;
    },
    fragment: (it) => `path=${items[it].path}`,
    facts: `lifted: ${plural(nodes.length, "canonical node")}`,
    expandAll: 3000, // "expand all" unfolds breadth-first while the drawing stays under this
    branches(most) {
      // the first branches of the tree unfolding, depth-first (the order of
      // Policy.iter_branches and of `ehatp show`'s timelines): a leaf's move renamed through
      // its parent's renaming, made into items only where sibling moves read the same (for
      // their numbers)
      const out = [];
      for (const stack = [[0, ROOT_TAU, "", -1, -1, null]]; stack.length && leafOptions.size < most;) {
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
        out.push([path, `branch ${leafOptions.size}: ${text} (leaf c${n})`]);
      }
      return out;
    },
  };
});
