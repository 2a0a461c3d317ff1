"""Running a policy: the executor a robot controller drives, the live JSON-lines protocol of
``ehatp execute``, the simulation of ``ehatp simulate`` and the walk of every branch."""
