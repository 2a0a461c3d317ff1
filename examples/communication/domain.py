"""A jar on a shelf, for the communication options (docs/semantics.md §5).

Where the jar stands is hidden (behind doors), so the human knows it only from what it believed
at the start or from what it is told. Shelves stand in the kitchen (where the robot works) or in
the pantry. The human fetches the jar from the shelf it believes holds it: going to the pantry
first if needed. A false belief makes it reach for the wrong shelf and fail.
"""

from ehatp import HIDDEN, Domain, Var, exists

d = Domain("jar", robot="R", human="H", doc=__doc__ or "")
Place, Shelf = d.type("place"), d.type("shelf")
kitchen = d.constant("kitchen", Place)
d.constant("pantry", Place)
p, p0 = Var("p", Place), Var("p0", Place)
s = Var("s", Shelf)

human_at = d.predicate("human_at", p)
shelf_in = d.predicate("shelf_in", s, p)  # static
jar_on = d.predicate("jar_on", s, observability=HIDDEN)
has_jar = d.predicate("has_jar")
d.copresence = human_at(kitchen)

# the robot only talks here; give it a chore so it has something to do
dusted = d.predicate("dusted")
dust = d.robot.action("dust", pre=~dusted(), effects=[dusted()])
chores = d.robot.task("chores", done=dusted())
d.robot.method(chores, "dust", subtasks=[dust()])

go = d.human.action("go", p0, p, pre=human_at(p0) & ~human_at(p),
                    effects=[human_at(p), ~human_at(p0)])
take = d.human.action("take", s, pre=jar_on(s) & exists(p, shelf_in(s, p) & human_at(p)),
                      effects=[has_jar(), ~jar_on(s)])
fetch = d.human.task("fetch", done=has_jar())
d.human.method(fetch, "here", params=[s, p], pre=jar_on(s) & shelf_in(s, p) & human_at(p),
               subtasks=[take(s)])
d.human.method(fetch, "there", params=[s, p, p0],
               pre=jar_on(s) & shelf_in(s, p) & human_at(p0) & ~human_at(p),
               subtasks=[go(p0, p), take(s)])
d.goal = has_jar()
domain = d
