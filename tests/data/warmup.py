"""The domain of ``warmup``: tests/test_profile_switch.py builds its problem in Python,
tests/test_relabel_after.py writes this file as ``warm.py`` beside its problem file. The robot
warms ``b``, then either puts ``a`` (``share``) or grabs ``b``, puts ``a`` and drops ``b``
(``all``); the human puts ``b`` once it is warm."""

from ehatp import Domain, Var

domain = Domain("warmup", robot="R", human="H")
thing = domain.type("thing")
x = Var("x", thing)
a, b = domain.constant("a", thing), domain.constant("b", thing)
placed, held = domain.predicate("placed", x), domain.predicate("held", x)
ready = domain.predicate("ready", x)
warm = domain.robot.action("warm", x, pre=~ready(x), effects=[ready(x)])
put = domain.robot.action("put", x, pre=~placed(x), effects=[placed(x)], resources=[x])
grab = domain.robot.action("grab", x, pre=~placed(x) & ~held(x), effects=[held(x)],
                           resources=[x])
drop = domain.robot.action("drop", x, pre=held(x), effects=[~held(x), placed(x)],
                           resources=[x])
prep = domain.robot.task("prep")
domain.robot.method(prep, "warm", subtasks=[warm(b)])
work = domain.robot.task("work")
domain.robot.method(work, "share", subtasks=[put(a)])
domain.robot.method(work, "all", subtasks=[grab(b), put(a), drop(b)])
hput = domain.human.action("hput", x, pre=ready(x) & ~placed(x) & ~held(x),
                           effects=[placed(x)], resources=[x])
task = domain.human.task("help", x, done=placed(x))
domain.human.method(task, "put", subtasks=[hput(x)])
