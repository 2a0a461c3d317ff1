"""Sally-Anne, human-robot style: a false-belief test for the planner.

The human will need the ball later, and the robot must first clean it and put it in the box
(cleaning is hidden: it is not something the human needs to know). While the human is out on an
errand, the robot may do that unseen. The human does not expect the robot to touch the ball (its
estimate of the robot's model has no ``move``), and ball positions are hidden inside the
containers, so an unseen move leaves the human with a false belief. The robot must then inform
before the human reaches for the basket, or defer the move until the human is back to see it.
"""

from ehatp import HIDDEN, Domain, Var, observable

d = Domain("sally-anne", robot="R", human="H", doc=__doc__ or "")
Place, Container = d.type("place"), d.type("container")
room = d.constant("room", Place)
d.constant("street", Place)
p, p2 = Var("p", Place), Var("p2", Place)
c, c2 = Var("c", Container), Var("c2", Container)

at_h = d.predicate("human_at", p)
in_c = d.predicate("ball_in", c, observability=HIDDEN)
has_ball = d.predicate("has_ball")
clean = d.predicate("clean", observability=HIDDEN)
errand_done = d.predicate("errand_done", observability=observable(at_h(room)))
d.copresence = at_h(room)

# robot: tidy the ball into the box
move = d.robot.action("move", c, c2, pre=in_c(c), effects=[in_c(c2), ~in_c(c), clean()])
tidy = d.robot.task("tidy", done=in_c("box") | has_ball())
d.robot.method(tidy, "move", params=[c], pre=in_c(c), subtasks=[move(c, "box")])

# what the human expects of the robot: nothing involving the ball
d.robot_seen_by_human = d.robot.copy()
d.robot_seen_by_human.operators.pop("move")
d.robot_seen_by_human.methods.clear()

# human: run an errand, come back, take the ball from where it believes it is
go = d.human.action("go", p, p2, pre=at_h(p), effects=[at_h(p2), ~at_h(p)])
errand = d.human.action("errand", pre=at_h("street") & ~errand_done(), effects=[errand_done()])
take = d.human.action("take", c, pre=at_h(room) & in_c(c), effects=[has_ball(), ~in_c(c)])
trip = d.human.task("trip", done=errand_done() & at_h(room))
d.human.method(trip, "go", subtasks=[go(room, "street"), errand(), go("street", room)])
fetch = d.human.task("fetch", done=has_ball())
d.human.method(fetch, "take", params=[c], pre=in_c(c), subtasks=[take(c)])

d.goal = clean() & has_ball()
domain = d
