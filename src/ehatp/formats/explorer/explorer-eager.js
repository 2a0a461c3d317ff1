/* ehatp policy explorer, the eager page: the model of a version 2 policy (docs/policy-format.md)
 * embedded whole, for the shared explorer (explorer.js, which comes first in the page). */
ehatpExplorer(function eagerModel(core) {
  "use strict";

  const { nodes, items, plural, label, tellApart } = core;

  const parentsOf = new Map(); // node id -> ids of the nodes with a move into it
  for (const n of nodes) {
    for (const m of n.moves) {
      if (!parentsOf.has(m.to)) parentsOf.set(m.to, []);
      const ps = parentsOf.get(m.to);
      if (!ps.includes(n.id)) ps.push(n.id);
    }
  }
  const firstItem = new Map(); // node id -> its expanded item
  let sizeOf = []; // item -> the items below it, folded or not
  const first = (id) => firstItem.get(id);

  return {
    build() {
      // The policy is a graph; it is drawn as a tree of items, one per move plus the root,
      // depth-first in move order, all made now. A node is expanded at its first item (in id
      // order, since ids are that same preorder); every later move into it is a reference item
      // with no children that links to the first copy. Items are linear in the graph's size.
      for (const stack = [{ node: 0, move: null, parent: -1 }]; stack.length;) {
        const x = stack.pop();
        const idx = items.length;
        const ref = firstItem.has(x.node);
        const moves = nodes[x.node].moves;
        items.push({
          node: x.node, view: nodes[x.node], move: x.move, parent: x.parent, kids: [], ref,
          depth: 0, width: ref ? 0 : moves.length, sibling: null,
        });
        if (x.parent >= 0) {
          items[idx].depth = items[x.parent].depth + 1;
          items[x.parent].kids.push(idx);
        }
        if (ref) continue;
        firstItem.set(x.node, idx);
        for (let j = moves.length - 1; j >= 0; j--) {
          stack.push({ node: moves[j].to, move: moves[j], parent: idx });
        }
      }
      // the moves of a node are the children of its first item, in order: number and tell apart
      // those that read the same, once per node
      for (const idx of firstItem.values()) tellApart(items[idx].kids);
      sizeOf = new Array(items.length).fill(1);
      for (let i = items.length - 1; i > 0; i--) sizeOf[items[i].parent] += sizeOf[i];
    },
    makeKids: () => [], // never asked: every item is made with its children
    first,
    find: (key) => first(Number(key)), // a node id: its first copy
    key: (it) => items[it].node,
    tag: (it) => `#${items[it].node}`,
    named: (it) => `node ${items[it].node}`,
    nodeId: (n) => String(n.id),
    title: (it) => `Node ${items[it].node}`,
    from(it) {
      // every node with a move into this one, at its first copy
      const ups = parentsOf.get(items[it].node) || [];
      if (!ups.length) return null;
      return { text: ups.length > 1 ? `from (${ups.length} nodes lead here): ` : "from: ",
        items: ups.map(first) };
    },
    withWorlds: (n) => n,
    boxHooks(it) {
      const item = items[it], id = item.node;
      return item.ref
        ? { "data-ref-id": id, "aria-label": `${label(it)}: leads to node ${id}, drawn at its first path` }
        : { "data-node-id": id, "aria-label": `node ${id}: ${label(it)}, ${plural(item.view.worlds, "world")}` };
    },
    toggleHooks: (it) => ({ "data-toggle-id": items[it].node }),
    stepHooks: () => ({}),
    below: (it) => `${sizeOf[it] - 1}`,
    shownText: (visible) =>
      `${visible.filter((it) => !items[it].ref).length} of ${plural(nodes.length, "node")} shown`,
    branchValue: (it) => String(items[it].node),
    fromHash(hash) {
      const m = /node=(\d+)/.exec(hash);
      return m && firstItem.has(Number(m[1])) ? first(Number(m[1])) : null;
    },
    fragment: (it) => `node=${items[it].node}`,
    facts: plural(nodes.length, "node"),
    expandAll: Infinity, // the drawing is linear in the graph: everything
    branches(most) {
      // distinct leaves, in id order; a leaf is shown on the branch to its first copy
      const out = [];
      for (const n of nodes) {
        if (n.moves.length || out.length >= most) continue;
        out.push([n.id, `leaf #${n.id}: ${label(first(n.id))}`]);
      }
      return out;
    },
  };
});
